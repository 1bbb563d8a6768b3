// ABA pass 1 for one link in frame 0 (docs/math/unit_response.md, "Pass 1", eq. P1-1 to P1-7),
// over the number type: the body's inertia for Simulation (algorithm/aba.cpp, double) and the
// lanes (sim/simd_lane_step.hpp's link_velocity_and_bias, one vector of a pack), so that both
// form it with the same operations, and so the velocity, velocity-product acceleration and bias
// force (each engine forms S qd itself: one column, a ball's three, a root's six). A 3 x 3
// matrix is anything with m(r, c) (Eigen's Mat3, or a row-major T[9] through
// joint_transform_law::rows); spatial vectors are T[6], [angular; linear]; the symmetric block A
// is T[6]: 00 11 22 01 02 12 (link_laws.hpp's packed layout, its first six). Only
// spatial/vector3_law.hpp, so that the lanes' units compiled for AVX2 and AVX-512 take in no
// inline function of the rest of the library.
#pragma once

#include "featherdrive/spatial/vector3_law.hpp"

namespace featherdrive::link_motion_law {

/// Where A(r, c) is in the packed T[6].
constexpr int kA[3][3] = {{0, 3, 4}, {3, 1, 5}, {4, 5, 2}};

/// RI = R Ic for principal moments xx, yy, zz: R's columns scaled (eq. P1-1).
template <class T, class M, class N>
void rotate_principal(const M& R, const T& xx, const T& yy, const T& zz, N&& RI) {
  for (int r = 0; r < 3; ++r) {
    RI(r, 0) = R(r, 0) * xx;
    RI(r, 1) = R(r, 1) * yy;
    RI(r, 2) = R(r, 2) * zz;
  }
}

/// RI = R Ic for a full Ic, each entry summed left to right (eq. P1-1).
template <class M, class N, class O>
void rotate_full(const M& R, const N& Ic, O&& RI) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      RI(r, c) = R(r, 0) * Ic(0, c) + R(r, 1) * Ic(1, c) + R(r, 2) * Ic(2, c);
}

/// The body's centre of mass in frame 0, c = p + R com, and m c (eq. P1-2), for a link with
/// orientation R at p and centre of mass com in its own frame.
template <class T, class M>
void centre_of_mass(const M& R, const T* p, const T* com, const T& m, T* c, T* mc) {
  for (int r = 0; r < 3; ++r) {
    c[r] = p[r] + (R(r, 0) * com[0] + R(r, 1) * com[1] + R(r, 2) * com[2]);
    mc[r] = m * c[r];
  }
}

/// The top-left block of the body's inertia [A, m c x; m c x^T, m 1] in frame 0 (eq. P1-2),
/// A = RI R^T + (mc . c) 1 - mc c^T on its six distinct entries, from RI = R Ic and
/// centre_of_mass's c and mc.
template <class T, class M, class N>
void rotational_block(const M& R, const N& RI, const T* c, const T* mc, T* A) {
  const T mcc = vector3_law::dot(mc, c);
  for (int r = 0; r < 3; ++r)
    for (int k = r; k < 3; ++k) {
      T a = RI(r, 0) * R(k, 0) + RI(r, 1) * R(k, 1) + RI(r, 2) * R(k, 2) - mc[r] * c[k];
      if (r == k) a = a + mcc;
      A[kA[r][k]] = a;
    }
}

/// v = v_parent + S qd (eq. P1-3); v_parent null for a link without a parent, whose v is S qd.
template <class T>
void velocity(const T* v_parent, const T* sqd, T* v) {
  for (int r = 0; r < 6; ++r) v[r] = v_parent ? v_parent[r] + sqd[r] : sqd[r];
}

/// c = v x S qd, the velocity-product acceleration (eq. P1-4): [w x wJ; w x vJ + vo x wJ].
template <class T>
void velocity_product(const T* v, const T* sqd, T* c) {
  T t1[3], t2[3];
  vector3_law::cross(v, sqd, c);
  vector3_law::cross(v, sqd + 3, t1);
  vector3_law::cross(v + 3, sqd, t2);
  for (int r = 0; r < 3; ++r) c[3 + r] = t1[r] + t2[r];
}

/// p = v x* I v, the bias force (eq. P1-5), from the body inertia's parts (A packed, mc, m):
/// h = I v = [A w + mc x vo; m vo - mc x w] (a third of the 6 x 6 product's multiplies), then
/// p = [w x h_w + vo x h_v; w x h_v]. A is anything with A[e] (the lanes read it where it is
/// stored: kept in registers, it spilled).
template <class T, class AV>
void bias_force(const T* v, const AV& A, const T* mc, const T& m, T* p) {
  T h[6], mv[3], mw[3];
  vector3_law::cross(mc, v + 3, mv);
  vector3_law::cross(mc, v, mw);
  for (int r = 0; r < 3; ++r) {
    h[r] = (A[kA[r][0]] * v[0] + A[kA[r][1]] * v[1] + A[kA[r][2]] * v[2]) + mv[r];
    h[3 + r] = m * v[3 + r] - mw[r];
  }
  T t1[3], t2[3];
  vector3_law::cross(v, h, t1);
  vector3_law::cross(v + 3, h + 3, t2);
  for (int r = 0; r < 3; ++r) p[r] = t1[r] + t2[r];
  vector3_law::cross(v, h + 3, p + 3);
}

/// v_c = vo + w x c, the velocity of the link's point at c (frame 0) from its velocity
/// v = [w; vo] (eq. P1-6): a centre of mass's, for compat physx's link bias and link damping.
template <class T>
void point_velocity(const T* v, const T* c, T* vc) {
  T t[3];
  vector3_law::cross(v, c, t);
  for (int r = 0; r < 3; ++r) vc[r] = v[3 + r] + t[r];
}

/// w_L = R^T w, the angular velocity w (world axes) in the link's axes R (eq. P1-7), each entry
/// summed left to right.
template <class T, class M>
void in_link_axes(const M& R, const T* w, T* w_L) {
  for (int r = 0; r < 3; ++r) w_L[r] = R(0, r) * w[0] + R(1, r) * w[1] + R(2, r) * w[2];
}

/// x_W = R x, a vector x in the link's axes R in world axes (eq. PD-7), each entry summed left to
/// right: a floating root's twist and a ball's rates in compat physx's world velocities.
template <class T, class M>
[[gnu::always_inline]] inline void in_world_axes(const M& R, const T* x, T* x_W) {
  for (int r = 0; r < 3; ++r) x_W[r] = R(r, 0) * x[0] + R(r, 1) * x[1] + R(r, 2) * x[2];
}

/// What a joint adds to world_velocity: nothing (fixed), qd about or along its unit axis, a
/// ball's three rates about the link's axes.
enum class JointRates { none, about_axis, along_axis, ball };

/// Compat physx's world velocities (docs/math/physx_departures.md, eq. PD-6): link i's angular
/// velocity w and centre-of-mass velocity v in the pose R (its axes), p (its origin), c (its
/// centre of mass), from its parent's w_p and v_p at the parent's centre of mass c_p and the
/// joint's rates qd (axis in the link's axes, for one dof). A root (c_p null) takes w_p, v_p as
/// its world twist at its origin. Parent and link arrays must not overlap. Inlined: a call per
/// link cost Simulation's compat physx step 4 % more instructions.
template <class T, class M, class U>
[[gnu::always_inline]] inline void world_velocity(const T* w_p, const T* v_p, const T* c_p, const M& R, const T* p, const T* c,
                    JointRates joint, const U* axis, const T* qd, T* w, T* v) {
  T vo[3], t[3], d[3];
  for (int r = 0; r < 3; ++r) w[r] = w_p[r], vo[r] = v_p[r];
  if (c_p) {
    for (int r = 0; r < 3; ++r) d[r] = p[r] - c_p[r];
    vector3_law::cross(w_p, d, t);
    for (int r = 0; r < 3; ++r) vo[r] = v_p[r] + t[r];
    T a[3];
    if (joint == JointRates::about_axis || joint == JointRates::along_axis) {
      const T u[3] = {T(axis[0]), T(axis[1]), T(axis[2])};
      in_world_axes(R, u, a);
      T* x = joint == JointRates::about_axis ? w : vo;
      for (int r = 0; r < 3; ++r) x[r] = x[r] + a[r] * qd[0];
    } else if (joint == JointRates::ball) {
      in_world_axes(R, qd, a);
      for (int r = 0; r < 3; ++r) w[r] = w[r] + a[r];
    }
  }
  for (int r = 0; r < 3; ++r) d[r] = c[r] - p[r];
  vector3_law::cross(w, d, t);
  for (int r = 0; r < 3; ++r) v[r] = vo[r] + t[r];
}

}  // namespace featherdrive::link_motion_law
