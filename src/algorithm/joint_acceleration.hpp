// ABA's third pass at one link, shared by aba.cpp and accelerations_and_response
// (inverse_mass_diagonal.cpp): a_i = a_parent + c_i, qdd = D^-1 (u - U^T a_i), a_i += S qdd, in
// frame 0 with gravity as an upward acceleration of the world (Featherstone 2008, table 7.1); at a
// one-dof joint by articulated_law (docs/math/unit_response.md, eq. AP5-AP6).
#pragma once

#include "featherdrive/algorithm/articulated_law.hpp"
#include "featherdrive/algorithm/data.hpp"
#include "featherdrive/algorithm/multi_dof_law.hpp"

namespace featherdrive::detail {

// S of a joint of N dofs as multi_dof_law reads it: a spherical joint's dense, a floating root's
// diag(R, R) from its rotation (the root's origin is frame 0's: the same values as
// motion_subspace's, with half the products).
template <int N>
struct Subspace {
  using type = multi_dof_law::DenseSubspace<double, N>;
  static type of(const Data& data, int i) { return {data.motion_subspace[i].data()}; }
};
template <>
struct Subspace<6> {
  using type = multi_dof_law::RotationPair<double, true>;
  static type of(const Data& data, int i) { return {data.world_rotation[i].data()}; }
};

// At a joint with N dofs (multi_dof_law, eq. AP12-AP13). Out of line: inlined, it costs the
// 1-dof path registers.
template <int N>
[[gnu::noinline]] void joint_acceleration_fixed(Data& data, int i, int v_index, Vec6& a) {
  double qdd[N];
  multi_dof_law::joint_acceleration<N>(data.U[i].data(), data.D_inv[i].data(),
                                       data.u.data() + v_index, a.data(), qdd);
  for (int d = 0; d < N; ++d) data.qdd[v_index + d] = qdd[d];
  multi_dof_law::add_joint_motion(Subspace<N>::of(data, i), qdd, a.data());
}

// Link i's qdd and acceleration0 (its parent's are done; a_world for the root).
[[gnu::always_inline]] inline void link_acceleration(Data& data, int i, const Vec6& a_world) {
  const Data::LinkInfo& link = data.info[i];
  Vec6 a =
      (link.parent >= 0 ? data.acceleration0[link.parent] : a_world) + data.bias_acceleration0[i];
  if (link.nv == 1) {  // docs/math/unit_response.md, eq. AP5-AP6
    const Data::OneDof& J = data.one_dof[i];
    const double qdd =
        articulated_law::joint_acceleration(J.U.data(), J.D_inv, data.u[link.v_index], a.data());
    data.qdd[link.v_index] = qdd;
    // AP6 as Eigen's pairs, the same operations as add_joint_motion's: after the dot product's
    // scalar sum clang does add_joint_motion in six scalar steps (18 instructions a link more).
    a += qdd * J.S;
  } else if (link.nv == 6) {
    joint_acceleration_fixed<6>(data, i, link.v_index, a);
  } else if (link.nv == 3) {
    joint_acceleration_fixed<3>(data, i, link.v_index, a);
  }
  data.acceleration0[i] = a;
}

// The world's acceleration: gravity's opposite.
inline Vec6 world_acceleration(const Model& model) {
  Vec6 a = Vec6::Zero();
  a.tail<3>() = -model.gravity;
  return a;
}

}  // namespace featherdrive::detail
