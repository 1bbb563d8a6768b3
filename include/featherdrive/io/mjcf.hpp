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
/// them). options.fixed_base welds a free root to the world where it stands; options.gravity is
/// the model's (a warning says when the file's <option gravity> differs). Throws InputError, one
/// line naming the file: MuJoCo's own load error, a tendon or equality constraint (refused,
/// naming the element and its name), several free bodies, a free joint not alone in its body.
/// Contacts, joint springs, ball ranges and unsupported actuators are warned about and ignored.
MjcfRobot load_mjcf(const std::filesystem::path& path, const UrdfOptions& options = {});

/// The same from a string (through MuJoCo's virtual file system); `name` stands for the file in
/// messages. Files the text includes are read from disk relative to the working directory.
MjcfRobot parse_mjcf(const std::string& xml, const std::string& name,
                     const UrdfOptions& options = {});

/// The actuators as `featherdrive info` lists them: per actuator its joint, kind, gains, ranges
/// and the featherdrive actuator it maps to (empty when there are none).
std::string describe_actuators(const MjcfRobot& robot);

/// A robot file of either kind, chosen by is_mjcf_file: load_mjcf's robot (the UrdfRobot part)
/// or load_urdf's. Scenes' `model` key reads it.
UrdfRobot load_robot(const std::filesystem::path& path, const UrdfOptions& options = {});

/// Whether `path` names an MJCF file: a .xml extension, or else a root element <mujoco> (the
/// first element of the file). URDF files have the extension .urdf or the root <robot>.
bool is_mjcf_file(const std::filesystem::path& path);

}  // namespace featherdrive
