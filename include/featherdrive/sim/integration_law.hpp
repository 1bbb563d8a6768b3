// The step's position update where it turns a quaternion or a rotation (docs/math/
// quaternion_update.md), written once over the number type: double for Simulation
// (joint_motion.cpp's integrate_configuration, momentum_correction.cpp's integrate_root_about_com,
// spherical_rows.cpp's integrate_spherical_joints), SIMD packs of environments in the lanes
// (LaneStep::integrate, integrate_root, integrate_root_physx, integrate_balls_physx in
// sim/simd_lane_step.hpp). A 1-dof joint's q + h qd needs no law. Only laws over the number type
// (quaternion_law, link_motion_law, vector3_law, joint_transform_law's rows), so that the lanes'
// units compiled for AVX2 and AVX-512 take in no inline function of the rest of the library.
#pragma once

#include "featherdrive/algorithm/link_motion_law.hpp"
#include "featherdrive/spatial/joint_transform_law.hpp"
#include "featherdrive/spatial/quaternion_law.hpp"
#include "featherdrive/spatial/vector3_law.hpp"

namespace featherdrive::integration_law {

/// The joint frame of a floating root as the lanes keep it: E and r of its tree transform (E
/// row-major), E^T's quaternion Q_T (w x y z) and whether E is exactly the identity.
struct RootFrame {
  const double* E;
  const double* r;
  const double* QT;
  bool identity;
};

/// compat physx: a floating root's q[0..7) (origin, quaternion in its joint frame) moved over h
/// about its centre of mass c (link frame) with the world velocities of its step's start axes R0
/// (row-major): w = R0 qd[0..3), v_com = R0 (qd[3..6) + qd[0..3) x c). Its COM moves by h v_com,
/// its world rotation Q_T Q turns by exp(h w) in the world and is taken back to the joint frame
/// (eq. Q-8, physx_departures.md "Root pose"). q is read, then written.
template <class T>
void root_about_com(const RootFrame& f, const T* c, const T* R0, const T* qd, const T& h, T* q) {
  using link_motion_law::in_link_axes;
  using link_motion_law::in_world_axes;
  using quaternion_law::product;
  using quaternion_law::rotate;
  using quaternion_law::unit;
  const auto E = [&f](int r, int c) { return T(f.E[3 * r + c]); };  // row-major, as T
  const T QT[4] = {T(f.QT[0]), T(f.QT[1]), T(f.QT[2]), T(f.QT[3])};
  T Q[4];
  unit(q + 3, Q);
  if (!f.identity) {  // Q_T Q_J
    const T QJ[4] = {Q[0], Q[1], Q[2], Q[3]};
    product(QT, QJ, Q);
  }
  T p[3];  // the root's origin in the world, r_T + E_T^T q
  if (f.identity) {
    for (int r = 0; r < 3; ++r) p[r] = T(f.r[r]) + q[r];
  } else {
    in_link_axes(E, q, p);
    for (int r = 0; r < 3; ++r) p[r] = T(f.r[r]) + p[r];
  }
  T wc[3], vb[3], w[3], vcom[3], Qc[3], com[3];
  vector3_law::cross(qd, c, wc);
  for (int r = 0; r < 3; ++r) vb[r] = qd[3 + r] + wc[r];
  in_world_axes(joint_transform_law::rows(R0), qd, w);
  in_world_axes(joint_transform_law::rows(R0), vb, vcom);
  rotate(Q, c, Qc);
  for (int r = 0; r < 3; ++r) com[r] = (p[r] + Qc[r]) + h * vcom[r];
  const T t[3] = {h * w[0], h * w[1], h * w[2]};
  T d[4];
  quaternion_law::turn(t, d);
  // exp(h w) Q, normalised, then taken back to the joint frame (Q_T^-1 first) and normalised
  // again.
  T dQ[4], once[4], o[4], oc[3];
  product(d, Q, dQ);
  unit(dQ, once);
  if (f.identity) {
    unit(once, o);
    rotate(o, c, oc);
    for (int r = 0; r < 3; ++r) q[r] = (com[r] - oc[r]) - T(f.r[r]);
  } else {
    rotate(once, c, oc);
    const T back[4] = {QT[0], T(0.0) - QT[1], T(0.0) - QT[2], T(0.0) - QT[3]};
    T joint[4], d_world[3];
    product(back, once, joint);
    unit(joint, o);
    for (int r = 0; r < 3; ++r) d_world[r] = (com[r] - oc[r]) - T(f.r[r]);
    in_world_axes(E, d_world, q);  // E_T (p - r_T)
  }
  for (int e = 0; e < 4; ++e) q[3 + e] = o[e];
}

}  // namespace featherdrive::integration_law
