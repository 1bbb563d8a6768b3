// ABA's third pass at one link, shared by aba.cpp and accelerations_and_response
// (inverse_mass_diagonal.cpp): a_i = a_parent + c_i, qdd = D^-1 (u - U^T a_i), a_i += S qdd, in
// frame 0 with gravity as an upward acceleration of the world (Featherstone 2008, table 7.1); at a
// one-dof joint by articulated_law (docs/math/unit_response.md, eq. AP5-AP6).
#pragma once

#include "featherdrive/algorithm/articulated_law.hpp"
#include "featherdrive/algorithm/data.hpp"

namespace featherdrive::detail {

// At a joint with N dofs, on fixed sizes. Out of line: inlined, it costs the 1-dof path
// registers.
template <int N>
[[gnu::noinline]] void joint_acceleration_fixed(Data& data, int i, int v_index, Vec6& a) {
  using Mat6K = Eigen::Matrix<double, 6, N>;
  using VecK = Eigen::Matrix<double, N, 1>;
  const Mat6K U = data.U[i];
  const Eigen::Matrix<double, N, N> D_inv = data.D_inv[i];
  const VecK qdd = D_inv * (data.u.template segment<N>(v_index) - U.transpose() * a);
  data.qdd.template segment<N>(v_index) = qdd;
  a.noalias() += Mat6K(data.motion_subspace[i]) * qdd;
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
  } else if (link.nv > 0) {
    auto qdd = data.qdd.segment(link.v_index, link.nv);
    Vec6 r = Vec6::Zero();  // u - U^T a in the first nv entries, on the stack
    r.head(link.nv) = data.u.segment(link.v_index, link.nv);
    r.head(link.nv).noalias() -= data.U[i].transpose() * a;
    qdd.noalias() = data.D_inv[i] * r.head(link.nv);
    a.noalias() += data.motion_subspace[i] * qdd;
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
