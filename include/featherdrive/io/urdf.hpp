// URDF import (urdfdom): links, inertials, fixed / revolute / continuous / prismatic joints,
// limits, dynamics and mimic tags. Fixed joints are merged into their parent's inertia, so the
// Model holds the root and the links behind moving joints only.
#pragma once

#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "featherdrive/constraint/contact.hpp"
#include "featherdrive/constraint/mimic_row.hpp"
#include "featherdrive/io/error.hpp"
#include "featherdrive/model/model_builder.hpp"
#include "featherdrive/sim/settings.hpp"

namespace featherdrive {

/// Elements nested deeper than this are refused before any XML reader sees the text (TinyXML
/// recurses per level); real URDFs are under 10 deep.
inline constexpr int kMaxUrdfDepth = 100;

/// What a URDF <limit effort> becomes (apply_urdf_effort_limits): Isaac Lab's effort_limit_sim or
/// effort_limit (docs/conventions.md, "Actuators").
enum class UrdfEffort {
  none,          ///< informative only (UrdfRobot::effort_limits)
  max_force,     ///< every implicit drive's max_force, the solver's bound
  effort_limit,  ///< every explicit actuator's effort_limit, its clip
};
const char* to_string(UrdfEffort effort);

struct UrdfOptions {
  /// true: the root link is welded to the world; false: it gets a floating joint.
  bool fixed_base = true;
  Vec3 gravity{0.0, 0.0, -9.81};
  UrdfEffort effort = UrdfEffort::none;
};

/// A <mimic> tag: joint = multiplier * leader + offset (simulated as UrdfRobot::mimic_joints).
struct UrdfMimic {
  std::string joint;
  std::string leader;
  double multiplier = 1.0;
  double offset = 0.0;
};

/// A link merged into an ancestor through fixed joints: its frame's pose in the ancestor's frame.
struct MergedLink {
  std::string into;
  Vec3 xyz = Vec3::Zero();
  Mat3 rotation = Mat3::Identity();
};

/// A <visual> or <collision> geometry as the URDF writes it, placed in the frame of the model link
/// it moves with (read for exports and viewers; the dynamics never use it).
struct UrdfGeometry {
  enum class Shape { box, cylinder, sphere, mesh };
  std::string link;  ///< the URDF link that has it
  std::string name;  ///< the element's name attribute, or ""
  std::string body;  ///< the model link it moves with: link, or the one link was merged into
  bool collision = false;  ///< <collision>; else <visual>
  int index = 0;           ///< its place among link's visuals (or collisions)
  Shape shape = Shape::box;
  /// box: the full extents; cylinder: radius, length (along z), 0; sphere: radius, 0, 0.
  Vec3 size = Vec3::Zero();
  std::string filename;          ///< mesh: as written (package://, file:// or relative)
  Vec3 scale = Vec3::Ones();     ///< mesh
  Vec3 xyz = Vec3::Zero();       ///< the geometry frame's origin in body's frame
  Mat3 rotation = Mat3::Identity();
};

struct UrdfRobot {
  std::filesystem::path path;
  std::string name;  ///< <robot name>
  std::string root_link;
  std::string root_joint;  ///< the name given to the root's joint (fixed or floating)
  UrdfOptions options;
  /// The builder's input after merging, in URDF document order; edit and call rebuild() to change
  /// what URDF cannot say (armature).
  std::vector<LinkSpec> links;
  std::shared_ptr<const Model> model;
  /// Every <joint> in document order, fixed ones included.
  std::vector<std::string> joint_order;
  /// The model dofs in URDF document order: the floating root's first, then one per moving joint.
  std::vector<int> dof_order;
  /// Maps between the file's joint order (joint_order, index j) and the model's: the first dof of
  /// joint j (-1 for a fixed joint), the model link its child is (for a fixed joint, the link the
  /// child was merged into), and the joint_order index of each dof (-1 for a floating root's).
  std::vector<int> dof_of_urdf_joint, link_of_urdf_joint, urdf_joint_of_dof;
  std::vector<UrdfMimic> mimics;
  /// The mimic tags as rigid mimic rows: a = the joint, b = the leader, gear_ratio = -multiplier,
  /// offset = -offset (docs/math/mimic_joints.md); scenes apply them (make_simulation).
  std::vector<MimicJoint> mimic_joints;
  std::map<std::string, MergedLink> merged;  ///< merged link name -> where it went
  /// Every link's visuals, then its collisions, links in document order (merged ones included).
  std::vector<UrdfGeometry> geometry;
  /// Collision shapes by model link (or frame) name, poses in its frame: URDF <collision> box
  /// and sphere, MJCF sphere, capsule and box geoms; rebuild() gives them to the model (a scene's
  /// `shapes:` are added to this list too).
  std::vector<std::pair<std::string, CollisionShape>> shapes;
  /// Collision geometry contacts cannot use yet (URDF meshes other than STL, OBJ, MSH and DAE;
  /// MJCF planes and height fields on links): Model::unsupported_shapes.
  std::vector<std::string> unsupported_shapes;
  /// The file's own floor: an MJCF plane geom on the world body (enabled, its height along its
  /// normal, friction[0] as static and dynamic friction). A scene of the file takes it unless
  /// the scene says `ground:` itself. URDF has none.
  std::optional<Ground> ground;
  std::vector<std::string> warnings;         ///< for the user (mimic tags ignored, ...)
  /// The URDF effort limit of each moving joint (informative; drives need their own max_force).
  std::map<std::string, double> effort_limits;
  /// The file's joint springs (MJCF's hinge and slide stiffness toward qpos_spring; URDF has
  /// none), which robot_settings and a scene's settings give their dofs as joint_spring rows
  /// (constraint/joint_spring.hpp; apply_robot_springs).
  struct Spring {
    std::string joint;
    double stiffness = 0.0;
    double reference = 0.0;  ///< featherdrive's q (MJCF: MuJoCo's qpos)
  };
  std::vector<Spring> springs;
  /// Every file the loader read or that MuJoCo opens for it: the robot file, and for MJCF its
  /// includes and its mesh, skin, hfield and texture files. No output of a run may replace one
  /// (the CLI's check_outputs).
  std::vector<std::filesystem::path> input_files;

  /// Builds model from links again; throws InputError naming the file.
  void rebuild();
};

/// Reads a URDF file. Throws InputError naming the file, the element and the value for a
/// malformed file, one nested deeper than kMaxUrdfDepth, a link that is the child of two joints, a
/// name with a control character, an unsupported joint type (floating, planar) or a moving link
/// without <inertial>.
UrdfRobot load_urdf(const std::filesystem::path& path, const UrdfOptions& options = {});

/// The same from a string; `name` stands for the file in messages.
UrdfRobot parse_urdf(const std::string& xml, const std::string& name,
                     const UrdfOptions& options = {});

class Simulation;
/// Gives each moving joint's URDF effort limit (where the URDF has one) to what
/// robot.options.effort names, on `sim` (a simulation of robot.model) as it is now: a drive of
/// type != none without its own max_force or max_impulse gets max_force, an explicit actuator
/// without its own effort_limit gets effort_limit (set again: its delay history starts over).
/// Call it after setting the drives and actuators, before stepping.
void apply_urdf_effort_limits(const UrdfRobot& robot, Simulation& sim);
/// The same on settings of robot.model.
void apply_urdf_effort_limits(const UrdfRobot& robot, Settings& settings);
/// The robot's springs (UrdfRobot::springs) into settings' joint_spring rows.
void apply_robot_springs(const UrdfRobot& robot, Settings& settings);

/// What the file says beyond the Model, as the settings a simulation starts from
/// (Simulation(robot.model, settings), Batch(robot.model, N, settings)): Settings::defaults with
/// `options` (limits, friction, damping and velocity limits are the model's), the <mimic> rows,
/// and the effort limits as robot.options.effort says (apply_urdf_effort_limits). Throws
/// std::invalid_argument for invalid options.
Settings robot_settings(const UrdfRobot& robot, const SimulationOptions& options = {});

/// Roll, pitch, yaw of R = Rz(yaw) Ry(pitch) Rx(roll) (the inverse of rotation_from_rpy), for
/// joint origins composed through merged fixed joints.
Vec3 rpy_from_rotation(const Mat3& R);

}  // namespace featherdrive
