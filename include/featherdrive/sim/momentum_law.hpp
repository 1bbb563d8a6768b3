// compat physx's momentum corrections of a floating base (docs/math/physx_departures.md, PD-4,
// PD-5 and PD-8 to PD-11), written once over the number type: double for Simulation
// (momentum_correction.cpp), SIMD packs of environments in the lanes (sim/simd_lane_step.hpp's
// physx_start, physx_free_momentum, physx_end_momentum). 3-vectors are T[3] arrays, 3 x 3 results
// row-major T[9]. Positions enter only as differences (c_i - C, c - p), so each caller keeps its
// own origin: Simulation the world's, the lanes frame 0's. The sums over links read them through
// `links`, which has
//   T mass(int i), const T* com(int i) (the centre of mass, the caller's origin),
//   void world_inertia(int i, T* I) (this file's world_inertia of link i),
//   void world_inertia_times(int i, const T* w, T* Iw) (this file's of link i),
//   void velocity(int i, T* w, T* v) (the world angular and COM velocities, biased where asked).
// Only the number type's laws, so that the lanes' units compiled for AVX2 and AVX-512 take in no
// inline function of the rest of the library.
#pragma once

#include "featherdrive/algorithm/link_motion_law.hpp"
#include "featherdrive/core/select.hpp"
#include "featherdrive/spatial/joint_transform_law.hpp"
#include "featherdrive/spatial/vector3_law.hpp"

namespace featherdrive::momentum_law {

/// A link's inertia about its centre of mass in world axes, (R Ic) R^T with R Ic formed first
/// (eq. PD-8); R and Ic anything with m(r, c).
template <class T, class M, class N>
void world_inertia(const M& R, const N& Ic, T* I) {
  T RI[9];
  link_motion_law::rotate_full(R, Ic, joint_transform_law::rows(RI));
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      I[3 * r + c] = RI[3 * r] * R(c, 0) + RI[3 * r + 1] * R(c, 1) + RI[3 * r + 2] * R(c, 2);
}

/// I w for a link's world inertia I = R Ic R^T, as R (Ic (R^T w)) (eq. PD-8): a third of the
/// multiplies of forming I.
template <class T, class M, class N>
void world_inertia_times(const M& R, const N& Ic, const T* w, T* Iw) {
  T wl[3], Iwl[3];
  link_motion_law::in_link_axes(R, w, wl);
  for (int r = 0; r < 3; ++r) Iwl[r] = Ic(r, 0) * wl[0] + Ic(r, 1) * wl[1] + Ic(r, 2) * wl[2];
  link_motion_law::in_world_axes(R, Iwl, Iw);
}

/// I_C, the inertia of the n links about C (eq. PD-8), summed link after link.
template <class T, class Links>
void compound_inertia(const Links& links, int n, const T* C, T* I) {
  for (int e = 0; e < 9; ++e) I[e] = T(0.0);
  for (int i = 0; i < n; ++i) {
    const T m = links.mass(i);
    const T* c = links.com(i);
    T Ii[9], d[3];
    links.world_inertia(i, Ii);
    for (int r = 0; r < 3; ++r) d[r] = c[r] - C[r];
    const T d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    for (int r = 0; r < 3; ++r)
      for (int k = 0; k < 3; ++k) {
        const T parallel = m * ((r == k ? d2 : T(0.0)) - d[r] * d[k]);
        I[3 * r + k] = I[3 * r + k] + (Ii[3 * r + k] + parallel);
      }
  }
}

/// The inverse of a 3 x 3 matrix by cofactors (eq. PD-9): cofactor (i, j) = m(i1, j1) m(i2, j2) -
/// m(i1, j2) m(i2, j1) with i1, i2 = i + 1, i + 2 (mod 3), the determinant along column 0, one
/// reciprocal, out(j, i) = cofactor(i, j) / det.
template <class T>
void inverse(const T* I, T* out) {
  auto cofactor = [&](int i, int j) {
    const int i1 = (i + 1) % 3, i2 = (i + 2) % 3, j1 = (j + 1) % 3, j2 = (j + 2) % 3;
    return I[3 * i1 + j1] * I[3 * i2 + j2] - I[3 * i1 + j2] * I[3 * i2 + j1];
  };
  const T c0[3] = {cofactor(0, 0), cofactor(1, 0), cofactor(2, 0)};
  const T det = c0[0] * I[0] + c0[1] * I[3] + c0[2] * I[6];
  const T inv = T(1.0) / det;
  for (int j = 0; j < 3; ++j) out[j] = c0[j] * inv;
  for (int i = 0; i < 3; ++i)
    for (int j = 1; j < 3; ++j) out[3 * j + i] = cofactor(i, j) * inv;
}

/// I_C^-1 of the n links about C (eqs. PD-8, PD-9).
template <class T, class Links>
void compound_inverse(const Links& links, int n, const T* C, T* out) {
  T I[9];
  compound_inertia(links, n, C, I);
  inverse(I, out);
}

/// The linear momentum P and the angular momentum L about C of the n links' velocities (eq.
/// PD-10), M their total mass: P first, then L = sum I_i w_i + m_i (c_i - C) x (v_i - P / M);
/// L null: P only.
template <class T, class Links>
void momentum(const Links& links, int n, const T* C, const T& M, T* P, T* L) {
  for (int r = 0; r < 3; ++r) P[r] = T(0.0);
  for (int i = 0; i < n; ++i) {
    const T m = links.mass(i);
    T w[3], v[3];
    links.velocity(i, w, v);
    for (int r = 0; r < 3; ++r) P[r] = P[r] + m * v[r];
  }
  if (!L) return;
  T vcom[3];
  for (int r = 0; r < 3; ++r) L[r] = T(0.0);
  for (int r = 0; r < 3; ++r) vcom[r] = select(T(0.0) < M, P[r] / M, T(0.0));
  for (int i = 0; i < n; ++i) {
    const T m = links.mass(i);
    const T* c = links.com(i);
    T w[3], v[3], Iw[3], arm[3], dv[3], h[3];
    links.velocity(i, w, v);
    links.world_inertia_times(i, w, Iw);
    for (int r = 0; r < 3; ++r) arm[r] = c[r] - C[r], dv[r] = v[r] - vcom[r];
    vector3_law::cross(arm, dv, h);
    for (int r = 0; r < 3; ++r) L[r] = L[r] + (Iw[r] + m * h[r]);
  }
}

/// The free velocity's targets (physx_departures.md, "After the free velocity"): the momenta P, L
/// about C plus dt times the external wrench: gravity M g at C and the wrench (n, f) on the root's
/// dofs in world axes at its origin p0.
template <class T>
void add_root_wrench(const T& dt, const T& M, const T* g, const T* n, const T* f, const T* p0,
                     const T* C, T* P, T* L) {
  T arm[3], nf[3];
  for (int r = 0; r < 3; ++r) arm[r] = p0[r] - C[r];
  vector3_law::cross(arm, f, nf);
  for (int r = 0; r < 3; ++r) {
    P[r] = P[r] + dt * (M * g[r] + f[r]);
    L[r] = L[r] + dt * (n[r] + nf[r]);
  }
}

/// The same for a link's force F = [torque about frame 0's origin; force], C0 the centre of mass
/// relative to frame 0's origin (link damping, link velocity limits).
template <class T>
void add_link_wrench(const T& dt, const T* F, const T* C0, T* P, T* L) {
  T cf[3];
  vector3_law::cross(C0, F + 3, cf);
  for (int r = 0; r < 3; ++r) {
    P[r] = P[r] + dt * F[3 + r];
    L[r] = L[r] + dt * (F[r] - cf[r]);
  }
}

/// The rigid rotation dw about C that scales the angular momentum L1 by `ratio` (eq. PD-4, Iinv
/// = I_C^-1), then the uniform linear velocity dv that makes the linear momentum P1 `target`
/// (eq. PD-5).
template <class T, class Links>
void rigid_correction(const Links& links, int n, const T* Iinv, const T* C, const T& M,
                      const T* P1, const T* L1, const T& ratio, const T* target, T* dw, T* dv) {
  T l[3];
  for (int r = 0; r < 3; ++r) l[r] = L1[r] * (ratio - T(1.0));
  for (int r = 0; r < 3; ++r)
    dw[r] = Iinv[3 * r] * l[0] + Iinv[3 * r + 1] * l[1] + Iinv[3 * r + 2] * l[2];
  T P[3] = {P1[0], P1[1], P1[2]};
  for (int i = 0; i < n; ++i) {
    const T m = links.mass(i);
    const T* c = links.com(i);
    T d[3], t[3];
    for (int r = 0; r < 3; ++r) d[r] = c[r] - C[r];
    vector3_law::cross(dw, d, t);
    for (int r = 0; r < 3; ++r) P[r] = P[r] + m * t[r];
  }
  for (int r = 0; r < 3; ++r) dv[r] = (target[r] - P[r]) / M;
}

/// The root's world twist (w0, origin velocity v0, origin p0) moved by the rigid correction's
/// field (dw, dv + dw x r) at its origin, r = p0 - C.
template <class T>
void move_root(const T* dw, const T* dv, const T* p0, const T* C, T* w0, T* v0) {
  T arm[3], turn[3];
  for (int r = 0; r < 3; ++r) arm[r] = p0[r] - C[r];
  vector3_law::cross(dw, arm, turn);
  for (int r = 0; r < 3; ++r) {
    w0[r] = w0[r] + dw[r];
    v0[r] = v0[r] + (dv[r] + turn[r]);
  }
}

/// The end of the step's root origin velocity (eq. PD-11): the root keeps its world angular
/// velocity w0 and its centre of mass's velocity, v0 + w0 x (c_s - p_s) at the start (COM c_s,
/// origin p_s), so its new origin moves at that less w0 x (c_n - p_n).
template <class T>
void keep_root_com_velocity(const T* w0, const T* v0, const T* c_s, const T* p_s, const T* c_n,
                            const T* p_n, T* vo) {
  T ds[3], dn[3], a[3], b[3];
  for (int r = 0; r < 3; ++r) ds[r] = c_s[r] - p_s[r], dn[r] = c_n[r] - p_n[r];
  vector3_law::cross(w0, ds, a);
  vector3_law::cross(w0, dn, b);
  for (int r = 0; r < 3; ++r) vo[r] = (v0[r] + a[r]) - b[r];
}

/// The end of the step's shift of every link (physx_departures.md, "End of the step", 4): the
/// COM from C_now to C_start + P_pos per_mass (per_mass = dt / M), world positions.
template <class T>
void com_shift(const T* C_start, const T* P_pos, const T& per_mass, const T* C_now, T* shift) {
  for (int r = 0; r < 3; ++r) shift[r] = (C_start[r] + P_pos[r] * per_mass) - C_now[r];
}

}  // namespace featherdrive::momentum_law
