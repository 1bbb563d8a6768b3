// compat physx's link bias at a prismatic joint (docs/math/physx_departures.md, PD-1 to PD-3),
// written once over the number type: double for Simulation (link_bias.cpp), SIMD packs of
// environments in the lanes (sim/simd_lane_step.hpp). 3-vectors are T[3] arrays (an Eigen
// Vec3's data() for double); no other include, so that the lanes' units compiled for AVX2 and AVX-512
// take in no inline function of the rest of the library.
#pragma once

#include "featherdrive/spatial/vector3_law.hpp"

namespace featherdrive::link_bias_law {

using vector3_law::cross;
using vector3_law::dot;

/// PD-1: link i's bias (b_w, b_v) from its parent's (b_wp, b_vp), the world angular velocities
/// and centre-of-mass velocities of the two at the step's start (w_p, v_p; w_i, v_i) and
/// r = c_i - c_p: the parent's bias moved rigidly to c_i plus dt times the classical acceleration
/// of c_i at zero joint and root accelerations.
template <class T>
void link_bias(const T* w_p, const T* v_p, const T* b_wp, const T* b_vp, const T* w_i,
               const T* v_i, const T* r, const T& dt, T* b_w, T* b_v) {
  T wr[3], mu_w[3], mu_v[3];
  cross(w_p, r, wr);
  for (int k = 0; k < 3; ++k) {
    mu_w[k] = w_i[k] - w_p[k];
    mu_v[k] = v_i[k] - v_p[k] - wr[k];
  }
  T a[3], wwr[3], wmu[3], mm[3], br[3];
  cross(w_p, mu_w, a);
  cross(w_p, wr, wwr);
  cross(w_p, mu_v, wmu);
  cross(mu_w, mu_v, mm);
  cross(b_wp, r, br);
  for (int k = 0; k < 3; ++k) {
    b_w[k] = b_wp[k] + dt * a[k];
    b_v[k] = b_vp[k] + br[k] + dt * (wwr[k] + T(2.0) * wmu[k] + mm[k]);
  }
}

/// PD-2: a prismatic row's bias u . (B_child - B_parent) at the joint point j, with the links'
/// centres of mass c_i, c_p and biases.
template <class T>
T prismatic_row_bias(const T* u, const T* j, const T* c_i, const T* c_p, const T* b_wi,
                     const T* b_vi, const T* b_wp, const T* b_vp) {
  T di[3], dp[3], child[3], parent[3], diff[3];
  for (int k = 0; k < 3; ++k) di[k] = j[k] - c_i[k], dp[k] = j[k] - c_p[k];
  cross(b_wi, di, child);
  cross(b_wp, dp, parent);
  for (int k = 0; k < 3; ++k) diff[k] = (b_vi[k] + child[k]) - (b_vp[k] + parent[k]);
  return dot(u, diff);
}

/// PD-3: a prismatic joint's position change along its start axis u from its child's and
/// parent's centres of mass now (c_i', c_p') and at the step's start (c_i, c_p), less the
/// parent's accumulated turn t_p applied to the offset c_p - c_i.
template <class T>
T prismatic_position_change(const T* u, const T* c_i_now, const T* c_i, const T* c_p_now,
                            const T* c_p, const T* t_p) {
  T off[3], t[3], moved[3];
  for (int k = 0; k < 3; ++k) off[k] = c_p[k] - c_i[k];
  cross(t_p, off, t);
  for (int k = 0; k < 3; ++k) moved[k] = ((c_i_now[k] - c_i[k]) - (c_p_now[k] - c_p[k])) + t[k];
  return dot(u, moved);
}

}  // namespace featherdrive::link_bias_law
