// A mimic joint as PhysX 5.6.1 has it (PxArticulationMimicJoint): the row
// C = q_a + gear_ratio q_b + offset = 0 coupling two dofs, rigid or soft (natural frequency and
// damping ratio). One impulse lambda acts on both dofs, lambda on a and gear_ratio lambda on b.
// docs/math/mimic_joints.md.
#pragma once

#include <string>
#include <vector>

#include "featherdrive/constraint/mimic_law.hpp"
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

/// The row for a step of h with response r; bias_coefficient is the solver's (PGS 0.8, TGS
/// 2 sqrt(1 / n)), used by a rigid row.
inline MimicRow setup_mimic_row(const MimicJoint& mimic, double r, double h,
                                double bias_coefficient) {
  return mimic_law::setup(mimic.natural_frequency, mimic.damping_ratio, r, h, bias_coefficient);
}

}  // namespace featherdrive
