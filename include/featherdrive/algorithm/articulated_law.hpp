// ABA passes 2 and 3 at a one-dof (revolute or prismatic) joint, written once over the number type
// T and over how a symmetric 6 x 6 matrix is stored (docs/math/unit_response.md, eq. AP1-AP6):
// double and Eigen's Mat6 for Simulation (algorithm/aba.cpp, algorithm/joint_acceleration.hpp),
// one vector of a SIMD pack and the packed 21 entries in the lanes (sim/simd_lane_step.hpp's
// articulated_pass; pass 3 on whole packs in link_acceleration). Vectors are T[6] arrays
// [angular; linear] in frame 0. A matrix is read through an adapter m(a, b) (entry a, b) and
// accumulated through one with accumulate(f), which adds f(a, b) to every entry it stores, in the
// order and grouping its storage is fastest at. Sums run left to right, the lanes' order. No
// include, so that the lanes' units compiled for AVX2 and AVX-512 take in no inline function of
// the rest of the library.
#pragma once

namespace featherdrive::articulated_law {

/// a^T b summed left to right.
template <class T>
T dot6(const T* a, const T* b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3] + a[4] * b[4] + a[5] * b[5];
}

/// y = M x, each row summed left to right. Read whole before y is stored, so that no store may
/// alias a later read.
template <class T, class M>
[[gnu::always_inline]] inline void times(const M& m, const T* x, T* y) {
  T out[6];
  for (int r = 0; r < 6; ++r) {
    T sum = m(r, 0) * x[0];
    for (int k = 1; k < 6; ++k) sum = sum + m(r, k) * x[k];
    out[r] = sum;
  }
  for (int r = 0; r < 6; ++r) y[r] = out[r];
}

/// AP1: U = I^A S; returns D^-1 = 1 / (S^T U + armature).
template <class T, class M>
[[gnu::always_inline]] inline T joint_inertia(const M& IA, const T* S, const T& armature, T* U) {
  T out[6];
  times(IA, S, out);
  for (int r = 0; r < 6; ++r) U[r] = out[r];
  return T(1.0) / (dot6(S, out) + armature);
}

/// AP2: u = tau - S^T p^A.
template <class T>
T joint_force(const T& tau, const T* S, const T* pA) {
  return tau - dot6(S, pA);
}

/// AP3: the parent's I^A += I^A - U D^-1 U^T, entry (a, b) as I^A_ab - (D^-1 U_b) U_a. U and
/// D^-1 are copied first: the parent's stores may not then be taken to change them.
template <class T, class M, class Parent>
[[gnu::always_inline]] inline void project_inertia(const M& IA, const T* U, T D_inv,
                                                   Parent& parent) {
  T u[6];
  for (int r = 0; r < 6; ++r) u[r] = U[r];
  parent.accumulate([&](int a, int b) { return IA(a, b) - (D_inv * u[b]) * u[a]; });
}

/// AP4: the parent's p^A += p^A + I^A c + U D^-1 (u - U^T c), c the link's velocity-product
/// acceleration.
template <class T, class M>
[[gnu::always_inline]] inline void project_bias(const M& IA, const T* pA, const T* c, const T* U,
                                                const T& D_inv, const T& u, T* pA_parent) {
  T IAc[6];
  times(IA, c, IAc);
  const T beta = D_inv * (u - dot6(U, c));
  T out[6];
  for (int r = 0; r < 6; ++r) out[r] = pA_parent[r] + ((pA[r] + IAc[r]) + beta * U[r]);
  for (int r = 0; r < 6; ++r) pA_parent[r] = out[r];
}

/// AP5 (pass 3): qdd = D^-1 (u - U^T a), a the parent's acceleration plus c.
template <class T>
[[gnu::always_inline]] inline T joint_acceleration(const T* U, const T& D_inv, const T& u,
                                                   const T* a) {
  return D_inv * (u - dot6(U, a));
}

/// AP6: a += qdd S, entry by entry.
template <class T>
[[gnu::always_inline]] inline void add_joint_motion(const T& qdd, const T* S, T* a) {
  for (int r = 0; r < 6; ++r) a[r] = a[r] + qdd * S[r];
}

}  // namespace featherdrive::articulated_law
