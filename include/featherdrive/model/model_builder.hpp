// Builds a Model from link descriptions with URDF's conventions, validating everything once.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "featherdrive/model/model.hpp"

namespace featherdrive {

/// Bad model input: the message names the link or joint, the field and the value.
class ModelError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// The inbound joint of a link, as in URDF: the joint frame's pose in the parent link frame is
/// (origin_xyz, origin_rpy); the axis is in the joint frame; the child link frame is the joint frame
/// moved by the joint's motion.
struct JointSpec {
  std::string name;
  JointType type = JointType::fixed;
  Vec3 origin_xyz = Vec3::Zero();
  Vec3 origin_rpy = Vec3::Zero();
  Vec3 axis = Vec3::UnitX();       ///< need not be unit length; must not be zero
  /// Armature: empty (none), one value (every dof of the joint) or one value per dof.
  std::vector<double> armature;
  double lower_limit = -std::numeric_limits<double>::infinity();
  double upper_limit = std::numeric_limits<double>::infinity();
  double effort_limit = std::numeric_limits<double>::infinity();
  double velocity_limit = std::numeric_limits<double>::infinity();
  double damping = 0.0;
  double friction = 0.0;
};

/// A link with its inertial (URDF <inertial>: mass, origin of the centre of mass in the link frame,
/// full inertia tensor about the centre of mass in link axes) and its inbound joint.
struct LinkSpec {
  std::string name;
  std::string parent;             ///< empty for the root link
  double mass = 0.0;
  Vec3 com = Vec3::Zero();
  Mat3 inertia = Mat3::Zero();
  JointSpec joint;
};

/// Why a link or joint name is refused ("name 'a\x0a' contains a control character (0x0a)"), or
/// "" when it is fine. Names go into CSV headers, JSON and one-line messages, so control
/// characters (0x00 to 0x1f, 0x7f) are refused; the name is shown with them escaped.
std::string name_problem(const std::string& name);

/// Shorthands for the joint of each type.
JointSpec fixed_joint(std::string name, const Vec3& xyz = Vec3::Zero(), const Vec3& rpy = Vec3::Zero());
JointSpec revolute_joint(std::string name, const Vec3& axis, const Vec3& xyz = Vec3::Zero(),
                         const Vec3& rpy = Vec3::Zero());
JointSpec prismatic_joint(std::string name, const Vec3& axis, const Vec3& xyz = Vec3::Zero(),
                          const Vec3& rpy = Vec3::Zero());
JointSpec spherical_joint(std::string name, const Vec3& xyz = Vec3::Zero(),
                          const Vec3& rpy = Vec3::Zero());
JointSpec floating_joint(std::string name);

/// Sets link's mass, com, inertia about the com (symmetrised) and spatial inertia, validated as
/// ModelBuilder::build() validates a LinkSpec's (`can_move`: the link or an ancestor has a dof);
/// throws ModelError naming link.name, the field and the value.
void set_link_inertial(Link& link, double mass, const Vec3& com, const Mat3& inertia,
                       bool can_move);

/// A shape's sizes (finite, > 0, as its type reads them), pose (finite position, a rotation
/// matrix) and material (frictions finite and >= 0, restitution in [0, 1]); throws ModelError
/// "model: <who>: <field> = <value> ...". `who` names the shape and its link.
void check_shape(const std::string& who, const CollisionShape& shape);
/// "shape 'foot' (sphere) of link 'shin'", or "shape #3 ..." when the shape has no name.
std::string shape_label(const CollisionShape& shape, size_t index, const std::string& link);

/// A link description in one call.
LinkSpec make_link(std::string name, std::string parent, double mass, const Vec3& com,
                   const Mat3& inertia, JointSpec joint);

class ModelBuilder {
 public:
  ModelBuilder& set_gravity(const Vec3& gravity);
  ModelBuilder& add_link(LinkSpec link);
  /// A named frame fixed on `link` at (xyz, rotation) in its frame (Model::frames); build()
  /// checks that the link exists and the name is new.
  ModelBuilder& add_frame(std::string name, std::string link, const Vec3& xyz,
                          const Mat3& rotation);
  /// A collision shape on `link` (shape.link is set by build()); build() checks the link, the
  /// sizes (finite, > 0), the pose and the material (friction >= 0, restitution in [0, 1]).
  /// `link` may name a frame (add_frame): the shape goes to its link, its pose composed.
  ModelBuilder& add_shape(std::string link, CollisionShape shape);
  /// Geometry the importer saw that contacts cannot use yet (Model::unsupported_shapes).
  ModelBuilder& add_unsupported_shape(std::string description);
  /// Validates everything and returns the model; throws ModelError naming the offending link or
  /// joint, field and value.
  Model build() const;

 private:
  Vec3 gravity_{0.0, 0.0, -9.81};
  std::vector<LinkSpec> links_;
  std::vector<std::pair<NamedFrame, std::string>> frames_;  // the frame and its link's name
  std::vector<std::pair<CollisionShape, std::string>> shapes_;  // the shape and its link's name
  std::vector<std::string> unsupported_shapes_;
};

}  // namespace featherdrive
