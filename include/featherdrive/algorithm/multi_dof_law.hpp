// ABA passes 2 and 3 at a joint of N dofs (3: spherical, 6: floating root), written once over the
// number type T (docs/math/unit_response.md, eq. AP7-AP14): double for Simulation
// (algorithm/aba.cpp, algorithm/joint_acceleration.hpp), whole SIMD packs in the lanes
// (sim/simd_lane_step.hpp's root_articulated, ball_articulated, root_acceleration,
// ball_acceleration). Vectors are T[6] arrays [angular; linear] in frame 0; U and U D^-1 are
// 6 x N column-major (column c at 6 c), D^-1 N x N (symmetric, entry (a, b) at N a + b). The
// symmetric I^A is read and its parent's accumulated through articulated_law's adapters
// (m(a, b), accumulate(f)); S through one of the two below. Every sum runs left to right, over
// the entries S does not hold zero. Every loop is unrolled in full (#pragma GCC unroll), so that
// the bounds and S's index arithmetic fold to constants: left to clang, the nested loops stay
// loops (a floating root's U and D took 4.6 times the instructions). No include, as
// articulated_law.
#pragma once

namespace featherdrive::multi_dof_law {

/// S as a dense 6 x N column-major array (Simulation's Mat6N, the lanes' ball_S).
template <class T, int N>
struct DenseSubspace {
  const T* s;
  T operator()(int r, int c) const { return s[6 * c + r]; }
  static int first_row(int) { return 0; }  // column c's entries that may be non-zero: rows
  static int end_row(int) { return 6; }    // [first_row(c), end_row(c))
  static int first_col(int) { return 0; }  // row r's: columns [first_col(r), end_col(r))
  static int end_col(int) { return N; }
};

/// A floating root's S = diag(R, R) in frame 0 (its origin is frame 0's), read from R (3 x 3,
/// row-major: the lanes', or column-major: Eigen's Mat3): entry (r, c) is R(r mod 3, c mod 3)
/// where r and c are in the same half, 0 elsewhere.
template <class T, bool kColumnMajor = false>
struct RotationPair {
  const T* R;
  T operator()(int r, int c) const {
    return kColumnMajor ? R[3 * (c % 3) + r % 3] : R[3 * (r % 3) + c % 3];
  }
  static int first_row(int c) { return c < 3 ? 0 : 3; }
  static int end_row(int c) { return c < 3 ? 3 : 6; }
  static int first_col(int r) { return r < 3 ? 0 : 3; }
  static int end_col(int r) { return r < 3 ? 3 : 6; }
  /// As response_law's sums skip zeros.
  static constexpr bool nonzero(int r, int c) { return (r < 3) == (c < 3); }
};

/// (S^T x)_c, over column c's entries.
template <class T, class S>
[[gnu::always_inline]] inline T column_dot(const S& s, int c, const T* x) {
  const int k0 = s.first_row(c), k1 = s.end_row(c);
  T sum = s(k0, c) * x[k0];
  #pragma GCC unroll 6
  for (int k = 1; k < 6; ++k)  // constant bounds: GCC unrolls no other
    if (k > k0 && k < k1) sum = sum + s(k, c) * x[k];
  return sum;
}

/// AP9: the inverse of a symmetric positive definite N x N matrix D from its Cholesky factor L,
/// D^-1 = L^-T L^-1, entry (a, b) summed over k >= max(a, b) (L^-1 is lower triangular) and
/// written to both halves. sqrt: a correctly rounded square root of T.
template <int N, class T, class Sqrt>
[[gnu::always_inline]] inline void spd_inverse(const T* D, T* out, const Sqrt& sqrt) {
  T L[N * N], Li[N * N];
  #pragma GCC unroll 6
  for (int j = 0; j < N; ++j) {
    T d = D[N * j + j];
    #pragma GCC unroll 6
    for (int k = 0; k < j; ++k) d = d - L[N * j + k] * L[N * j + k];
    L[N * j + j] = sqrt(d);
    #pragma GCC unroll 6
    for (int i = j + 1; i < N; ++i) {
      T x = D[N * i + j];
      #pragma GCC unroll 6
      for (int k = 0; k < j; ++k) x = x - L[N * i + k] * L[N * j + k];
      L[N * i + j] = x / L[N * j + j];
    }
  }
  #pragma GCC unroll 6
  for (int j = 0; j < N; ++j) {  // L^-1, column by column (forward substitution)
    Li[N * j + j] = T(1.0) / L[N * j + j];
    #pragma GCC unroll 6
    for (int i = j + 1; i < N; ++i) {
      T x = T(0.0) - L[N * i + j] * Li[N * j + j];
      #pragma GCC unroll 6
      for (int k = j + 1; k < i; ++k) x = x - L[N * i + k] * Li[N * k + j];
      Li[N * i + j] = x / L[N * i + i];
    }
  }
  #pragma GCC unroll 6
  for (int a = 0; a < N; ++a)
    #pragma GCC unroll 6
    for (int b = a; b < N; ++b) {
      T sum = Li[N * b + a] * Li[N * b + b];
      #pragma GCC unroll 6
      for (int k = b + 1; k < N; ++k) sum = sum + Li[N * k + a] * Li[N * k + b];
      out[N * a + b] = sum;
      out[N * b + a] = sum;
    }
}

/// AP7-AP9: U = I^A S, D = S^T U + diag(armature), D^-1. armature(a): dof a's.
template <int N, class T, class M, class S, class Armature, class Sqrt>
[[gnu::always_inline]] inline void joint_inertia(const M& IA, const S& s, const Armature& armature,
                                                 const Sqrt& sqrt, T* U, T* D_inv) {
  #pragma GCC unroll 6
  for (int c = 0; c < N; ++c)
    #pragma GCC unroll 6
    for (int r = 0; r < 6; ++r) {
      const int k0 = s.first_row(c), k1 = s.end_row(c);
      T x = IA(r, k0) * s(k0, c);
      #pragma GCC unroll 6
      for (int k = 1; k < 6; ++k)
        if (k > k0 && k < k1) x = x + IA(r, k) * s(k, c);
      U[6 * c + r] = x;
    }
  T D[N * N];
  #pragma GCC unroll 6
  for (int a = 0; a < N; ++a)
    #pragma GCC unroll 6
    for (int b = 0; b < N; ++b) D[N * a + b] = column_dot(s, a, U + 6 * b);
  #pragma GCC unroll 6
  for (int a = 0; a < N; ++a) D[N * a + a] = D[N * a + a] + armature(a);
  spd_inverse<N>(D, D_inv, sqrt);
}

/// AP8: u = tau - S^T p^A.
template <int N, class T, class S>
[[gnu::always_inline]] inline void joint_force(const T* tau, const S& s, const T* pA, T* u) {
  #pragma GCC unroll 6
  for (int c = 0; c < N; ++c) u[c] = tau[c] - column_dot(s, c, pA);
}

/// AP10: I^a = I^A - (U D^-1) U^T, entry (a, b) for b >= a and mirrored, into Ia (36, column-major)
/// and added to the parent's; U D^-1 into UD for AP11.
template <int N, class T, class M, class Parent>
[[gnu::always_inline]] inline void project_inertia(const M& IA, const T* U, const T* D_inv,
                                                   Parent& parent, T* UD, T* Ia) {
  #pragma GCC unroll 6
  for (int b = 0; b < N; ++b)
    #pragma GCC unroll 6
    for (int r = 0; r < 6; ++r) {
      T x = U[r] * D_inv[b];
      #pragma GCC unroll 6
      for (int k = 1; k < N; ++k) x = x + U[6 * k + r] * D_inv[N * k + b];
      UD[6 * b + r] = x;
    }
  #pragma GCC unroll 6
  for (int a = 0; a < 6; ++a)
    #pragma GCC unroll 6
    for (int b = a; b < 6; ++b) {
      T x = UD[a] * U[b];
      #pragma GCC unroll 6
      for (int k = 1; k < N; ++k) x = x + UD[6 * k + a] * U[6 * k + b];
      Ia[6 * b + a] = IA(a, b) - x;
      Ia[6 * a + b] = Ia[6 * b + a];
    }
  parent.accumulate([&](int a, int b) { return Ia[6 * b + a]; });
}

/// AP11: the parent's p^A += (p^A + (U D^-1) u) + I^a c, c the link's velocity-product
/// acceleration.
template <int N, class T>
[[gnu::always_inline]] inline void project_bias(const T* Ia, const T* UD, const T* pA, const T* u,
                                                const T* c, T* pA_parent) {
  T out[6];
  #pragma GCC unroll 6
  for (int r = 0; r < 6; ++r) {
    T x = UD[r] * u[0];
    #pragma GCC unroll 6
    for (int k = 1; k < N; ++k) x = x + UD[6 * k + r] * u[k];
    T Iac = Ia[r] * c[0];
    #pragma GCC unroll 6
    for (int k = 1; k < 6; ++k) Iac = Iac + Ia[6 * k + r] * c[k];
    out[r] = pA_parent[r] + ((pA[r] + x) + Iac);
  }
  #pragma GCC unroll 6
  for (int r = 0; r < 6; ++r) pA_parent[r] = out[r];
}

/// AP12 (pass 3): qdd = D^-1 (u - U^T a), a the parent's acceleration plus c.
template <int N, class T>
[[gnu::always_inline]] inline void joint_acceleration(const T* U, const T* D_inv, const T* u,
                                                      const T* a, T* qdd) {
  T r[N];
  #pragma GCC unroll 6
  for (int c = 0; c < N; ++c) {
    T Ua = U[6 * c] * a[0];
    #pragma GCC unroll 6
    for (int m = 1; m < 6; ++m) Ua = Ua + U[6 * c + m] * a[m];
    r[c] = u[c] - Ua;
  }
  #pragma GCC unroll 6
  for (int d = 0; d < N; ++d) {
    T sum = D_inv[N * d] * r[0];
    #pragma GCC unroll 6
    for (int c = 1; c < N; ++c) sum = sum + D_inv[N * d + c] * r[c];
    qdd[d] = sum;
  }
}

/// AP14's rows 0 to kRows - 1 of y = S x, each over its entries left to right.
template <int kRows, class T, class S>
[[gnu::always_inline]] inline void joint_motion_rows(const S& s, const T* x, T* y) {
#pragma GCC unroll 6
  for (int r = 0; r < kRows; ++r) {
    const int k0 = s.first_col(r), k1 = s.end_col(r);
    T sum = s(r, k0) * x[k0];
#pragma GCC unroll 6
    for (int k = 1; k < 6; ++k)
      if (k > k0 && k < k1) sum = sum + s(r, k) * x[k];
    y[r] = sum;
  }
}

/// AP14: y = S x: a joint's S qd in pass 1 (unit_response.md, P1-3) and AP13's S qdd.
template <class T, class S>
[[gnu::always_inline]] inline void joint_motion(const S& s, const T* x, T* y) {
  joint_motion_rows<6>(s, x, y);
}

/// AP14's angular rows alone: w = (S x)_0..2, a joint's turn in compat physx's integration of
/// spherical joints (eq. S-7).
template <class T, class S>
[[gnu::always_inline]] inline void joint_turn(const S& s, const T* x, T* w) {
  joint_motion_rows<3>(s, x, w);
}

/// AP13: a += S qdd (AP14's sums).
template <class T, class S>
[[gnu::always_inline]] inline void add_joint_motion(const S& s, const T* qdd, T* a) {
  T sq[6];
  joint_motion(s, qdd, sq);
#pragma GCC unroll 6
  for (int r = 0; r < 6; ++r) a[r] = a[r] + sq[r];
}

}  // namespace featherdrive::multi_dof_law
