// The immutable, validated description of an articulation. Built once by ModelBuilder::build();
// algorithms read it and never change it, so one Model serves many simulations and threads.
#pragma once

#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "featherdrive/model/shape.hpp"
#include "featherdrive/spatial/spatial.hpp"

namespace featherdrive {

enum class JointType {
  fixed,      ///< welds the link to its parent, 0 dofs
  revolute,   ///< rotation about the axis, 1 dof (bounded or continuous)
  prismatic,  ///< translation along the axis, 1 dof
  spherical,  ///< free rotation, quaternion position (nq = 4), body-frame angular velocity (nv = 3)
  floating    ///< root only: position + quaternion (nq = 7), body-frame [w; v] (nv = 6)
};

const char* to_string(JointType type);

/// A link and its inbound joint (the joint that connects it to its parent).
struct Link {
  std::string name;
  int parent = -1;             ///< index of the parent link, -1 for the world
  std::vector<int> children;   ///< in the order they were added

  double mass = 0.0;
  Vec3 com = Vec3::Zero();               ///< centre of mass in the link frame
  Mat3 inertia_com = Mat3::Zero();       ///< rotational inertia about the centre of mass, link axes
  Mat6 inertia = Mat6::Zero();           ///< spatial inertia about the link frame's origin

  // Inbound joint.
  std::string joint_name;
  JointType joint_type = JointType::fixed;
  Transform tree_transform;    ///< X_T: parent link frame -> joint frame at q = 0
  Vec3 axis = Vec3::UnitZ();   ///< unit axis in the joint frame (revolute, prismatic)
  int q_index = 0;             ///< first entry of this joint in q
  int v_index = 0;             ///< first entry of this joint in v
  int nq = 0;
  int nv = 0;
  Mat6N motion_subspace;       ///< S (6 x nv), constant in the link frame
  int subtree_end = 0;         ///< links [index, subtree_end) form this link's subtree
};

/// A named frame fixed on a link: a URDF link merged into it through fixed joints keeps its name
/// and its pose in that link's frame (x_link = position + rotation x_frame). A link is the frame
/// at its own origin.
struct NamedFrame {
  std::string name;
  int link = 0;
  Vec3 position = Vec3::Zero();
  Mat3 rotation = Mat3::Identity();
};

struct Model {
  std::vector<Link> links;     ///< depth-first preorder from the root, children in insertion order
  int nq = 0;                  ///< size of the configuration vector
  int nv = 0;                  ///< number of degrees of freedom
  Vec3 gravity{0.0, 0.0, -9.81};

  // Per dof (nv x 1).
  VecX armature;               ///< added to the diagonal of the joint-space inertia
  VecX lower_limit;            ///< -inf where unbounded
  VecX upper_limit;            ///< +inf where unbounded
  VecX effort_limit;           ///< +inf where not set (informative; URDF <limit effort>)
  VecX velocity_limit;         ///< +inf where not set (URDF <limit velocity>)
  /// Joint damping and friction (URDF <dynamics>, MJCF damping and frictionloss): a Simulation's
  /// initial viscous and static/dynamic joint friction.
  VecX damping;                ///< viscous joint damping
  VecX friction;               ///< Coulomb joint friction
  std::vector<int> dof_link;   ///< link owning each dof
  std::vector<std::string> dof_names;  ///< joint name, or joint name + ":twist" etc. for multi-dof

  std::vector<NamedFrame> frames;      ///< merged links' frames (names unlike any link's)
  /// Collision shapes, grouped by link in link order (a merged link's shapes are its parent's).
  std::vector<CollisionShape> shapes;
  /// Collision geometry the importer read that contacts cannot use yet (a mesh of a format not
  /// read, a plane, ...), one description each, e.g. "link 'l_foot': mesh collision 'foot.ply'". A
  /// ground is refused while there is any (check_ground_supported, sim/settings.hpp).
  std::vector<std::string> unsupported_shapes;

  bool floating_base() const { return !links.empty() && links[0].joint_type == JointType::floating; }
  int num_links() const { return static_cast<int>(links.size()); }

  /// Index of the link with this name; throws std::invalid_argument naming it if there is none.
  int link_index(const std::string& name) const;
  /// A link (itself at the identity) or a frame by name; throws std::invalid_argument naming it
  /// and the nearest link and frame names if there is none.
  NamedFrame frame(const std::string& name) const;
  /// Index of the link whose inbound joint has this name; throws if there is none.
  int joint_link_index(const std::string& joint_name) const;
  /// First dof index of the named joint; throws if there is none or it has no dofs.
  int dof_index(const std::string& joint_name) const;
  /// q at which every joint is at its reference (zero angles, identity quaternions, root at its
  /// joint origin).
  VecX neutral_configuration() const;
};

}  // namespace featherdrive
