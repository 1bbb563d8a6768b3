// The whole-articulation response at a one-dof (revolute or prismatic) joint, written once over
// the number type T and over how a symmetric 6 x 6 matrix is stored (docs/math/unit_response.md,
// eq. R1-R5): double and Eigen's Mat6 for Simulation (algorithm/inverse_mass_diagonal.cpp's
// link_response), one vector of a SIMD pack and the packed 21 entries in the lanes
// (sim/simd_lane_step.hpp's link_response). Vectors, matrix adapters and sums as
// in articulated_law.hpp; Lambda_i is written through an adapter with assign(f), which sets every
// entry (a, b) it stores to f(a, b).
#pragma once

#include "featherdrive/algorithm/articulated_law.hpp"

namespace featherdrive::response_law {

/// R1-R4 at link i with the parent's response T (zero for the world): W = T U, returns
/// r = (M^-1)_ii = D^-1 + D^-1 D^-1 U^T W, G = r S - D^-1 W and Lambda_i, entry (a, b) as
/// (T_ab + G_b S_a) - (S_b D^-1) W_a. W, G and Lambda's storage must not overlap the parent's
/// matrix: W and G are stored before Lambda reads it.
template <class T, class M, class Out>
[[gnu::always_inline]] inline T response(const M& parent, const T* S, const T* U, const T& D_inv,
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

}  // namespace featherdrive::response_law
