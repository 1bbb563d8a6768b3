// Trajectory CSV files: one row per state, columns per dof in the URDF's joint order.
//   step,t,q:<joint>...,qd:<joint>...,f:<joint>...
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

/// Column names after step,t: q (nq of them: a floating root gives x, y, z, qw, qx, qy, qz), then
/// qd and f (one per dof).
std::vector<std::string> trajectory_columns(const UrdfRobot& robot);

class TrajectoryWriter {
 public:
  TrajectoryWriter(std::ostream& out, const UrdfRobot& robot);
  /// One row of the simulation's state; `initial` writes f = 0 (no step has run).
  void write(long step, const Simulation& sim, bool initial = false);

 private:
  std::ostream& out_;
  std::vector<int> q_order_, v_order_;
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
