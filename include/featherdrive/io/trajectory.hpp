// Trajectory CSV files: one row per state, columns per dof in the URDF's joint order.
//   step,t,q:<joint>...,qd:<joint>...,f:<joint>...[,target:<joint>...,target_velocity:<joint>...]
//   [,contact:<link>:fx,contact:<link>:fy,contact:<link>:fz...][,foot:<name>:fx,fy,fz...]
//   [,guard_substeps]
// q:<joint> is each dof's position (model/dof_position.hpp): a spherical joint's three axes are
// PhysX's positions, a floating root's q its 7 entries. The targets of row k are the drive's
// commanded target during the step from row k to row k + 1, as `featherdrive fit` reads a log.
// contact:<link> is the ground's force on each link with shapes over the step that reached the
// row (Simulation::link_contact_force, world axes, N; 0 in the initial row), with the ground on;
// foot:<name> the sum of those of the foot's links (scene key feet).
// Numbers are written in the shortest form that reads back to the same double. A column name
// holding a comma, a quote or a line break is quoted as RFC 4180 says (csv_field).
#pragma once

#include <ostream>
#include <string>
#include <vector>

#include "featherdrive/io/scene.hpp"

namespace featherdrive {

/// `s` as one CSV field: unchanged, or in double quotes (quotes doubled) when it holds a comma,
/// a quote or a line break (RFC 4180).
std::string csv_field(const std::string& s);

/// Column names after step,t: q (a floating root gives x, y, z, qw, qx, qy, qz, then one per dof
/// with a position), then qd and f (one per dof), then target and target_velocity of each of
/// `target_dofs` (in URDF order), then fx, fy, fz of each of `contact_links`, then of each foot.
std::vector<std::string> trajectory_columns(const UrdfRobot& robot,
                                            const std::vector<int>& target_dofs = {},
                                            const std::vector<int>& contact_links = {},
                                            const std::vector<Foot>& feet = {});

/// The sum of the contact forces of the foot's links over sim's last step (world axes, N).
Vec3 foot_contact_force(const Simulation& sim, const Foot& foot);

/// The links that carry shapes, in link order: those whose contact force a log holds.
std::vector<int> shape_links(const Model& model);

/// The dofs a scene's log gives targets for: those with an implicit drive (type force or
/// acceleration), in URDF order.
std::vector<int> target_dofs(const Scene& scene);

class TrajectoryWriter {
 public:
  /// target_dofs: the dofs whose drive targets each row holds (target_dofs(scene), or none).
  /// guard_substeps: a last column with the sub-steps the step guard took for the step that
  /// reached the row's state (1 for the initial row; docs/math/step_guard.md).
  /// contact_forces: the contact:<link> columns of shape_links (pass sim.ground().enabled),
  /// then the foot:<name> columns of `feet` (scene.feet).
  TrajectoryWriter(std::ostream& out, const UrdfRobot& robot,
                   const std::vector<int>& target_dofs = {}, bool guard_substeps = false,
                   bool contact_forces = false, const std::vector<Foot>& feet = {});
  /// One row of the simulation's state and its drives' current targets; `initial` writes f = 0
  /// (no step has run).
  void write(long step, const Simulation& sim, bool initial = false);

 private:
  std::ostream& out_;
  std::vector<int> q_order_, v_order_, target_order_, contact_links_;
  std::vector<Foot> feet_;
  bool guard_substeps_ = false;
};

/// The drive targets of a scene at each row's time t = step dt (target position per driven
/// joint), for plotting beside a trajectory: step,t,target:<joint>...
class TargetWriter {
 public:
  TargetWriter(std::ostream& out, const Scene& scene);
  void write(long step, double t);

 private:
  std::ostream& out_;
  const Scene& scene_;
};

}  // namespace featherdrive
