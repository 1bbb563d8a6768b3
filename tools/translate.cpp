#include <cstdio>
#include <filesystem>
#include <map>
#include <stdexcept>

#include "cli_common.hpp"
#include "featherdrive/io/files.hpp"
#include "featherdrive/io/mjcf.hpp"
#include "featherdrive/io/mjcf_export.hpp"
#include "featherdrive/io/mujoco_scene.hpp"
#include "featherdrive/io/scene.hpp"
#include "mujoco_commands.hpp"

using namespace featherdrive;

namespace {

// --to physx: SCENE is an MJCF; the output a featherdrive scene that reads it.
int translate_to_physx_scene(const TranslateArgs& args) {
  check_outputs({{"--out", args.out}}, {{"the MJCF", args.scene}}, mjcf_input_files(args.scene));
  SimulationOptions options;
  args.overrides.apply(options);
  const int steps = args.overrides.steps.value_or(240);
  const SceneTranslation t = translate_mjcf_to_scene(args.scene, args.out, options, steps);
  make_parent_folders(args.out);
  AtomicFile out(args.out, "the scene");
  out.stream() << t.yaml;
  out.commit();
  std::printf("%s: MuJoCo %s, timestep %.6g s, integrator %s -> featherdrive %s %d/%d\n",
              args.scene.c_str(), mujoco_version().c_str(), t.dt, to_string(t.integrator),
              to_string(options.solver), options.position_iterations, options.velocity_iterations);
  std::printf(
      "  per joint, at qpos0 (m = 1 / (M^-1)_jj); match: the largest |q| difference of\n"
      "  the two 1-dof step responses / the step\n");
  std::printf("  %-16s %10s %11s %11s %11s %11s %11s %10s  %s\n", "joint", "m", "MuJoCo kp", "kv",
              "damping", "stiffness", "damping", "match", "");
  for (const TranslatedJoint& j : t.joints) {
    const PhysxTranslation& p = j.physx;
    std::printf("  %-16s %10.4g %11.4g %11.4g %11.4g %11.4g %11.4g %10.2e  %s\n", j.joint.c_str(),
                j.effective_inertia, j.mujoco.kp, j.mujoco.kv, j.mujoco.damping, p.drive.stiffness,
                p.drive.damping, p.distance.step_response, p.exact ? "exact" : p.note.c_str());
  }
  for (const std::string& note : t.notes) std::printf("  note: %s\n", note.c_str());
  if (t.restored)
    std::printf("  scene: the one the MJCF was exported from (its %s text), model the MJCF\n",
                kMjcfSceneText);
  std::printf("  scene: %s\n", args.out.c_str());
  return 0;
}

// The URDF's visuals and collisions for the export (MuJoCo's viewer shows them); what cannot be
// exported is a warning line each.
std::vector<std::string> add_geometry(const Scene& scene, const TranslateArgs& args,
                                      MjcfExportOptions& options) {
  std::map<std::string, std::string> packages;
  for (const std::string& p : args.packages) {
    const size_t eq = p.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == p.size())
      throw std::invalid_argument("--package '" + p + "': expected NAME=DIR");
    const std::string folder = p.substr(eq + 1);
    std::error_code error;
    if (!std::filesystem::is_directory(folder, error))
      throw std::invalid_argument("--package '" + p + "': " + folder + " is not a folder");
    packages[p.substr(0, eq)] = folder;
  }
  std::vector<std::string> warnings;
  options.geometry = mjcf_geometry(scene.robot, packages, warnings);
  return warnings;
}

// A refused export whose geometry MuJoCo cannot load (a broken mesh file) is the input's fault:
// throws std::invalid_argument naming the URDF when the export without geometry compiles.
void check_geometry_loads(const Simulation& sim, MjcfExportOptions options, const Scene& scene,
                          const std::string& error) {
  if (options.geometry.empty()) return;
  options.geometry.clear();
  if (mujoco_compile_error(export_mjcf(sim, options).xml).empty())
    throw std::invalid_argument(scene.robot.path.string() +
                                ": MuJoCo cannot load its geometry: " + error);
}

}  // namespace

int translate(const TranslateArgs& args) {
  if (args.to == "physx") return translate_to_physx_scene(args);
  Scene scene = args.overrides.load(args.scene);
  check_outputs({{"--out", args.out}},
                {{"the scene", args.scene}, {"the scene's model", scene.robot.path}},
                scene.robot.input_files);
  const Simulation sim = make_simulation(scene);
  MjcfExportOptions options;
  options.integrator =
      args.integrator == "implicit" ? MujocoIntegrator::implicit : MujocoIntegrator::euler;
  options.keep_timestep = args.keep_timestep;
  const std::vector<std::string> geometry_warnings = add_geometry(scene, args, options);
  MjcfExport e;
  try {
    options.model_name = scene.robot.name;
    options.scene_record = scene_record(read_input_file(args.scene, "the scene"), sim, args.scene);
    e = export_mjcf(sim, options);
  } catch (const InputError& error) {
    throw std::invalid_argument(args.scene + ": " + error.what());
  }
  if (e.drives.empty())
    throw std::invalid_argument(args.scene + ": no joint has a drive: nothing to translate");
  // MuJoCo must take what is written (a refusal here is a bug of the export, not the input's).
  if (const std::string error = mujoco_compile_error(e.xml); !error.empty()) {
    check_geometry_loads(sim, options, scene, error);
    throw std::runtime_error("MuJoCo refused the translated model: " + error);
  }
  make_parent_folders(args.out);
  AtomicFile out(args.out, "the MJCF");
  out.stream() << e.xml;
  out.commit();

  const SimulationOptions& o = sim.options();
  std::printf(
      "%s: robot %s, dt %.6g s, solver %s %d/%d -> MuJoCo %s, integrator %s, "
      "timestep %.6g s (%d per step)\n",
      args.scene.c_str(), scene.robot.name.c_str(), o.dt, to_string(o.solver),
      o.position_iterations, o.velocity_iterations, mujoco_version().c_str(),
      to_string(e.integrator), e.timestep, e.substeps);
  std::printf(
      "  per drive, at the initial configuration (m = 1 / (M^-1)_jj); match: the largest\n"
      "  |q| difference of the two 1-dof step responses / the step, translated and literal\n");
  std::printf("  %-16s %10s %10s %11s %11s %11s %11s %10s %10s  %s\n", "joint", "m", "kp dt^2/m",
              "kp", "damping", "armature", "ctrl+=g*vT", "match", "literal", "");
  for (const MjcfDrive& d : e.drives) {
    const MujocoDrive& mj = d.mujoco;
    const MujocoTranslation& t = d.translation;
    const Drive& drive = sim.drive(d.dof);
    const DriveStepMap physx = physx_step_map(d.effective_inertia, drive, o);
    const DriveStepMap literal = mujoco_step_map(
        d.effective_inertia, literal_mujoco_drive(d.effective_inertia, drive, e.integrator), o.dt);
    const double literal_match = map_distance(physx, literal).step_response;
    std::string verdict = t.exact ? "exact" : t.note;
    if (!stable(literal)) verdict += "; literal copy unstable in MuJoCo";
    // The 1-dof map sees the drive alone: a row kind beside it (the joint spring) is not in it.
    for (const RowKindInfo& kind : row_kinds())
      if (kind.active(sim.row_parameters(kind.name, d.dof)))
        verdict += "; the drive alone: its " + std::string(kind.name) + " is not in the map (note)";
    std::printf("  %-16s %10.4g %10.4g %11.4g %11.4g %11.4g %11.4g %10.2e %10.2e  %s\n",
                d.joint.c_str(), d.effective_inertia, mj.kp * o.dt * o.dt / d.effective_inertia,
                mj.kp, mj.damping, mj.armature, mj.ctrl_velocity_gain, t.distance.step_response,
                literal_match, verdict.c_str());
  }
  for (const std::string& note : e.notes) std::printf("  note: %s\n", note.c_str());
  for (const std::string& w : geometry_warnings) std::printf("  warning: %s\n", w.c_str());
  std::printf("  MJCF: %s\n", args.out.c_str());
  return 0;
}
