// Per-simulation workspace of the algorithms (after Pinocchio's Model/Data split): everything an
// algorithm writes lives here, sized once from the Model, so a step never allocates.
//
// Two frames are used. The kinematics (forward_kinematics) and the inverse dynamics (rnea, crba)
// keep per-link quantities in the link's own frame. The articulated-body algorithm, the response
// and the Gauss-Seidel sweep work in one common frame, "frame 0": world axes, origin at the root
// link's origin (`frame_origin`, taken from the kinematics when aba_from_kinematics or
// articulated_inertias runs). In a common frame nothing has to be transformed from link to link:
// a child hands its articulated inertia to its parent by adding it (docs/math/unit_response.md,
// "Frame 0").
#pragma once

#include <vector>

#include "featherdrive/model/model.hpp"

namespace featherdrive {

struct Data {
  explicit Data(const Model& model);

  /// What the passes read of a link, copied from the Model once, contiguous.
  struct LinkInfo {
    int parent = -1;
    int nv = 0;
    int v_index = 0;
    int q_index = 0;
    JointType type = JointType::fixed;
    bool last_child = true;  ///< no sibling after it in the model order
    bool later = false;      ///< it or an ancestor has a sibling after it (a later subtree)
    bool tree_rotation_identity = false;  ///< the joint frame is parallel to the parent frame
    bool inertia_diagonal = false;        ///< the inertia about the centre of mass is diagonal
    /// k when a revolute or prismatic joint's axis is +-e_k (the kinematics' and ABA's shortcut:
    /// a rotation about a coordinate axis mixes two columns), else -1; axis_sign is the sign.
    int unit_axis = -1;
    double axis_sign = 1.0;
    /// A revolute joint about +-e_k whose frame is parallel to its parent link's, not the root:
    /// the kinematics' shortcut (only two columns of the parent's rotation mix).
    bool coordinate_revolute = false;
  };
  std::vector<LinkInfo> info;
  /// What the kinematics and the articulated-body passes read of a link, copied from the Model
  /// once and stored contiguously (a Link spreads them over a kilobyte).
  struct LinkConstants {
    Transform tree_transform;
    Vec3 axis = Vec3::UnitZ();
    Vec3 com = Vec3::Zero();
    Mat3 inertia_com = Mat3::Zero();
    double mass = 0.0;
  };
  std::vector<LinkConstants> constants;

  // Kinematics (forward_kinematics), one entry per link, link frames.
  std::vector<Transform> parent_transform;  ///< X_i: parent frame (world for the root) -> link i
  std::vector<Mat3> world_rotation;         ///< link frame orientation in the world
  std::vector<Vec3> world_position;         ///< link frame origin in the world
  std::vector<Vec3> frame_position;         ///< link frame origin in frame 0 (JT-12)
  std::vector<Vec6> velocity;               ///< spatial velocity v_i, link frame
  std::vector<Vec6> bias_acceleration;      ///< c_i = v_i x (S_i qd_i), link frame

  // Frame 0 (world axes, origin frame_origin): the articulated-body algorithm. motion_subspace,
  // U, D_inv and parent_coupling are kept for joints with nv_i != 1 only; 1-dof joints (revolute,
  // prismatic) keep theirs in one_dof below.
  Vec3 frame_origin = Vec3::Zero();
  std::vector<Mat6N> motion_subspace;       ///< S_i in frame 0 (6 x nv_i); a floating root's 6 x 0
                                            ///< (diag(R_i, R_i), read from world_rotation)
  std::vector<Vec6> velocity0;              ///< v_i in frame 0 (aba_from_kinematics)
  std::vector<Vec6> bias_acceleration0;     ///< c_i = v_i x (S_i qd_i) in frame 0
  std::vector<Mat6> articulated_inertia;    ///< IA_i, frame 0
  std::vector<Vec6> articulated_bias;       ///< pA_i, frame 0
  std::vector<Mat6N> U;                     ///< U_i = IA_i S_i (6 x nv_i), frame 0
  std::vector<MatNN> D_inv;                 ///< (S_i^T U_i + armature)^-1 (nv_i x nv_i)
  VecX u;                                   ///< tau - S^T pA (nv)
  std::vector<Vec6> acceleration0;          ///< a_i, frame 0 (gravity as an upward acceleration)
  VecX qdd;                                 ///< joint accelerations (nv)

  // Whole-articulation response (articulated_response), frame 0.
  std::vector<Mat6> response;               ///< Lambda_i: a_i = Lambda_i f for a force f on link i
  std::vector<Mat6N> parent_coupling;       ///< W_i = Lambda_parent U_i (6 x nv_i)
  std::vector<MatNN> inverse_mass_block;    ///< (M^-1)_ii, the joint's diagonal block
  VecX inverse_mass_diagonal;               ///< diag(M^-1) (nv)

  /// S_i, U_i, W_i (6-vectors), D_i^-1 and (M^-1)_ii (numbers) of 1-dof joints (nv_i = 1), packed
  /// per link for the passes and the sweep. Links with other joints leave theirs unused.
  struct OneDof {
    Vec6 S = Vec6::Zero();
    Vec6 U = Vec6::Zero();
    Vec6 W = Vec6::Zero();
    /// G_i = (M^-1)_ii S_i - D_i^-1 W_i: the joint's velocity change is -G_i^T f under an impulse
    /// f handed to link i by its subtree (docs/math/implicit_drives.md, "Propagating impulses").
    Vec6 G = Vec6::Zero();
    double D_inv = 0.0;
    double inverse_mass = 0.0;
    /// With a 1-dof parent p: U_i^T W_p and U_i^T S_p (the sweep's scalar shortcuts); else 0.
    double parent_W = 0.0;
    double parent_S = 0.0;
    /// With a 1-dof parent p, the sweep's base_i (gauss_seidel_sweep) as base_p times the first
    /// plus p's impulse times the second, plus a term in p's parent's velocity change:
    /// -D_i^-1 U_i^T S_p and D_p^-1 D_i^-1 U_i^T W_p + (M^-1)_pp times the first; else 0.
    double base_per_parent_base = 0.0;
    double base_per_parent_impulse = 0.0;
  };
  std::vector<OneDof> one_dof;

  // Inverse dynamics and joint-space inertia (link frames).
  std::vector<Vec6> acceleration;           ///< a_i (rnea)
  std::vector<Vec6> force;                  ///< f_i (rnea)
  VecX tau;                                 ///< rnea output (nv)
  std::vector<Mat6> composite_inertia;      ///< Ic_i (crba)
  MatX M;                                   ///< joint-space inertia (nv x nv), armature included

  // Centre-of-mass Jacobian (center_of_mass_jacobian), world coordinates.
  std::vector<double> subtree_mass;         ///< mass of link i's subtree
  std::vector<Vec3> subtree_moment;         ///< sum of m_k c_k over link i's subtree
};

}  // namespace featherdrive
