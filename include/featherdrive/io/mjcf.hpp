// MJCF import through MuJoCo 2.2.2's own compiler (mj_loadXML): the compiled mjModel's bodies,
// joints and actuators become the same robot description a URDF gives (UrdfRobot), plus what the
// file says about drives. docs/mujoco_bridge.md ("Importing MJCF") has the mapping.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "featherdrive/io/urdf.hpp"
#include "featherdrive/sim/explicit_actuator.hpp"

namespace featherdrive {

/// Bounds on what an MJCF document may ask of MuJoCo 2.2.2, checked before its compiler runs
/// (docs/mujoco_bridge.md, "Refused, warned, ignored"). Elements nested, includes followed
/// (MuJoCo's parser and compiler recurse per level, about 4 KiB of stack each):
inline constexpr int kMaxMjcfDepth = 1000;
/// <include> elements followed in one document (each names a file of its own).
inline constexpr int kMaxMjcfIncludes = 1000;
/// <size nkey> and the number of <key> elements (the compiler's time is quadratic in them).
inline constexpr long kMaxMjcfKeyframes = 1000;
/// <size nuser_body>, nuser_jnt, ... (numbers allocated per element).
inline constexpr long kMaxMjcfUserValues = 1000;
/// <size nuserdata> and nstack (numbers allocated in every mjData).
inline constexpr long kMaxMjcfUserData = 1000000;
inline constexpr long kMaxMjcfStack = 10000000;
/// <size njmax> and nconmax (a constraint row is as long as the model's dofs).
inline constexpr long kMaxMjcfConstraints = 100000;

/// What an MJCF actuator on a joint is, by its compiled gain and bias (MuJoCo's shortcuts).
enum class MjcfActuatorKind {
  motor,     ///< force = gain * ctrl: no featherdrive drive (the scene gives one)
  position,  ///< force = kp (ctrl - gear q): an explicit IdealPD actuator with stiffness
  velocity,  ///< force = kv (ctrl - gear qd): an explicit IdealPD actuator with damping
};
const char* to_string(MjcfActuatorKind kind);

/// One MJCF actuator with a joint transmission, in MuJoCo's units, and its featherdrive form.
struct MjcfActuator {
  std::string name;   ///< the actuator's name (MuJoCo's index "actuator<k>" when unnamed)
  std::string joint;  ///< the joint it drives
  int dof = 0;        ///< that joint's dof in the model
  MjcfActuatorKind kind = MjcfActuatorKind::motor;
  double gear = 1.0;  ///< joint effort = gear * actuator force; length = gear * q
  double gain = 0.0;  ///< gainprm[0]: kp (position), kv (velocity), the motor's gain
  /// forcerange (actuator force, before gear) and ctrlrange; +-inf where not limited.
  double force_lower = -std::numeric_limits<double>::infinity();
  double force_upper = std::numeric_limits<double>::infinity();
  double ctrl_lower = -std::numeric_limits<double>::infinity();
  double ctrl_upper = std::numeric_limits<double>::infinity();
  /// position / velocity: ideal_pd with stiffness (damping) gain * gear^2 and effort_limit
  /// gear * max(|force_lower|, |force_upper|); its target is ctrl / gear. motor: kind none.
  ExplicitActuator actuator;
};

/// The robot of an MJCF file: the UrdfRobot fields as load_urdf fills them (links are bodies,
/// joint names MJCF joint names, joint_order MuJoCo's joint order without a free root), plus the
/// actuators and MuJoCo's reference configuration.
struct MjcfRobot : UrdfRobot {
  std::vector<MjcfActuator> actuators;  ///< in MuJoCo's actuator order; others are warned about
  /// MuJoCo's qpos0 in featherdrive's q: a free root's body pose, hinge and slide refs, identity
  /// quaternions. q = MuJoCo's qpos for every joint (ball and free: (w, x, y, z) quaternions).
  VecX q0;
};

/// Reads an MJCF file through MuJoCo's compiler (includes and meshes resolve as MuJoCo resolves
/// them). Before the compiler runs, the document and every file it names are checked: files
/// must be regular (a FIFO, folder or device is refused, not opened), nesting, includes and
/// <size> counts stay within the bounds above, and no numeric attribute is NaN or infinite
/// (refused naming the element and attribute; MuJoCo would take its default). The robot's
/// input_files lists the file, its includes and its asset files. options.fixed_base welds a free root to the world where it stands; options.gravity is
/// the model's (a warning says when the file's <option gravity> differs). Throws InputError, one
/// line naming the file: MuJoCo's own load error, a tendon or an equality constraint other than
/// a mimic joint (refused, naming the element and its name; an active joint equality
/// q1 = c0 + c1 q2 between hinges or slides, c1 != 0, is the robot's mimic_joints row
/// q1 - c1 q2 - c0 = 0, as a URDF <mimic> tag), several free bodies, a free joint not alone in its body.
/// A hinge's or slide's stiffness becomes its spring (UrdfRobot::springs, toward qpos_spring;
/// implicit: a note says so); contacts, a ball joint's stiffness, ball ranges and unsupported actuators are warned about
/// and ignored.
/// Loads from several threads run one at a time (MuJoCo's warning hook is a global).
MjcfRobot load_mjcf(const std::filesystem::path& path, const UrdfOptions& options = {});

/// The same from a string (through MuJoCo's virtual file system); `name` stands for the file in
/// messages. Files the text includes are read from disk relative to the working directory (and
/// listed in input_files).
MjcfRobot parse_mjcf(const std::string& xml, const std::string& name,
                     const UrdfOptions& options = {});

class Simulation;
/// Gives `sim` (a simulation of robot.model) each position and velocity actuator's explicit
/// ideal_pd form (MjcfActuator::actuator); a position and a velocity actuator on one joint become
/// one actuator with both gains and the sum of their effort limits (the same effort while neither
/// saturates). Motors give nothing. Targets stay the caller's: ctrl / gear. Throws
/// std::invalid_argument when a dof already has an implicit drive.
void apply_mjcf_actuators(const MjcfRobot& robot, Simulation& sim);

/// The file's settings (urdf.hpp's robot_settings: defaults with `options`, the mimic rows) with
/// the actuators as apply_mjcf_actuators gives them, the springs as joint_spring rows, and the
/// effort limits as robot.options.effort says.
Settings robot_settings(const MjcfRobot& robot, const SimulationOptions& options = {});

/// The actuators as `featherdrive info` lists them: per actuator its joint, kind, gains, ranges
/// and the featherdrive actuator it maps to (empty when there are none).
std::string describe_actuators(const MjcfRobot& robot);

/// A robot file of either kind, chosen by is_mjcf_file: load_mjcf's robot (the UrdfRobot part)
/// or load_urdf's. Scenes' `model` key reads it.
UrdfRobot load_robot(const std::filesystem::path& path, const UrdfOptions& options = {});

/// The files load_mjcf(path) reads, without compiling: the file, its includes and its asset
/// files, found as MuJoCo finds them. Throws InputError as load_mjcf does for what its checks
/// refuse.
std::vector<std::filesystem::path> mjcf_input_files(const std::filesystem::path& path);

/// Whether `path` names an MJCF file: a .xml extension, or else a root element <mujoco> (the
/// first element of the file). URDF files have the extension .urdf or the root <robot>.
bool is_mjcf_file(const std::filesystem::path& path);

}  // namespace featherdrive
