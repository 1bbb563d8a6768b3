// A link's part of a Gauss-Seidel sweep with exact joint velocities
// (docs/math/implicit_drives.md, "Propagating impulses", eq. SW0-SW14 and GS1-GS3), over the
// number type: Simulation's gauss_seidel_sweep (double) and the lanes' sweep
// (sim/simd_lane_step.hpp: a pack, or one vector of it) form it with the same operations. The
// walk over the links (which link is entered, left or finished when) is sweep_walk.hpp's.
// A one-dof link's spatial vectors are anything with v[r], r < 6, that reads a T (an Eigen Vec6,
// a T*, the lanes' view of one vector of a pack). A joint of N dofs (3: spherical, 6: floating
// root; SW6-SW11) takes T[6] arrays, and multi_dof_law's conventions: U, W 6 x N column-major,
// D^-1 and (M^-1)_ii N x N (entry (a, b) at N a + b), S through multi_dof_law's adapters; every
// sum of those runs left to right. Only multi_dof_law is included, itself include-free: the
// lanes' units compiled for AVX2 and AVX-512 take in no inline function of the rest of the
// library.
#pragma once

#include "featherdrive/algorithm/multi_dof_law.hpp"

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

// ---- The hand-over to the parent (eq. SW12-SW14) ----

/// Eigen's vectors (the scalar step's): the hand-over's copies, sums and product go through their
/// own expressions, which keep them in packets; the others entry by entry.
template <class X>
concept Dense = requires(X& x) { x.dot(x); };

/// A one-dof joint's p^a = pA + beta U (eq. SW3), each entry formed where it is read.
template <class T, class A6, class U6>
struct Handed {
  A6 pA;
  T beta;
  U6 U;
  [[gnu::always_inline]] T operator[](int r) const { return pA[r] + beta * U[r]; }
};
template <class T, class A6, class U6>
[[gnu::always_inline]] inline auto handed(const A6& pA, const T& beta, const U6& U) {
  if constexpr (Dense<const A6>) return pA + beta * U;
  else return Handed<T, A6, U6>{pA, beta, U};
}

/// Link k hands its subtree's impulse pa to its parent: pA_p = pa when k is the parent's first
/// child (pA_p needs no clearing between sweeps), else pA_p + pa (eq. SW12).
template <class T, class Pa6, class P6>
[[gnu::always_inline]] inline void hand_over(const Pa6& pa, bool first, P6&& pA_parent) {
  if constexpr (Dense<P6>) {
    if (first) pA_parent = pa;
    else pA_parent += pa;
  } else {
    for (int r = 0; r < 6; ++r) pA_parent[r] = first ? pa[r] : pA_parent[r] + pa[r];
  }
}

/// Where a sibling follows k, pA_p as k left it: its later siblings' p^a at k's finish are pA_p
/// less this (eq. SW14, for SW5's E_hat).
template <class T, class P6, class A6>
[[gnu::always_inline]] inline void record_after(const P6& pA_parent, A6&& after) {
  if constexpr (Dense<A6>) after = pA_parent;
  else
    for (int r = 0; r < 6; ++r) after[r] = pA_parent[r];
}

/// The parent's velocity change, read again by the sibling entered next, less its whole-
/// articulation response to the impulse pa handed it: dv - Lambda pa (eq. SW13), Lambda anything
/// with Lambda(r, c), each row's sum left to right.
template <class T, class L, class Pa6, class D6>
[[gnu::always_inline]] inline void correct_parent(const L& Lambda, const Pa6& pa, D6&& dv) {
  if constexpr (Dense<D6>) {
    dv.noalias() -= Lambda * pa;
  } else {
    T x[6];
    for (int c = 0; c < 6; ++c) x[c] = pa[c];
    for (int r = 0; r < 6; ++r) {
      T sum = Lambda(r, 0) * x[0];
      for (int c = 1; c < 6; ++c) sum = sum + Lambda(r, c) * x[c];
      dv[r] = dv[r] - sum;
    }
  }
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

// ---- A joint of N dofs (eq. SW6-SW11) ----

/// Row a of an N x N matrix m (at N a + b) times x, summed left to right.
template <int N, class T>
[[gnu::always_inline]] inline T row_times(const T* m, int a, const T* x) {
  T sum = m[N * a] * x[0];
  #pragma GCC unroll 6
  for (int b = 1; b < N; ++b) sum = sum + m[N * a + b] * x[b];
  return sum;
}

/// (X^T y)_c for a dense 6 x N X (U, W): column c's six products left to right.
template <int N, class T>
[[gnu::always_inline]] inline T column_dot(const T* X, int c, const T* y) {
  return multi_dof_law::column_dot(multi_dof_law::DenseSubspace<T, N>{X}, c, y);
}

/// Entering: the joint's velocity change from outside its subtree, base = -D^-1 U^T dv_p (eq. SW6).
template <int N, class T>
[[gnu::always_inline]] inline void base_n(const T* D_inv, const T* U, const T* dvp, T* base) {
  T Ud[N];
  #pragma GCC unroll 6
  for (int b = 0; b < N; ++b) Ud[b] = column_dot<N>(U, b, dvp);
  #pragma GCC unroll 6
  for (int a = 0; a < N; ++a) base[a] = -row_times<N>(D_inv, a, Ud);
}

/// The velocity row a of the joint sees: (qd_a + base_a) + ((M^-1)_ii impulse)_a, impulse its
/// joint's impulses so far in the sweep (eq. SW7).
template <int N, class T>
[[gnu::always_inline]] inline T row_velocity(const T& qd, const T& base, const T* inverse_mass,
                                             int a, const T* impulse) {
  return (qd + base) + row_times<N>(inverse_mass, a, impulse);
}

/// After the joint's rows applied `impulse`: the parent side's change now = dv_p - W D^-1 impulse,
/// the joint's entry change D^-1 (impulse - U^T now) and the link's dv = now + S entry (eq. SW8).
/// Every entry of dv_p is read before dv is written.
template <int N, class T, class S>
[[gnu::always_inline]] inline void after_rows_n(const T* impulse, const T* D_inv, const T* W,
                                                const T* U, const S& s, const T* dvp, T* entry,
                                                T* dv) {
  T t[N], Wt[6], now[6], r[N];
  #pragma GCC unroll 6
  for (int a = 0; a < N; ++a) t[a] = row_times<N>(D_inv, a, impulse);
  multi_dof_law::joint_motion(multi_dof_law::DenseSubspace<T, N>{W}, t, Wt);
  #pragma GCC unroll 6
  for (int k = 0; k < 6; ++k) now[k] = dvp[k] - Wt[k];
  #pragma GCC unroll 6
  for (int a = 0; a < N; ++a) r[a] = impulse[a] - column_dot<N>(U, a, now);
  #pragma GCC unroll 6
  for (int a = 0; a < N; ++a) entry[a] = row_times<N>(D_inv, a, r);
  multi_dof_law::add_joint_motion(s, entry, now);
  #pragma GCC unroll 6
  for (int k = 0; k < 6; ++k) dv[k] = now[k];
}

/// Leaving: the impulse the subtree hands its parent, pa = pA + U D^-1 (impulse - S^T pA)
/// (eq. SW9).
template <int N, class T, class S>
[[gnu::always_inline]] inline void hand_over_n(const T* impulse, const S& s, const T* U,
                                               const T* D_inv, const T* pA, T* pa) {
  T t[N], y[N], Uy[6];
  #pragma GCC unroll 6
  for (int a = 0; a < N; ++a) t[a] = impulse[a] - multi_dof_law::column_dot(s, a, pA);
  #pragma GCC unroll 6
  for (int b = 0; b < N; ++b) y[b] = row_times<N>(D_inv, b, t);
  multi_dof_law::joint_motion(multi_dof_law::DenseSubspace<T, N>{U}, y, Uy);
  #pragma GCC unroll 6
  for (int k = 0; k < 6; ++k) pa[k] = pA[k] + Uy[k];
}

/// Finishing: the joint's velocity change from its entry and its subtree's impulses,
/// dqd = (entry - (M^-1)_ii S^T pA) + D^-1 W^T pA (eq. SW10).
template <int N, class T, class S>
[[gnu::always_inline]] inline void finished_n(const T* entry, const S& s, const T* W,
                                              const T* inverse_mass, const T* D_inv, const T* pA,
                                              T* dqd) {
  T Sp[N], Wp[N];
  #pragma GCC unroll 6
  for (int a = 0; a < N; ++a)
    Sp[a] = multi_dof_law::column_dot(s, a, pA), Wp[a] = column_dot<N>(W, a, pA);
  #pragma GCC unroll 6
  for (int a = 0; a < N; ++a)
    dqd[a] = (entry[a] - row_times<N>(inverse_mass, a, Sp)) + row_times<N>(D_inv, a, Wp);
}

/// A later subtree's part: dqd += -D^-1 U^T E_hat and E = E_hat + S (that) (eq. SW5 over N dofs).
template <int N, class T, class S>
[[gnu::always_inline]] inline void later_n(const T* D_inv, const T* U, const S& s, const T* E_hat,
                                           T* dqd, T* E) {
  T later[N];
  base_n<N>(D_inv, U, E_hat, later);
  #pragma GCC unroll 6
  for (int a = 0; a < N; ++a) dqd[a] = dqd[a] + later[a];
  T Sl[6];
  multi_dof_law::joint_motion(s, later, Sl);
  #pragma GCC unroll 6
  for (int k = 0; k < 6; ++k) E[k] = E_hat[k] + Sl[k];
}

/// A joint of the root without rows (a floating root: no entry change, W = 0), finished after
/// the sweep: qd -= D^-1 S^T pA (eq. SW11).
template <int N, class T, class S>
[[gnu::always_inline]] inline void finish_rowless_root(const S& s, const T* D_inv, const T* pA,
                                                       T* qd) {
  T y[N];
  #pragma GCC unroll 6
  for (int c = 0; c < N; ++c) y[c] = multi_dof_law::column_dot(s, c, pA);
  #pragma GCC unroll 6
  for (int d = 0; d < N; ++d) qd[d] = qd[d] - row_times<N>(D_inv, d, y);
}

}  // namespace featherdrive::sweep_law
