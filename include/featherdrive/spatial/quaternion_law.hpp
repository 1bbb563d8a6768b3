// Unit quaternions and rotations on raw arrays, written once over the number type
// (docs/math/quaternion_update.md): double for Simulation (joint_motion.cpp,
// momentum_correction.cpp, spherical_rows.cpp), SIMD packs of environments in the lanes
// (sim/simd_lane_step.hpp), so that both move a quaternion with the same operations. A quaternion
// is T[4], w x y z; a rotation matrix T[9], row-major. Only <cmath>, core/select.hpp and
// spatial/sincos.hpp, so that the lanes' units compiled for AVX2 and AVX-512 take in no inline
// function of the rest of the library; sqrt is found by argument-dependent lookup for a pack
// (correctly rounded, as std::sqrt).
#pragma once

#include <cmath>

#include "featherdrive/core/select.hpp"
#include "featherdrive/spatial/sincos.hpp"

namespace featherdrive::quaternion_law {

/// q / |q| (eq. Q-3).
template <class T>
void unit(const T* q, T* out) {
  using std::sqrt;
  const T n = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  for (int e = 0; e < 4; ++e) out[e] = q[e] / n;
}

/// a b, Hamilton's product (eq. Q-2). out must not alias a or b.
template <class T>
void product(const T* a, const T* b, T* out) {
  out[0] = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3];
  out[1] = a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2];
  out[2] = a[0] * b[2] + a[2] * b[0] + a[3] * b[1] - a[1] * b[3];
  out[3] = a[0] * b[3] + a[3] * b[0] + a[1] * b[2] - a[2] * b[1];
}

/// sin and cos of a turn's angle: sincos_law's for a pack; for a double the same bits up to
/// 1e5 rad, glibc's beyond and for inf or NaN (sincos_inline), where the law loses its digits.
template <class T>
void angle_sincos(const T& x, T& s, T& c) {
  sincos_law::sincos(x, s, c);
}
inline void angle_sincos(double x, double& s, double& c) { sincos_inline(x, s, c); }

/// exp(t / 2): the quaternion of the turn by |t| about t, the identity for t = 0 (eq. Q-1).
template <class T>
void turn(const T* t, T* out) {
  using std::sqrt;
  const T angle = sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
  T s, c;
  angle_sincos(T(0.5) * angle, s, c);
  const auto turns = T(0.0) < angle;  // else the identity (and t / angle is not used)
  out[0] = select(turns, c, T(1.0));
  for (int r = 0; r < 3; ++r) out[1 + r] = select(turns, s * (t[r] / angle), T(0.0));
}

/// out = q v q^-1 for a unit q: v + 2 w (u x v) + 2 u x (u x v), u = (x, y, z) (eq. Q-4).
/// out must not alias v.
template <class T>
void rotate(const T* q, const T* v, T* out) {
  const T* u = q + 1;
  const T uv[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                   u[0] * v[1] - u[1] * v[0]};
  const T uv2[3] = {uv[0] + uv[0], uv[1] + uv[1], uv[2] + uv[2]};
  const T uuv[3] = {u[1] * uv2[2] - u[2] * uv2[1], u[2] * uv2[0] - u[0] * uv2[2],
                    u[0] * uv2[1] - u[1] * uv2[0]};
  for (int r = 0; r < 3; ++r) out[r] = (v[r] + q[0] * uv2[r]) + uuv[r];
}

/// The rotation matrix of q / |q| (eq. Q-5).
template <class T>
void rotation(const T* q, T* R) {
  T u[4];
  unit(q, u);
  const T w = u[0], x = u[1], y = u[2], z = u[3];
  const T tx = T(2.0) * x, ty = T(2.0) * y, tz = T(2.0) * z;
  const T twx = tx * w, twy = ty * w, twz = tz * w, txx = tx * x, txy = ty * x, txz = tz * x;
  const T tyy = ty * y, tyz = tz * y, tzz = tz * z;
  R[0] = T(1.0) - (tyy + tzz);
  R[1] = txy - twz;
  R[2] = txz + twy;
  R[3] = txy + twz;
  R[4] = T(1.0) - (txx + tzz);
  R[5] = tyz - twx;
  R[6] = txz - twy;
  R[7] = tyz + twx;
  R[8] = T(1.0) - (txx + tyy);
}

/// A unit quaternion Q advanced by the body-frame angular velocity w over h: unit(Q exp(w h / 2))
/// (eq. Q-6). out may alias Q.
template <class T>
void integrate_unit_body(const T* Q, const T* w, const T& h, T* out) {
  T d[4], o[4];
  const T t[3] = {w[0] * h, w[1] * h, w[2] * h};
  turn(t, d);
  product(Q, d, o);
  unit(o, out);
}

/// q advanced by w over h: integrate_unit_body of unit(q) (eq. Q-6). out may alias q.
template <class T>
void integrate_body(const T* q, const T* w, const T& h, T* out) {
  T Q[4];
  unit(q, Q);
  integrate_unit_body(Q, w, h, out);
}

/// out = exp(h turn) R: R turned by the angle h |turn| about turn in the world, R when that angle
/// is 0 (eq. Q-7). out must not alias R.
template <class T>
void turn_rotation(const T* turn, const T& h, const T* R, T* out) {
  using std::sqrt;
  const T norm = sqrt(turn[0] * turn[0] + turn[1] * turn[1] + turn[2] * turn[2]);
  const T angle = h * norm;
  const auto turns = T(0.0) < angle;
  T s, c;
  angle_sincos(angle, s, c);
  T axis[3], sa[3], ca[3], E[9];
  for (int r = 0; r < 3; ++r) {
    axis[r] = turn[r] / norm;
    sa[r] = s * axis[r];
    ca[r] = (T(1.0) - c) * axis[r];
  }
  T tmp = ca[0] * axis[1];
  E[1] = tmp - sa[2], E[3] = tmp + sa[2];
  tmp = ca[0] * axis[2];
  E[2] = tmp + sa[1], E[6] = tmp - sa[1];
  tmp = ca[1] * axis[2];
  E[5] = tmp - sa[0], E[7] = tmp + sa[0];
  for (int r = 0; r < 3; ++r) E[4 * r] = ca[r] * axis[r] + c;
  for (int r = 0; r < 3; ++r)
    for (int col = 0; col < 3; ++col)
      out[3 * r + col] = select(
          turns, (E[3 * r] * R[col] + E[3 * r + 1] * R[3 + col]) + E[3 * r + 2] * R[6 + col],
          R[3 * r + col]);
}

}  // namespace featherdrive::quaternion_law
