// PhysX's per-link stages (docs/math/joint_constraints.md, J8-J10), written once over the number
// type: double for Simulation (link_cfm.cpp, transmitted_force.cpp, link_damping.cpp), SIMD packs
// of environments in the lanes (sim/simd_lane_step.hpp). Vectors are T[3] / T[6] arrays, spatial
// ones [angular; linear] in frame 0 (world axes, origin at the root link's origin); a symmetric 6 x
// 6 matrix [A, B; B^T, C] is T[21]: A's entries 00 11 22 01 02 12, B's nine row by row, C's as A's
// (the lanes' layout). Only <cmath>, core/select.hpp and spatial/vector3_law.hpp, so that the
// lanes' units compiled for AVX2 and AVX-512 take in no inline function of the rest of the library;
// sqrt is found by argument-dependent lookup for a pack (correctly rounded, as std::sqrt).
#pragma once

#include <cmath>

#include "featherdrive/core/select.hpp"
#include "featherdrive/spatial/vector3_law.hpp"

namespace featherdrive::link_law {

/// The packed T[21] of the upper triangle of a 6 x 6 matrix m (m(r, c) = m[r + 6 c], Eigen's
/// column-major Mat6; symmetric, so a row-major one reads the same).
template <class T>
void pack_symmetric(const T* m, T* out) {
  for (int r = 0; r < 3; ++r) {
    out[r] = m[r + 6 * r];
    out[15 + r] = m[(3 + r) + 6 * (3 + r)];
    for (int c = 0; c < 3; ++c) out[6 + 3 * r + c] = m[r + 6 * (3 + c)];
  }
  out[3] = m[0 + 6 * 1], out[4] = m[0 + 6 * 2], out[5] = m[1 + 6 * 2];
  out[18] = m[3 + 6 * 4], out[19] = m[3 + 6 * 5], out[20] = m[4 + 6 * 5];
}

/// Where entry (r, c) of a symmetric 6 x 6 is in the packed T[21] (pack_symmetric's layout), as a
/// table: loops index it with their counters, where a recursive constexpr function is not always
/// folded (it showed as 5 % of the lanes' step on arm7).
inline constexpr int kPacked[6][6] = {{0, 3, 4, 6, 7, 8},     {3, 1, 5, 9, 10, 11},
                                      {4, 5, 2, 12, 13, 14},  {6, 9, 12, 15, 18, 19},
                                      {7, 10, 13, 18, 16, 20}, {8, 11, 14, 19, 20, 17}};

/// y = M x for a packed symmetric M, each row summed left to right.
template <class T>
void symmetric_times(const T* M, const T* x, T* y) {
  for (int r = 0; r < 6; ++r) {
    T sum = M[kPacked[r][0]] * x[0];
    for (int k = 1; k < 6; ++k) sum = sum + M[kPacked[r][k]] * x[k];
    y[r] = sum;
  }
}

using vector3_law::cross;

/// J8: a link's cfm, cfm_scale times the largest b_j^T Lambda b_j over the world axes e_j,
/// b_j = [c x e_j; e_j], from its whole-articulation response Lambda (packed) and its centre of
/// mass c. With u = c x e_j, whose entry j is 0 and whose others are p, q:
/// b_j^T Lambda b_j = (u_p^2 A_pp + 2 u_p u_q A_pq + u_q^2 A_qq) + 2 (u_p B_pj + u_q B_qj) + C_jj.
template <class T>
T cfm(const T* Lambda, const T* c, const T& scale) {
  // Per axis j: p, q and u_p, u_q as signs of c's entries (e_0: (0, c2, -c1); e_1: (-c2, 0, c0);
  // e_2: (c1, -c0, 0)).
  const T u[3][2] = {{c[2], -c[1]}, {-c[2], c[0]}, {c[1], -c[0]}};
  constexpr int kP[3] = {1, 0, 0}, kQ[3] = {2, 2, 1};
  constexpr int kA[3][3] = {{0, 3, 4}, {3, 1, 5}, {4, 5, 2}};
  T largest(0.0);
  for (int j = 0; j < 3; ++j) {
    const int p = kP[j], q = kQ[j];
    const T up = u[j][0], uq = u[j][1];
    const T angular = (up * up * Lambda[kA[p][p]] + T(2.0) * (up * uq) * Lambda[kA[p][q]]) +
                      uq * uq * Lambda[kA[q][q]];
    const T coupling = up * Lambda[6 + 3 * p + j] + uq * Lambda[6 + 3 * q + j];
    const T x = (angular + T(2.0) * coupling) + Lambda[15 + j];
    largest = select(largest < x, x, largest);  // std::max
  }
  return select(scale == T(0.0), T(0.0), scale * largest);
}

/// J9: |tau| + |f| of the spatial force F = IA a + pA a joint transmits to its subtree (IA, pA:
/// the child link's articulated inertia (packed) and bias force, a its acceleration; frame 0),
/// tau = F's torque less c x f, about the link's centre of mass c.
template <class T>
T transmitted_force_magnitude(const T* IA, const T* a, const T* pA, const T* c) {
  using std::sqrt;
  T F[6];
  symmetric_times(IA, a, F);
  for (int r = 0; r < 6; ++r) F[r] = F[r] + pA[r];
  T cf[3];
  cross(c, F + 3, cf);
  const T tx = F[0] - cf[0], ty = F[1] - cf[1], tz = F[2] - cf[2];
  return sqrt(tx * tx + ty * ty + tz * tz) + sqrt(F[3] * F[3] + F[4] * F[4] + F[5] * F[5]);
}

/// A link's damping and velocity-limit parameters as the numbers J10 reads.
template <class T>
struct Damping {
  T linear_damping, angular_damping, max_linear_velocity, max_angular_velocity;
};

/// J10: the external force [torque about frame 0's origin; force] of PhysX's link damping and
/// link velocity limits on a link of mass m with centre of mass c, from its start-of-step angular
/// velocity omega (world axes; omega_local the same in the link's axes) and centre-of-mass
/// velocity v_com, RI = R Ic (row by row, Ic the inertia about the centre of mass in link axes),
/// gravity g and step dt.
template <class T>
void damping_force(const Damping<T>& d, const T* omega, const T* omega_local, const T* v_com,
                   const T* RI, const T* c, const T& m, const T* g, const T& dt, T* F) {
  using std::sqrt;
  const T zero(0.0), inv_dt = T(1.0) / dt;
  // c = min(damping, 1 / dt) for damping > 0, else 0; s = 1 - v_max / |v| beyond the limit.
  const T lin = select(zero < d.linear_damping,
                       select(inv_dt < d.linear_damping, inv_dt, d.linear_damping), zero);
  const T ang = select(zero < d.angular_damping,
                       select(inv_dt < d.angular_damping, inv_dt, d.angular_damping), zero);
  const T speed = sqrt(v_com[0] * v_com[0] + v_com[1] * v_com[1] + v_com[2] * v_com[2]);
  const T spin = sqrt(omega[0] * omega[0] + omega[1] * omega[1] + omega[2] * omega[2]);
  const T lin_scale =
      select(d.max_linear_velocity < speed, T(1.0) - d.max_linear_velocity / speed, zero);
  const T ang_scale =
      select(d.max_angular_velocity < spin, T(1.0) - d.max_angular_velocity / spin, zero);
  const T fc = -m * (lin + lin_scale / dt), gc = m * lin * dt;
  T f[3];
  for (int r = 0; r < 3; ++r) f[r] = fc * v_com[r] - gc * g[r];
  T Iw[3];  // I_w omega = (R Ic) omega_local
  for (int r = 0; r < 3; ++r)
    Iw[r] = RI[3 * r] * omega_local[0] + RI[3 * r + 1] * omega_local[1] +
            RI[3 * r + 2] * omega_local[2];
  const T tc = -(ang + ang_scale / dt);
  T cf[3];
  cross(c, f, cf);
  for (int r = 0; r < 3; ++r) {
    F[r] = tc * Iw[r] + cf[r];
    F[3 + r] = f[r];
  }
}

}  // namespace featherdrive::link_law
