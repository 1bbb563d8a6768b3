// Per-simulation workspace of the algorithms (after Pinocchio's Model/Data split): everything an
// algorithm writes lives here, sized once from the Model, so a step never allocates. Per-link
// quantities are in the link's own frame unless the name says otherwise.
#pragma once

#include <vector>

#include "featherdrive/model/model.hpp"

namespace featherdrive {

struct Data {
  explicit Data(const Model& model);

  // Kinematics (forward_kinematics), one entry per link.
  std::vector<Transform> parent_transform;  ///< X_i: parent frame (world for the root) -> link i
  std::vector<Mat3> world_rotation;         ///< link frame orientation in the world
  std::vector<Vec3> world_position;         ///< link frame origin in the world
  std::vector<Vec6> velocity;               ///< spatial velocity v_i
  std::vector<Vec6> bias_acceleration;      ///< c_i = v_i x (S_i qd_i)

  // Articulated-body algorithm.
  std::vector<Mat6> articulated_inertia;    ///< IA_i
  std::vector<Vec6> articulated_bias;       ///< pA_i
  std::vector<Mat6N> U;                     ///< U_i = IA_i S_i (6 x nv_i)
  std::vector<MatNN> D_inv;                 ///< (S_i^T U_i + armature)^-1 (nv_i x nv_i)
  VecX u;                                   ///< tau - S^T pA (nv)
  std::vector<Vec6> acceleration;           ///< a_i
  VecX qdd;                                 ///< joint accelerations (nv)

  // Whole-articulation response (inverse_mass_diagonal).
  std::vector<Mat6> response;               ///< Lambda_i: a_i = Lambda_i f for a force f on link i
  std::vector<Mat6N> parent_coupling;       ///< W_i = (X_i Lambda_parent X_i^T) U_i (6 x nv_i)
  std::vector<MatNN> inverse_mass_block;    ///< (M^-1)_ii, the joint's diagonal block
  VecX inverse_mass_diagonal;               ///< diag(M^-1) (nv)

  // Inverse dynamics and joint-space inertia.
  std::vector<Vec6> force;                  ///< f_i (rnea)
  VecX tau;                                 ///< rnea output (nv)
  std::vector<Mat6> composite_inertia;      ///< Ic_i (crba)
  MatX M;                                   ///< joint-space inertia (nv x nv), armature included
};

}  // namespace featherdrive
