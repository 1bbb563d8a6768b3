// A one-dof link's part of a Gauss-Seidel sweep with exact joint velocities
// (docs/math/implicit_drives.md, "Propagating impulses", eq. SW0-SW6 and GS1-GS3), over the
// number type: Simulation's gauss_seidel_sweep (double) and the lanes' sweep
// (sim/simd_lane_step.hpp: a pack, or one vector of it) form it with the same operations. Each
// engine keeps its own walk over the links (which link is entered, left or finished when).
// Spatial vectors are anything with v[r], r < 6, that reads a T (an Eigen Vec6, a T*, the lanes'
// view of one vector of a pack). No include: the lanes' units compiled for AVX2 and AVX-512 take
// in no inline function of the rest of the library.
#pragma once

namespace featherdrive::sweep_law {

/// a . b summed as (p0 + (p2 + p4)) + (p1 + (p3 + p5)), p_r = a_r b_r (eq. SW0): Eigen's order for
/// a 6-vector with SSE2's two-wide packets. Two Eigen vectors (the scalar step's) go through
/// Eigen's product, which sums so with the library's SSE2 build (tests/solver/sweep_law_test.cpp:
/// bit for bit) and keeps them in packets where the code around it has them so.
template <class T, class X, class Y>
[[gnu::always_inline]] inline T dot6(const X& a, const Y& b) {
  if constexpr (requires { a.dot(b); }) {
    return a.dot(b);
  } else {
    const T p0 = a[0] * b[0], p1 = a[1] * b[1], p2 = a[2] * b[2];
    const T p3 = a[3] * b[3], p4 = a[4] * b[4], p5 = a[5] * b[5];
    return (p0 + (p2 + p4)) + (p1 + (p3 + p5));
  }
}

/// The joint's velocity change from outside its subtree when link i is entered,
/// -D_i^-1 U_i^T dv_p (eq. SW1), dv_p its parent's velocity change of the sweep.
template <class T, class U6, class P6>
[[gnu::always_inline]] inline T base(const T& D_inv, const U6& U, const P6& dvp) {
  return -D_inv * dot6<T>(U, dvp);
}

/// Before link i's rows, the part of its one-dof child c's base that does not wait on i's impulse:
/// -D_c^-1 U_c^T dv_p + base_i b^b_c (eq. GS2), b^b_c = -D_c^-1 U_c^T S_i.
template <class T, class U6, class P6>
[[gnu::always_inline]] inline T ahead(const T& D_inv_child, const U6& U_child, const P6& dvp,
                                      const T& base, const T& base_per_parent_base) {
  return -D_inv_child * dot6<T>(U_child, dvp) + base * base_per_parent_base;
}

/// The child's base once i's impulse is known: ahead + impulse b^lambda_c (eq. GS1).
template <class T>
[[gnu::always_inline]] inline T chained_base(const T& ahead, const T& impulse,
                                             const T& base_per_parent_impulse) {
  return ahead + impulse * base_per_parent_impulse;
}

/// After link i's rows applied `impulse`: the joint's velocity change base + (M^-1)_ii impulse,
/// returned, and the link's dv = (dv_p - (D^-1 impulse) W) + dqd S (eq. SW2), every entry read
/// before any is written.
template <class T, class P6, class W6, class S6, class O6>
[[gnu::always_inline]] inline T after_rows(const T& base, const T& impulse, const T& inverse_mass,
                                           const T& D_inv, const P6& dvp, const W6& W, const S6& S,
                                           O6&& dv) {
  const T dqd = base + inverse_mass * impulse;
  const T h = D_inv * impulse;
  T out[6];
  for (int r = 0; r < 6; ++r) out[r] = (dvp[r] - h * W[r]) + dqd * S[r];
  for (int r = 0; r < 6; ++r) dv[r] = out[r];
  return dqd;
}

/// Leaving link k: beta = D^-1 (impulse - S^T pA) (eq. SW3), with S^T pA given.
template <class T>
[[gnu::always_inline]] inline T leave_beta(const T& D_inv, const T& impulse, const T& S_pA) {
  return D_inv * (impulse - S_pA);
}

/// The joint's last velocity change when its subtree is done: its entry change minus G^T pA
/// (eq. SW4), added to qd.
template <class T, class G6, class A6>
[[gnu::always_inline]] inline T finished_velocity(const T& qd, const T& entry, const G6& G,
                                                  const A6& pA) {
  return qd + (entry - dot6<T>(G, pA));
}

/// Along a run of only children, the one-dof parent's S_p^T pA_p after k hands it its impulse,
/// from k's pA before the hand-over: S_p^T pA + beta U_k^T S_p (eq. GS3).
template <class T, class S6, class A6>
[[gnu::always_inline]] inline T parent_S_pA(const S6& S_parent, const A6& pA, const T& beta,
                                            const T& parent_S) {
  return dot6<T>(S_parent, pA) + beta * parent_S;
}

/// A later subtree's part of a one-dof joint's velocity change, -D^-1 U^T E_hat (eq. SW5).
template <class T, class U6, class E6>
[[gnu::always_inline]] inline T later(const T& D_inv, const U6& U, const E6& E_hat) {
  return -D_inv * dot6<T>(U, E_hat);
}

}  // namespace featherdrive::sweep_law
