// A mimic joint as PhysX 5.6.1 has it (PxArticulationMimicJoint): the row
// C = q_a + gear_ratio q_b + offset = 0 coupling two dofs, rigid or soft (natural frequency and
// damping ratio). One impulse lambda acts on both dofs, lambda on a and gear_ratio lambda on b.
// docs/math/mimic_joints.md.
#pragma once

#include <string>
#include <vector>

#include "featherdrive/model/model.hpp"

namespace featherdrive {

struct MimicJoint {
  int dof_a = -1;           ///< the follower of a URDF <mimic> (the joint that has the element)
  int dof_b = -1;           ///< the leader
  double gear_ratio = 1.0;  ///< q_a + gear_ratio q_b + offset = 0 (URDF: -multiplier)
  double offset = 0.0;      ///< URDF: -offset
  /// omega_n [rad/s] and zeta of a soft row; either <= 0 makes it rigid (PhysX's rule).
  double natural_frequency = 0.0;
  double damping_ratio = 0.0;
};

/// "mimic joint 'a' -> 'b'": how messages name a row.
std::string describe(const Model& model, const MimicJoint& mimic);

/// Throws std::invalid_argument naming the joints and the value for: a dof out of range, a dof of
/// a joint that is not revolute or prismatic, a joint mimicking itself, a gear ratio that is 0 or
/// not finite, an offset, natural frequency or damping ratio that is not finite, and rows that
/// close a cycle among the dofs (two rows on one pair included): such rows over-determine the
/// dofs they couple.
void validate_mimic_joints(const Model& model, const std::vector<MimicJoint>& mimic);

/// One row's coefficients for one step (eq. 3-6): lambda = -(bias_per_error C + J v) *
/// effective_mass in position iterations, -J v / r in velocity iterations.
struct MimicRow {
  double response = 0.0;        ///< r = J M^-1 J^T, J = e_a^T + gear_ratio e_b^T (eq. 2)
  double bias_per_error = 0.0;  ///< erp / h
  double effective_mass = 0.0;  ///< 1 / (r + cfm)
};

/// The row for a step of h with response r; bias_coefficient is the solver's (PGS 0.8, TGS
/// 2 sqrt(1 / n)), used by a rigid row.
MimicRow setup_mimic_row(const MimicJoint& mimic, double r, double h, double bias_coefficient);

/// The row's impulse at constraint error C and constraint velocity J v (eq. 5, 6).
inline double mimic_impulse(const MimicRow& row, double error, double velocity,
                            bool velocity_iteration) {
  if (velocity_iteration) return -velocity / row.response;
  return -(row.bias_per_error * error + velocity) * row.effective_mass;
}

}  // namespace featherdrive
