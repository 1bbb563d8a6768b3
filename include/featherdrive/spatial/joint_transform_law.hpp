// A revolute joint's rotation, a prismatic joint's offset and their composition into the link's
// pose, written once over the number type (docs/math/joint_transform.md): double for Simulation
// (algorithm/kinematics.cpp), SIMD packs of environments in the lanes (sim/simd_lane_step.hpp's
// link_pose), so that both place a link with the same operations. A matrix is anything with
// m(r, c): Eigen's Mat3, or a row-major T[9] through rows(); a vector anything with v[k]. No
// include, so that the lanes' units compiled for AVX2 and AVX-512 take in
// no inline function of the rest of the library.
#pragma once

namespace featherdrive::joint_transform_law {

/// A row-major 3 x 3 matrix on a T[9], as m(r, c).
template <class T>
struct Rows {
  T* m;
  T& operator()(int r, int c) const { return m[3 * r + c]; }
};
template <class T>
Rows<T> rows(T* m) {
  return {m};
}

/// The two coordinate axes after k in cyclic order: R(e_k, x) has cos x and sin x in rows and
/// columns (k1, k2) and 1 at (k, k) (eq. JT-2).
constexpr int next_axis(int k) { return k == 2 ? 0 : k + 1; }
constexpr int previous_axis(int k) { return k == 0 ? 2 : k - 1; }

/// J = R(a, x) for a unit axis a, from s = sin x, c = cos x (Rodrigues, eq. JT-1):
/// c 1 + s [a]x + (1 - c) a a^T.
template <class T, class M>
void axis_rotation(const T& a0, const T& a1, const T& a2, const T& s, const T& c, M&& J) {
  const T t = T(1.0) - c;
  const T t01 = t * a0 * a1, t02 = t * a0 * a2, t12 = t * a1 * a2;
  const T s0 = s * a0, s1 = s * a1, s2 = s * a2;
  J(0, 0) = t * a0 * a0 + c, J(0, 1) = t01 - s2, J(0, 2) = t02 + s1;
  J(1, 0) = t01 + s2, J(1, 1) = t * a1 * a1 + c, J(1, 2) = t12 - s0;
  J(2, 0) = t02 - s1, J(2, 1) = t12 + s0, J(2, 2) = t * a2 * a2 + c;
}

/// R = P R(e_k, x), from s = sin x, c = cos x: columns k1 and k2 of P mix, column k stays
/// (eq. JT-3). R must not alias P.
template <class T, class M, class N>
void turn_columns(const M& P, int k, const T& s, const T& c, N&& R) {
  const int k1 = next_axis(k), k2 = previous_axis(k);
  for (int r = 0; r < 3; ++r) {
    R(r, k) = P(r, k);
    R(r, k1) = c * P(r, k1) + s * P(r, k2);
    R(r, k2) = c * P(r, k2) - s * P(r, k1);
  }
}

/// E = R(e_k, x)^T E_T, the rotation of X_J X_T: rows k1 and k2 of E_T mix, row k stays
/// (eq. JT-4). E must not alias E_T.
template <class T, class M, class N>
void turn_rows(const M& E_T, int k, const T& s, const T& c, N&& E) {
  const int k1 = next_axis(k), k2 = previous_axis(k);
  for (int col = 0; col < 3; ++col) {
    E(k, col) = E_T(k, col);
    E(k1, col) = c * E_T(k1, col) + s * E_T(k2, col);
    E(k2, col) = c * E_T(k2, col) - s * E_T(k1, col);
  }
}

/// P = R_p E_T^T, the joint frame's axes in the world from the parent's rotation R_p and the
/// tree transform's E_T (eq. JT-5). P must not alias R_p.
template <class M, class N, class O>
void joint_frame(const M& Rp, const N& E_T, O&& P) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      P(r, c) = Rp(r, 0) * E_T(c, 0) + Rp(r, 1) * E_T(c, 1) + Rp(r, 2) * E_T(c, 2);
}

/// R = P J, the link's rotation from its joint frame's axes and the joint's rotation (eq. JT-6).
/// R must not alias P or J.
template <class M, class N, class O>
void compose(const M& P, const N& J, O&& R) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) R(r, c) = P(r, 0) * J(0, c) + P(r, 1) * J(1, c) + P(r, 2) * J(2, c);
}

/// p = p_p + R_p r, the world position of the offset r in the parent's coordinates (the tree
/// transform's r_T: the link's origin, eq. JT-7), summed left to right. p must not alias r.
template <class U, class M, class W, class O>
void link_position(const U& p_p, const M& Rp, const W& r, O&& p) {
  for (int k = 0; k < 3; ++k) p[k] = p_p[k] + ((Rp(k, 0) * r[0] + Rp(k, 1) * r[1]) + Rp(k, 2) * r[2]);
}

/// a_w = P a, a joint's unit axis a (joint frame) in world axes from its joint frame's axes P;
/// for a = sign e_k (unit_axis k >= 0) P's column k times the sign (eq. JT-8).
template <class T, class M, class U, class O>
void joint_axis(const M& P, int unit_axis, const T& sign, const U& a, O&& a_w) {
  for (int r = 0; r < 3; ++r)
    a_w[r] = unit_axis >= 0 ? sign * P(r, unit_axis)
                            : (P(r, 0) * T(a[0]) + P(r, 1) * T(a[1])) + P(r, 2) * T(a[2]);
}

/// p += a_w x: a prismatic joint at x moves the link's origin along its world axis a_w
/// (joint_axis) from where the tree transform puts it (eq. JT-9).
template <class T, class W, class O>
void slide(const W& a_w, const T& x, O&& p) {
  for (int r = 0; r < 3; ++r) p[r] = p[r] + a_w[r] * x;
}

/// S = [a_w; p x a_w] (revolute) or [0; a_w] (prismatic): a 1-dof joint's motion subspace in
/// frame 0 from its world axis a_w (joint_axis) and the link's origin p relative to frame 0's
/// (eq. JT-10).
template <class T, class W, class O>
void one_dof_subspace(const T* a_w, const W& p, bool revolute, O&& S) {
  if (revolute) {
    for (int r = 0; r < 3; ++r) S[r] = a_w[r];
    S[3] = p[1] * a_w[2] - p[2] * a_w[1];
    S[4] = p[2] * a_w[0] - p[0] * a_w[2];
    S[5] = p[0] * a_w[1] - p[1] * a_w[0];
  } else {
    for (int r = 0; r < 3; ++r) {
      S[r] = T(0.0);
      S[3 + r] = a_w[r];
    }
  }
}

/// A 6 x N matrix stored column by column on a T* (Eigen's Mat6N, the lanes' ball_S), as m(r, c).
template <class T>
struct Columns {
  T* s;
  T& operator()(int r, int c) const { return s[6 * c + r]; }
};
template <class T>
Columns<T> columns(T* s) {
  return {s};
}

/// S = [R; p x R] column by column: a spherical joint's motion subspace in frame 0 from the
/// link's rotation R and its origin p relative to frame 0's (eq. JT-11), JT-10's cross product on
/// each column of R. S must not alias R or p.
template <class M, class W, class O>
void ball_subspace(const M& R, const W& p, O&& S) {
  for (int a = 0; a < 3; ++a) {
    for (int r = 0; r < 3; ++r) S(r, a) = R(r, a);
    S(3, a) = p[1] * R(2, a) - p[2] * R(1, a);
    S(4, a) = p[2] * R(0, a) - p[0] * R(2, a);
    S(5, a) = p[0] * R(1, a) - p[1] * R(0, a);
  }
}

}  // namespace featherdrive::joint_transform_law
