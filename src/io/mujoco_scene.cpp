// MJCF drives -> a featherdrive scene (mujoco_scene.hpp).
#include "featherdrive/io/mujoco_scene.hpp"

#include <mujoco/mujoco.h>
#include <yaml-cpp/yaml.h>

#include <array>
#include <cmath>
#include <map>
#include <memory>
#include <stdexcept>

#include "featherdrive/core/format.hpp"
#include "featherdrive/io/error.hpp"
#include "featherdrive/io/mjcf.hpp"
#include "featherdrive/io/mjcf_export.hpp"
#include "mujoco_calls.hpp"

namespace featherdrive {

SceneTranslation translate_mjcf_to_scene(const std::filesystem::path& mjcf,
                                         const std::filesystem::path& scene_path,
                                         const SimulationOptions& options, int steps) {
  namespace fs = std::filesystem;
  const std::string name = mjcf.string();
  std::string error;
  std::vector<std::string> warnings;  // load_mjcf below reports them
  const mujoco_calls::ModelPtr m = mujoco_calls::load_xml(name.c_str(), nullptr, error, warnings);
  if (!m) throw InputError(name + ": MuJoCo refused the file: " + error);
  SceneTranslation out;
  out.dt = m->opt.timestep;
  if (m->opt.integrator == mjINT_RK4)
    throw InputError(name + ": option integrator = RK4: only Euler and implicit translate");
  out.integrator =
      m->opt.integrator == mjINT_EULER ? MujocoIntegrator::euler : MujocoIntegrator::implicit;
  UrdfOptions load;
  load.gravity = Vec3(m->opt.gravity[0], m->opt.gravity[1], m->opt.gravity[2]);
  const MjcfRobot robot = load_mjcf(mjcf, load);
  const Model& model = *robot.model;
  const VecX mass = effective_inertia(model, robot.q0);
  SimulationOptions o = options;
  o.dt = out.dt;

  // Per dof: the position and velocity actuators' gains (gear^2 in joint space) and force limit.
  struct Gains {
    double kp = 0.0, kv = 0.0, max_force = INFINITY;
  };
  std::map<int, Gains> gains;
  for (const MjcfActuator& a : robot.actuators) {
    if (a.kind == MjcfActuatorKind::motor) continue;
    Gains& g = gains[a.dof];
    double& gain = a.kind == MjcfActuatorKind::position ? g.kp : g.kv;
    gain += a.gain * a.gear * a.gear;
    // A joint-space gain that overflows (or is NaN) would be written as inf or nan.
    if (!std::isfinite(gain) || gain < 0.0)
      throw InputError(name + ": actuator " + a.name + ": gear = " + format_double(a.gear) +
                       ", gain = " + format_double(a.gain) + " give the joint-space " +
                       (a.kind == MjcfActuatorKind::position ? "kp" : "kv") + " gain * gear^2 = " +
                       format_double(gain) + ": must be finite and >= 0");
    const double limit = std::abs(a.gear) * std::max(std::abs(a.force_lower), a.force_upper);
    if (std::isfinite(limit)) {
      g.max_force = std::min(g.max_force, limit);
      out.notes.push_back("actuator " + a.name +
                          ": forcerange clamps MuJoCo's actuator force; "
                          "featherdrive's max_force clamps the whole drive");
    }
  }
  if (gains.empty())
    throw InputError(name + ": no position or velocity actuator on a joint: nothing to translate");

  fs::path model_path = fs::absolute(mjcf).lexically_normal();
  const fs::path folder = fs::absolute(scene_path).parent_path();
  const fs::path relative = model_path.lexically_relative(folder);
  if (!relative.empty()) model_path = relative;

  YAML::Emitter y;
  y << YAML::BeginMap;
  y << YAML::Key << "model" << YAML::Value << model_path.generic_string();
  y << YAML::Key << "fixed_base" << YAML::Value << !model.floating_base();
  y << YAML::Key << "gravity" << YAML::Value << YAML::Flow << YAML::BeginSeq
    << format_double(load.gravity.x()) << format_double(load.gravity.y())
    << format_double(load.gravity.z()) << YAML::EndSeq;
  y << YAML::Key << "dt" << YAML::Value << format_double(out.dt);
  y << YAML::Key << "steps" << YAML::Value << steps;
  y << YAML::Key << "solver" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key << "type"
    << YAML::Value << to_string(o.solver) << YAML::Key << "position_iterations" << YAML::Value
    << o.position_iterations << YAML::Key << "velocity_iterations" << YAML::Value
    << o.velocity_iterations << YAML::EndMap;
  // MuJoCo's qpos0 (joint refs) as the initial state of 1-dof joints.
  bool any_ref = false;
  for (const Link& link : model.links)
    any_ref = any_ref || (link.nv == 1 && robot.q0[link.q_index] != 0.0);
  if (any_ref) {
    y << YAML::Key << "initial" << YAML::Value << YAML::BeginMap << YAML::Key << "q" << YAML::Value
      << YAML::BeginMap;
    for (const Link& link : model.links)
      if (link.nv == 1 && robot.q0[link.q_index] != 0.0)
        y << YAML::Key << link.joint_name << YAML::Value << format_double(robot.q0[link.q_index]);
    y << YAML::EndMap << YAML::EndMap;
  }
  y << YAML::Key << "drives" << YAML::Value << YAML::BeginMap;
  for (const auto& [dof, g] : gains) {
    TranslatedJoint& t = out.joints.emplace_back();
    const Link& link = model.links[static_cast<size_t>(model.dof_link[static_cast<size_t>(dof)])];
    t.joint = link.joint_name;
    t.effective_inertia = mass[dof];
    t.mujoco.kp = g.kp;
    t.mujoco.kv = g.kv;
    t.mujoco.damping = model.damping[dof];
    t.mujoco.integrator = out.integrator;
    try {
      t.physx = translate_to_physx(mass[dof], t.mujoco, o);
    } catch (const std::invalid_argument& e) {
      throw InputError(name + ": joint " + t.joint + ": " + e.what());
    }
    y << YAML::Key << t.joint << YAML::Value << YAML::Flow << YAML::BeginMap;
    y << YAML::Key << "type" << YAML::Value << "force";
    y << YAML::Key << "stiffness" << YAML::Value << format_double(t.physx.drive.stiffness);
    y << YAML::Key << "damping" << YAML::Value << format_double(t.physx.drive.damping);
    if (std::isfinite(g.max_force))
      y << YAML::Key << "max_force" << YAML::Value << format_double(g.max_force);
    y << YAML::Key << "target_position" << YAML::Value << format_double(robot.q0[link.q_index])
      << YAML::EndMap;
  }
  y << YAML::EndMap;
  // The joint damping is in the drive now: not a second time as viscous friction.
  y << YAML::Key << "joints" << YAML::Value << YAML::BeginMap;
  for (const TranslatedJoint& t : out.joints) {
    const int dof = model.dof_index(t.joint);
    y << YAML::Key << t.joint << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key
      << "friction" << YAML::Value << YAML::BeginMap << YAML::Key << "static" << YAML::Value
      << format_double(model.friction[dof]) << YAML::Key << "dynamic" << YAML::Value
      << format_double(model.friction[dof]) << YAML::Key << "viscous" << YAML::Value << 0
      << YAML::EndMap << YAML::EndMap;
  }
  y << YAML::EndMap << YAML::EndMap;
  // An export of a featherdrive scene keeps that scene: it comes back whole, with the MJCF as
  // its model (the translation above stays in the report).
  for (int i = 0; i < m->ntext; ++i) {
    const char* text_name = mj_id2name(m.get(), mjOBJ_TEXT, i);
    if (!text_name || std::string(text_name) != kMjcfSceneText) continue;
    YAML::Node scene;
    try {
      scene = YAML::Load(std::string(m->text_data + m->text_adr[i]));
    } catch (const YAML::Exception& e) {
      throw InputError(name + ": <custom><text name=\"" + kMjcfSceneText + "\">: not YAML: " +
                       e.msg);
    }
    if (!scene.IsMap())
      throw InputError(name + ": <custom><text name=\"" + kMjcfSceneText + "\">: not a YAML map");
    scene["model"] = model_path.generic_string();
    YAML::Emitter restored;
    restored << scene;
    out.restored = true;
    out.yaml = std::string("# The featherdrive scene kept in ") + mjcf.filename().string() +
               " by `featherdrive translate --to mujoco`, its model the MJCF "
               "(docs/mujoco_bridge.md)\n" + restored.c_str() + "\n";
    return out;
  }
  out.yaml = std::string("# Translated from ") + mjcf.filename().string() +
             " by `featherdrive translate --to physx` (docs/mujoco_bridge.md)\n" + y.c_str() + "\n";
  return out;
}

}  // namespace featherdrive
