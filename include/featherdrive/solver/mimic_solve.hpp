// The mimic rows of a step (constraint/mimic_row.hpp), solved as PhysX 5.6.1 solves them: every
// iteration, position and velocity, first each mimic row in order with the exact current joint
// velocities, then the dof rows' sweep (solveInternalConstraints). The rows' impulses reach every
// dof through one extra sweep, so an iteration costs O(n) plus O(m k) for m rows on k distinct
// dofs (docs/math/mimic_joints.md, "In the sweep").
#pragma once

#include <optional>
#include <vector>

#include "featherdrive/constraint/mimic_row.hpp"
#include "featherdrive/solver/gauss_seidel.hpp"

namespace featherdrive {

class MimicSolver {
 public:
  MimicSolver() = default;
  /// Validates the rows (validate_mimic_joints) and sizes every buffer a step uses.
  MimicSolver(const Model& model, std::vector<MimicJoint> joints);

  bool empty() const { return joints_.empty(); }
  const std::vector<MimicJoint>& joints() const { return joints_; }

  /// Once per step, after articulated_response: each row's response r = J M^-1 J^T and its
  /// velocity change at the coupled dofs per unit impulse, one sweep per row (eq. 2, 7).
  void setup(const Model& model, const Data& data, double h, double bias_coefficient);
  /// Every row once, in order, at positions q and velocities qd + row_bias (row_bias may be
  /// null), then their impulses applied: qd is exact on exit.
  void solve(const Model& model, const Data& data, const VecX& q, const double* row_bias,
             bool velocity_iteration, VecX& qd);

 private:
  std::vector<MimicJoint> joints_;
  std::vector<int> dofs_;             ///< the k distinct dofs the rows couple
  std::vector<int> q_index_;          ///< their positions in q
  std::vector<int> slot_a_, slot_b_;  ///< each row's dofs as indices into dofs_
  std::vector<MimicRow> rows_;
  std::vector<double> velocity_change_;  ///< m x k: dofs_' velocity change per unit lambda of row j
  std::vector<double> velocity_;         ///< k: current velocities of dofs_ during a pass
  VecX impulse_, scratch_;               ///< nv each; impulse_ is nonzero at dofs_ only
  std::optional<SweepWorkspace> sweep_;  ///< has_rows at dofs_
};

}  // namespace featherdrive
