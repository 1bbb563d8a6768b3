// The articulated-body algorithm in frame 0 (world axes, origin at the root link's origin;
// docs/math/unit_response.md, "Frame 0"): every link's subspace and inertia are brought into that
// frame once, after which a child hands its articulated inertia and bias force to its parent by
// plain addition. 1-dof joints (S a 6-vector, D a number) take a path of their own.
#include "featherdrive/algorithm/aba.hpp"

#include <cmath>

#include "featherdrive/algorithm/articulated_law.hpp"
#include "featherdrive/algorithm/kinematics.hpp"
#include "featherdrive/algorithm/link_motion_law.hpp"
#include "featherdrive/algorithm/multi_dof_law.hpp"
#include "featherdrive/spatial/joint_transform_law.hpp"
#include "joint_acceleration.hpp"
#include "mat6_storage.hpp"

namespace featherdrive {
namespace {

// A link's rigid-body inertia in frame 0 by its parts, I = [A, m c x; m c x^T, m 1]
// (link_motion_law, eq. P1-2): A's six distinct entries, m c and m.
struct BodyInertia {
  double A[6];
  double mc[3];  ///< m c
  double m;
};

// The inertia of a link with orientation R at p (relative to the frame origin). Forced inline:
// out of line, b returns through memory (20 instructions a link more in pass 1).
[[gnu::always_inline]] inline BodyInertia body_inertia(const Data::LinkConstants& link,
                                                       bool diagonal, const Mat3& R,
                                                       const Vec3& p) {
  BodyInertia b;
  b.m = link.mass;
  Mat3 RI;  // R Ic_link, or R's columns scaled by the principal moments (eq. P1-1)
  const Mat3& Ic = link.inertia_com;
  if (diagonal) link_motion_law::rotate_principal(R, Ic(0, 0), Ic(1, 1), Ic(2, 2), RI);
  else link_motion_law::rotate_full(R, Ic, RI);
  double c[3];
  link_motion_law::centre_of_mass(R, p.data(), link.com.data(), b.m, c, b.mc);
  link_motion_law::rotational_block(R, RI, c, b.mc, b.A);
  return b;
}

// The 6 x 6 matrix of b, column by column.
inline void write_inertia(const BodyInertia& b, Mat6& I) {
  const double* A = b.A;
  const double x = b.mc[0], y = b.mc[1], z = b.mc[2], m = b.m;
  I.col(0) << A[0], A[3], A[4], 0.0, -z, y;
  I.col(1) << A[3], A[1], A[5], z, 0.0, -x;
  I.col(2) << A[4], A[5], A[2], -y, x, 0.0;
  I.col(3) << 0.0, z, -y, m, 0.0, 0.0;
  I.col(4) << -z, 0.0, x, 0.0, m, 0.0;
  I.col(5) << y, -x, 0.0, 0.0, 0.0, m;
}

// Link i's joint frame axes P = R_p E_T^T (eq. JT-5), as kinematics.cpp's position_link forms
// them: E_T^T at the root (its parent, the world, does not rotate), R_p where X_T does not
// rotate. Out of line: only a joint about another than a coordinate axis takes it.
[[gnu::noinline]] Mat3 joint_frame_of(const Data& data, int i) {
  const Data::LinkInfo& link = data.info[i];
  const Mat3& E = data.constants[i].tree_transform.E;
  if (link.parent < 0) return E.transpose();
  const Mat3& Rp = data.world_rotation[link.parent];
  if (link.tree_rotation_identity) return Rp;
  Mat3 P;
  joint_transform_law::joint_frame(Rp, E, P);
  return P;
}

// S_i in frame 0 of a 1-dof joint (eq. JT-10) from its world axis a_w = P a (eq. JT-8), as the
// lanes' link_pose forms it: about a coordinate axis from R, whose column k is P's (eq. JT-3),
// else from P formed again. Forced inline: out of line, chain256's step took 0.6 % more
// instructions.
[[gnu::always_inline]] inline void one_dof_subspace(const Data& data, int i, const Mat3& R,
                                                    const Vec3& p, Vec6& S) {
  const Data::LinkInfo& link = data.info[i];
  const Vec3& axis = data.constants[i].axis;
  double a[3];
  if (link.unit_axis >= 0)
    joint_transform_law::joint_axis(R, link.unit_axis, link.axis_sign, axis, a);
  else
    joint_transform_law::joint_axis(joint_frame_of(data, i), -1, link.axis_sign, axis, a);
  joint_transform_law::one_dof_subspace(a, p, link.type == JointType::revolute, S);
}

// S_i in frame 0: a 1-dof joint's (above), a spherical joint's [R; p x R] (eq. JT-11). A floating
// root's, diag(R, R) (its origin is frame 0's), is not stored: every reader takes it from R
// (multi_dof_law::RotationPair).
void subspace_in_frame0(Data& data, int i, const Mat3& R, const Vec3& p) {
  const Data::LinkInfo& link = data.info[i];
  if (link.nv == 1) {
    one_dof_subspace(data, i, R, p, data.one_dof[i].S);
  } else if (link.nv == 3) {
    joint_transform_law::ball_subspace(
        R, p, joint_transform_law::columns(data.motion_subspace[i].data()));
  }
}

// The base of a Data array of Mat6, Vec6 or OneDof, which Eigen aligns to 16 bytes: said so, the
// compiler knows every element's entry pairs are aligned (the element sizes are multiples of 16)
// and SSE2 folds their loads into the arithmetic, as Eigen's own column operations did (42
// instructions a link fewer in pass 2 on chain256, docs/benchmarks.md).
template <class X>
X* aligned(X* p) {
  static_assert(alignof(X) >= 16 && sizeof(X) % 16 == 0);
  return static_cast<X*>(__builtin_assume_aligned(p, 16));
}

// A correctly rounded square root, for multi_dof_law::spd_inverse.
struct Sqrt {
  double operator()(double x) const { return std::sqrt(x); }
};

// ABA pass 2 at a joint of N dofs (multi_dof_law, docs/math/unit_response.md, eq. AP7-AP11):
// U, D^-1 and the parent's I^A; with kBias also u and the parent's p^A. S: the joint's
// (detail::Subspace). Out of line: inlined, it costs the 1-dof path registers.
template <int N, bool kBias>
[[gnu::noinline]] void multi_dof_pass(const Model& model, Data& data, int i, const VecX* tau) {
  const Data::LinkInfo& link = data.info[i];
  Mat6* const inertia = aligned(data.articulated_inertia.data());
  const detail::Mat6Entries IA(inertia[i]);
  const typename detail::Subspace<N>::type S = detail::Subspace<N>::of(data, i);
  double* const U = data.U[i].data();
  double* const D_inv = data.D_inv[i].data();
  const double* const armature = model.armature.data() + link.v_index;
  multi_dof_law::joint_inertia<N>(IA, S, [&](int a) { return armature[a]; }, Sqrt{}, U, D_inv);
  double* const u = data.u.data() + link.v_index;
  const double* const pA = data.articulated_bias[i].data();
  if (kBias) multi_dof_law::joint_force<N>(tau->data() + link.v_index, S, pA, u);
  if (link.parent < 0) return;
  double UD[6 * N], Ia[36];
  detail::Mat6Accumulated parent(inertia[link.parent]);
  multi_dof_law::project_inertia<N>(IA, U, D_inv, parent, UD, Ia);
  if (kBias)
    multi_dof_law::project_bias<N>(Ia, UD, pA, u, data.bias_acceleration0[i].data(),
                                   data.articulated_bias[link.parent].data());
}

}  // namespace

void articulated_inertias(const Model& model, Data& data) {
  const int n = model.num_links();
  data.frame_origin = data.world_position[0];
  for (int i = 0; i < n; ++i) {
    const Mat3& R = data.world_rotation[i];
    const Vec3& p = data.frame_position[i];
    const BodyInertia b = body_inertia(data.constants[i], data.info[i].inertia_diagonal, R, p);
    write_inertia(b, data.articulated_inertia[i]);
    subspace_in_frame0(data, i, R, p);
  }
  Mat6* const inertia = aligned(data.articulated_inertia.data());  // as in articulated_bodies
  Data::OneDof* const one_dof = aligned(data.one_dof.data());
  for (int i = n - 1; i >= 0; --i) {
    const Data::LinkInfo& link = data.info[i];
    const Mat6& IA = inertia[i];
    if (link.nv == 1) {  // docs/math/unit_response.md, eq. AP1 and AP3
      Data::OneDof& J = one_dof[i];
      const detail::Mat6Entries IA_i(IA);
      J.D_inv = articulated_law::joint_inertia(IA_i, J.S.data(), model.armature[link.v_index],
                                               J.U.data());
      if (link.parent < 0) continue;
      detail::Mat6Accumulated parent(inertia[link.parent]);
      articulated_law::project_inertia(IA_i, J.U.data(), J.D_inv, parent);
      continue;
    }
    if (link.nv == 3) multi_dof_pass<3, false>(model, data, i, nullptr);
    else if (link.nv == 6) multi_dof_pass<6, false>(model, data, i, nullptr);
    else if (link.parent >= 0) inertia[link.parent] += IA;  // a fixed joint
  }
}

void body_motions(const Model& model, Data& data, const VecX& v) {
  const int n = model.num_links();
  data.frame_origin = data.world_position[0];
  // Pass 1, in two loops (one would keep more values live than there are registers). First S_i
  // and I_i in frame 0, link by link, at the kinematics' frame 0 positions (as the lanes').
  for (int i = 0; i < n; ++i) {
    const Mat3& R = data.world_rotation[i];
    const Vec3& p = data.frame_position[i];
    write_inertia(body_inertia(data.constants[i], data.info[i].inertia_diagonal, R, p),
                  data.articulated_inertia[i]);
    if (data.info[i].nv == 1) one_dof_subspace(data, i, R, p, data.one_dof[i].S);
    else subspace_in_frame0(data, i, R, p);
  }
  // Then velocities v_i = v_parent + S qd, velocity-product accelerations c_i = v_i x S qd and bias
  // forces v_i x* I_i v_i, root to leaves (eq. P1-3 to P1-5), as the lanes form them.
  for (int i = 0; i < n; ++i) {
    const Data::LinkInfo& link = data.info[i];
    double J[6] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0};  // S qd
    if (link.nv == 1) {
      const double qd = v[link.v_index];
      for (int r = 0; r < 6; ++r) J[r] = qd * data.one_dof[i].S[r];
    } else if (link.nv == 3) {  // multi_dof_law, eq. AP14, as the lanes
      multi_dof_law::joint_motion(detail::Subspace<3>::of(data, i), v.data() + link.v_index, J);
    } else if (link.nv == 6) {
      multi_dof_law::joint_motion(detail::Subspace<6>::of(data, i), v.data() + link.v_index, J);
    }
    double vi[6], c[6], pA[6];
    link_motion_law::velocity(link.parent >= 0 ? data.velocity0[link.parent].data() : nullptr, J,
                              vi);
    link_motion_law::velocity_product(vi, J, c);
    // I_i is still the body's inertia here, laid out by write_inertia: A, m c x, m.
    const Mat6& I = data.articulated_inertia[i];
    const double A[6] = {I(0, 0), I(1, 1), I(2, 2), I(0, 1), I(0, 2), I(1, 2)};
    const double mc[3] = {I(2, 4), -I(2, 3), I(1, 3)};
    link_motion_law::bias_force(vi, A, mc, I(3, 3), pA);
    for (int r = 0; r < 6; ++r) data.velocity0[i][r] = vi[r];
    for (int r = 0; r < 6; ++r) data.bias_acceleration0[i][r] = c[r];
    Vec6& bias = data.articulated_bias[i];
    for (int r = 0; r < 6; ++r) bias[r] = pA[r];
  }
}

void articulate(const Model& model, Data& data, const VecX& tau,
                const std::vector<Vec6>* external_force) {
  const int n = model.num_links();
  if (external_force)  // taken off p_i before a child adds to it, as pass 1 did
    for (int i = 0; i < n; ++i)
      data.articulated_bias[i] -= (*external_force)[static_cast<size_t>(i)];
  // Pass 2: articulated inertias and bias forces, leaves to root. The arrays' bases said aligned,
  // so that every link's and parent's entries are (aligned()).
  Mat6* const inertia = aligned(data.articulated_inertia.data());
  Vec6* const bias = aligned(data.articulated_bias.data());
  const Vec6* const c_all = aligned(data.bias_acceleration0.data());
  Data::OneDof* const one_dof = aligned(data.one_dof.data());
  for (int i = n - 1; i >= 0; --i) {
    const Data::LinkInfo& link = data.info[i];
    const Mat6& IA = inertia[i];
    const Vec6& pA = bias[i];
    if (link.nv == 1) {  // docs/math/unit_response.md, eq. AP1-AP4
      Data::OneDof& J = one_dof[i];
      const detail::Mat6Entries IA_i(IA);
      const double D_inv = articulated_law::joint_inertia(IA_i, J.S.data(),
                                                          model.armature[link.v_index], J.U.data());
      J.D_inv = D_inv;
      const double u = articulated_law::joint_force(tau[link.v_index], J.S.data(), pA.data());
      data.u[link.v_index] = u;
      if (link.parent < 0) continue;
      articulated_law::project_bias(IA_i, pA.data(), c_all[i].data(), J.U.data(), D_inv, u,
                                    bias[link.parent].data());
      detail::Mat6Accumulated parent(inertia[link.parent]);
      articulated_law::project_inertia(IA_i, J.U.data(), D_inv, parent);
      continue;
    }
    if (link.nv == 3) {  // docs/math/unit_response.md, eq. AP7-AP11
      multi_dof_pass<3, true>(model, data, i, &tau);
      continue;
    }
    if (link.nv == 6) {
      multi_dof_pass<6, true>(model, data, i, &tau);
      continue;
    }
    if (link.parent < 0) continue;  // a fixed joint: I^A and p^A + I^A c to the parent
    Vec6 pa = pA;
    pa.noalias() += IA * c_all[i];
    inertia[link.parent] += IA;
    bias[link.parent] += pa;
  }
}

void articulated_bodies(const Model& model, Data& data, const VecX& v, const VecX& tau,
                        const std::vector<Vec6>* external_force) {
  body_motions(model, data, v);
  articulate(model, data, tau, external_force);
}

// Pass 3: accelerations, root to leaves; gravity as an upward acceleration of the world.
const VecX& joint_accelerations(const Model& model, Data& data) {
  const Vec6 a_world = detail::world_acceleration(model);
  for (int i = 0; i < model.num_links(); ++i) detail::link_acceleration(data, i, a_world);
  return data.qdd;
}

const VecX& aba_from_kinematics(const Model& model, Data& data, const VecX& v, const VecX& tau,
                                const std::vector<Vec6>* external_force) {
  articulated_bodies(model, data, v, tau, external_force);
  return joint_accelerations(model, data);
}

const VecX& aba(const Model& model, Data& data, const VecX& q, const VecX& v, const VecX& tau) {
  forward_kinematics(model, data, q, v);
  return aba_from_kinematics(model, data, v, tau);
}

}  // namespace featherdrive
