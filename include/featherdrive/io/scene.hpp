// Scene files (YAML, or JSON, read by yaml-cpp): a URDF robot, the simulation options, the initial
// state, drives with constant or sine targets and per-joint settings. README.md lists the keys.
#pragma once

#include <filesystem>
#include <functional>
#include <memory>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "featherdrive/io/error.hpp"
#include "featherdrive/io/fit_spec.hpp"
#include "featherdrive/io/urdf.hpp"
#include "featherdrive/sim/control_step.hpp"
#include "featherdrive/sim/simulation.hpp"

namespace featherdrive {

/// target position = offset + amplitude sin(2 pi frequency t + phase), target velocity its
/// derivative.
struct SineTarget {
  double amplitude = 0.0;
  double frequency = 0.0;  ///< Hz
  double phase = 0.0;      ///< rad
  double offset = 0.0;
  double position(double t) const;
  double velocity(double t) const;
};

struct DriveSpec {
  std::string joint;
  int dof = 0;
  Drive drive;                     ///< the targets in it hold for a constant target
  std::optional<SineTarget> sine;  ///< replaces the drive's targets at every step
  std::optional<ActuatorEnvelope> envelope;
  /// An explicit actuator (key actuator; the drive's type must be none): the targets are its.
  std::optional<ExplicitActuator> actuator;
  /// Steps between a target and the implicit drive's use of it (key delay; type force or
  /// acceleration only; Simulation::set_drive_delay).
  int delay = 0;
  /// The target position and velocity at time t.
  std::pair<double, double> target_at(double t) const;
};

/// Settings of one joint that override what the URDF says.
struct JointSettings {
  std::string joint;
  int dof = 0;
  std::optional<double> lower, upper, max_velocity, armature, friction_coefficient;
  std::optional<JointFriction> friction;
  std::optional<RevoluteWrap> revolute;  ///< key revolute: wrapped | unwrapped
  /// Row kinds (constraint/row_kinds.hpp) by their index: each field given, or not (the dof's
  /// own stays); key the kind's name, e.g. joint_spring: {stiffness: 8, reference: 0}.
  std::map<int, std::vector<std::optional<double>>> row_kinds;
};

/// applied_force.J: a joint force through every step (Simulation::set_applied_force), constant
/// or a sine of time (its position(t); t = k dt, the start of step k).
struct AppliedForceSpec {
  std::string joint;
  int dof = 0;
  double value = 0.0;
  std::optional<SineTarget> sine;
  double at(double t) const { return sine ? sine->position(t) : value; }
};

/// PhysX's link parameters a scene sets (link_parameters.hpp); the rest keep the simulation's
/// defaults (Compat::physx: PhysX's).
struct LinkSettings {
  std::string link;
  int index = 0;
  std::optional<double> cfm_scale, linear_damping, angular_damping, max_linear_velocity,
      max_angular_velocity;
  void apply_to(LinkParameters& parameters) const;
};

/// A foot of a legged robot: the links whose contact forces sum to its force (scene key feet).
struct Foot {
  std::string name;
  std::vector<std::string> link_names;  ///< as the scene names them
  std::vector<int> links;  ///< their model links (merged links resolved), each once, in order
};

struct Scene {
  std::filesystem::path path;        ///< the scene file
  std::filesystem::path model_path;  ///< the URDF, resolved against the scene's folder
  UrdfRobot robot;                   ///< robot.model is the model, armature applied
  SimulationOptions options;
  int steps = 0;
  VecX q0, qd0;                       ///< initial state; joints the file omits start at 0
  std::vector<DriveSpec> drives;      ///< in URDF joint order
  std::vector<JointSettings> joints;  ///< in URDF joint order
  /// link_defaults (every link) and joint_defaults (friction_coefficient for every joint,
  /// max_velocity for every joint whose URDF gives no velocity limit); links and joints override.
  std::optional<LinkSettings> link_defaults;
  std::vector<LinkSettings> links;    ///< in model link order
  std::optional<JointSettings> joint_defaults;
  std::vector<AppliedForceSpec> applied_forces;  ///< in URDF joint order
  /// The URDF's <mimic> rows, then the scene's mimic list (an entry replaces the URDF's row of
  /// its follower).
  std::vector<MimicJoint> mimic;
  /// control: {substeps: k, targets: hold | linear}: the targets change every k steps
  /// (apply_targets); the default 1 / hold is one target per step.
  ControlStep control;
  /// fit: what `featherdrive fit` identifies (fit_spec.hpp); absent without the key.
  std::optional<FitSpec> fit;
  /// ground: the scene's key; without it the robot file's own floor (an MJCF plane on the world
  /// body, UrdfRobot::ground) where the model's shapes allow one (else a warning in
  /// robot.warnings); disabled when neither has one, or with `ground: false`.
  Ground ground;
  /// contact: PhysX's contact and rest offsets and bounce threshold (docs/math/contact.md).
  ContactOptions contact;
  /// shapes: added to the robot's own (robot.shapes and robot.model->shapes), in file order.
  std::vector<std::pair<std::string, CollisionShape>> shapes;
  /// feet: {name: [link, ...]}: each foot's contact force is the sum of its links' (the CSV's
  /// foot:<name> columns), in file order.
  std::vector<Foot> feet;

  const std::shared_ptr<const Model>& model() const { return robot.model; }
};

/// A scene nested deeper than this (block and flow levels together) is refused before it is
/// parsed; a scene needs 5 (drives.J.target.sine.amplitude).
inline constexpr int kMaxSceneDepth = 64;

/// Reads a scene file. Throws InputError naming the file, the key path and the value for unknown
/// keys, missing or unknown joints, wrong types and bad values; errors of the URDF name the URDF.
Scene load_scene(const std::filesystem::path& path);
/// The same from text; `path` names the file in messages and anchors the relative model path.
Scene parse_scene(const std::string& text, const std::filesystem::path& path);

/// Every setting the scene gives (options, drives, delays, envelopes, actuators, joint and link
/// settings, mimic rows, ground, contact options, the URDF's effort limits as its urdf.effort
/// says) over Settings::defaults of its model: what make_simulation's simulation holds, and
/// what Batch(scene.model(), N, settings) gives every environment. Throws InputError naming the
/// scene and the first bad value, as a Simulation setter would word it.
Settings scene_settings(const Scene& scene);

/// A simulation of scene_settings in the scene's initial state; the drives' targets are those of
/// the first step.
Simulation make_simulation(const Scene& scene);

/// The applied force of step k (0-based), every joint the scene names (nv; 0 elsewhere).
VecX applied_force_at(const Scene& scene, const Simulation& sim, int step_index);

/// Sets the time-varying targets for step k (0-based). With scene.control's K substeps, step k
/// belongs to control step m = k / K as its sub-step j = k % K + 1: hold sets the sine targets
/// at the control step's end, t = (m + 1) K dt; linear interpolates from those at t = m K dt
/// (substep_target, docs/math/control_step.md). For K = 1 both are the targets at t = (k + 1) dt.
/// Also sets the applied force of step k (applied_force_at), if the scene has any.
void apply_targets(const Scene& scene, Simulation& sim, int step_index);

/// Runs the scene: on_state(sim, 0) for the initial state, then for each step k apply_targets,
/// sim.step() and on_state(sim, k + 1). Returns the simulation at the end.
Simulation run_scene(const Scene& scene,
                     const std::function<void(const Simulation&, int)>& on_state);

}  // namespace featherdrive
