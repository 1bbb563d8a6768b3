// The whole-articulation response, written once over the number type T and over how a symmetric
// 6 x 6 matrix is stored (docs/math/unit_response.md). At a one-dof (revolute or prismatic) joint
// (eq. R1-R5): double and Eigen's Mat6 for Simulation (algorithm/inverse_mass_diagonal.cpp's
// link_response), one vector of a SIMD pack and the packed 21 entries in the lanes
// (sim/simd_lane_step.hpp's link_response). At one of N dofs (spherical, floating; R6-R10,
// response_n and world_response): Simulation's multi_dof_response, whole packs in the lanes'
// ball_response and root_response. Vectors, matrix adapters and sums as in articulated_law.hpp;
// Lambda_i is written through an adapter with assign(f), which sets every entry (a, b) it stores
// to f(a, b).
#pragma once

#include "featherdrive/algorithm/articulated_law.hpp"

namespace featherdrive::response_law {

/// R1-R4 at link i with the parent's response T (zero for the world): W = T U, returns
/// r = (M^-1)_ii = D^-1 + D^-1 D^-1 U^T W, G = r S - D^-1 W and Lambda_i, entry (a, b) as
/// (T_ab + G_b S_a) - (S_b D^-1) W_a. W, G and Lambda's storage must not overlap the parent's
/// matrix: W and G are stored before Lambda reads it.
/// S is anything with S[e] (the lanes read it where it is stored: kept in registers, it spilled).
template <class T, class M, class SV, class Out>
[[gnu::always_inline]] inline T response(const M& parent, const SV& S, const T* U, const T& D_inv,
                                         T* W, T* G, Out& Lambda) {
  T w[6];
  articulated_law::times(parent, U, w);
  const T r = D_inv + D_inv * D_inv * articulated_law::dot6(U, w);
  for (int e = 0; e < 6; ++e) W[e] = w[e];
  T g[6], sd[6];  // Lambda reads w and g, not W and G: its stores cannot change them
  for (int e = 0; e < 6; ++e) g[e] = r * S[e] - D_inv * w[e];
  for (int e = 0; e < 6; ++e) G[e] = g[e];
  for (int e = 0; e < 6; ++e) sd[e] = S[e] * D_inv;
  Lambda.assign([&](int a, int b) { return (parent(a, b) + g[b] * S[a]) - sd[b] * w[a]; });
  return r;
}

/// R5: the constants the sweep uses between link i and a one-dof parent p (implicit_drives.md,
/// GS1-GS3).
template <class T>
struct Chain {
  T parent_W;                 ///< U_i^T W_p
  T parent_S;                 ///< U_i^T S_p
  T base_per_parent_base;     ///< -D_i^-1 U_i^T S_p
  T base_per_parent_impulse;  ///< D_p^-1 (D_i^-1 U_i^T W_p) + r_p base_per_parent_base
};
template <class T>
[[gnu::always_inline]] inline Chain<T> chain(const T* U, const T& D_inv, const T* S_p, const T* W_p,
                                             const T& D_inv_p, const T& r_p) {
  Chain<T> c;
  c.parent_W = articulated_law::dot6(U, W_p);
  c.parent_S = articulated_law::dot6(U, S_p);
  c.base_per_parent_base = -D_inv * c.parent_S;
  c.base_per_parent_impulse = D_inv_p * (D_inv * c.parent_W) + r_p * c.base_per_parent_base;
  return c;
}

/// A 6 x N matrix stored column by column (column c at m + 6 c), every entry taken as nonzero:
/// a spherical joint's S, read by response_n and world_response.
template <class T>
struct Columns {
  const T* m;
  [[gnu::always_inline]] const T& operator()(int r, int c) const { return m[r + 6 * c]; }
  static constexpr bool nonzero(int, int) { return true; }
};

/// sum_k x(k) y(k) for k = 0 .. N-1 with S(s_row, k) nonzero, left to right; x(k) * y(k) with
/// S(s_row, k) zero is zero and adding it would change no bit but the sign of a zero.
template <int N, class SM, class F>
[[gnu::always_inline]] inline auto sum_over(int s_row, const F& term) {
  int k = 0;
  while (!SM::nonzero(s_row, k)) ++k;
  auto sum = term(k);
  #pragma GCC unroll 6
  for (++k; k < N; ++k)
    if (SM::nonzero(s_row, k)) sum = sum + term(k);
  return sum;
}

/// R10 at a joint of N dofs on the world (T = 0; a floating root, or a spherical joint at the
/// root): Lambda = S D^-1 S^T, entry (a, b) as sum_k (S D^-1)_ak S_bk; W = 0 and (M^-1)_ii = D^-1
/// are the caller's. S and D^-1 read as s(r, c), d(a, b); S's adapter says which entries may be
/// nonzero (nonzero(r, c), constant), and every sum over S's columns skips the others.
template <int N, class T, class SM, class DM, class Out>
[[gnu::always_inline]] inline void world_response(const SM& S, const DM& D_inv, Out& Lambda) {
  T SD[6 * N];  // S D^-1, column b at SD + 6 b
  // Unrolled, so that S's zeros are known where they are skipped (RotationPair's for a floating
  // root; rolled, each entry's index and zero test are worked out at run time).
  #pragma GCC unroll 6
  for (int b = 0; b < N; ++b)
    #pragma GCC unroll 6
    for (int r = 0; r < 6; ++r)
      SD[6 * b + r] = sum_over<N, SM>(r, [&](int c) { return S(r, c) * D_inv(c, b); });
  Lambda.assign([&](int a, int b) {
    return sum_over<N, SM>(b, [&](int k) { return SD[6 * k + a] * S(b, k); });
  });
}

/// R6-R9 at a joint of N dofs with the parent's response T: W = T U, K = U^T W,
/// (M^-1)_ii = D^-1 + (D^-1 K) D^-1 and Lambda_i, entry (a, b) as
/// (((T_ab - (S D^-1 W^T)_ab) - (W (S D^-1)^T)_ab) + ((S D^-1 K) (S D^-1)^T)_ab) + (S D^-1 S^T)_ab.
/// U and W are 6 x N column by column (column c at U + 6 c), M^-1 N x N row by row; S and D^-1 as
/// in world_response. W and Minv must not overlap the parent's matrix.
template <int N, class T, class M, class SM, class DM, class Out>
[[gnu::always_inline]] inline void response_n(const M& parent, const SM& S, const T* U,
                                              const DM& D_inv, T* W, T* Minv, Out& Lambda) {
  T w[6 * N];
  for (int b = 0; b < N; ++b) articulated_law::times(parent, U + 6 * b, w + 6 * b);
  T K[N * N];  // U^T W
  for (int a = 0; a < N; ++a)
    for (int b = 0; b < N; ++b) K[N * a + b] = articulated_law::dot6(U + 6 * a, w + 6 * b);
  T SD[6 * N], SDK[6 * N];  // S D^-1 and (S D^-1) K, column b at + 6 b
  for (int b = 0; b < N; ++b)
    for (int r = 0; r < 6; ++r)
      SD[6 * b + r] = sum_over<N, SM>(r, [&](int c) { return S(r, c) * D_inv(c, b); });
  for (int b = 0; b < N; ++b)
    for (int r = 0; r < 6; ++r) {
      T sum = SD[r] * K[b];
      for (int c = 1; c < N; ++c) sum = sum + SD[6 * c + r] * K[N * c + b];
      SDK[6 * b + r] = sum;
    }
  for (int e = 0; e < 6 * N; ++e) W[e] = w[e];
  const auto cross = [](const T* X, int a, const T* Y, int b) {  // sum_k X_ak Y_bk, 6 x N each
    T sum = X[a] * Y[b];
    for (int k = 1; k < N; ++k) sum = sum + X[6 * k + a] * Y[6 * k + b];
    return sum;
  };
  Lambda.assign([&](int a, int b) {
    const T own = sum_over<N, SM>(b, [&](int k) { return SD[6 * k + a] * S(b, k); });
    return (((parent(a, b) - cross(SD, a, w, b)) - cross(w, a, SD, b)) + cross(SDK, a, SD, b)) +
           own;
  });
  T DK[N * N];  // D^-1 K
  for (int a = 0; a < N; ++a)
    for (int b = 0; b < N; ++b) {
      T sum = D_inv(a, 0) * K[b];
      for (int c = 1; c < N; ++c) sum = sum + D_inv(a, c) * K[N * c + b];
      DK[N * a + b] = sum;
    }
  for (int a = 0; a < N; ++a)
    for (int b = 0; b < N; ++b) {
      T sum = DK[N * a] * D_inv(0, b);
      for (int c = 1; c < N; ++c) sum = sum + DK[N * a + c] * D_inv(c, b);
      Minv[N * a + b] = D_inv(a, b) + sum;
    }
}

}  // namespace featherdrive::response_law
