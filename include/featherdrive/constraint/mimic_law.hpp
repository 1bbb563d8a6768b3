// A mimic row's law (docs/math/mimic_joints.md, eq. 3-6), written once over the number type:
// double for Simulation (mimic_solve.cpp), SIMD packs in the lanes (sim/simd_lane_step.hpp). No
// include beyond core/select.hpp, so that the lanes' units compiled for AVX2 and AVX-512 take in
// no inline function of the rest of the library.
#pragma once

#include "featherdrive/core/select.hpp"

namespace featherdrive {

/// One row's coefficients for one step (eq. 3-6): lambda = -(bias_per_error C + J v) *
/// effective_mass in position iterations, -J v / r in velocity iterations. Written over the number
/// type T: double for Simulation, a SIMD pack of environments in the lanes.
template <class T>
struct MimicRowOf {
  T response{0.0};        ///< r = J M^-1 J^T, J = e_a^T + gear_ratio e_b^T (eq. 2)
  T bias_per_error{0.0};  ///< erp / h
  T effective_mass{0.0};  ///< 1 / (r + cfm)
};
using MimicRow = MimicRowOf<double>;

namespace mimic_law {

/// The row for a step of h with response r (eq. 3-4): soft where natural_frequency and
/// damping_ratio are both > 0, else rigid with the solver's bias_coefficient (PGS 0.8, TGS
/// 2 sqrt(1 / n)). Chooses only through select (core/select.hpp).
template <class T>
MimicRowOf<T> setup(const T& natural_frequency, const T& damping_ratio, const T& r, double h,
                    double bias_coefficient) {
  const auto soft = (T(0.0) < natural_frequency) & (T(0.0) < damping_ratio);
  const T kp = natural_frequency * natural_frequency / r;
  const T kd = T(2.0) * natural_frequency * damping_ratio / r;
  const T hk = T(h) * kp + kd;
  const T cfm = select(soft, T(1.0) / (T(h) * hk), T(0.0));
  const T erp = select(soft, T(h) * kp / hk, T(bias_coefficient));
  return {r, erp / T(h), T(1.0) / (r + cfm)};
}

/// The row's impulse at constraint error C and constraint velocity J v (eq. 5, 6).
template <class T>
T impulse(const MimicRowOf<T>& row, const T& error, const T& velocity, bool velocity_iteration) {
  if (velocity_iteration) return -velocity / row.response;
  return -(row.bias_per_error * error + velocity) * row.effective_mass;
}

/// Every mimic row once, in order, as PhysX solves them before a sweep (mimic_joints.md): row j
/// sees the velocities of the k coupled dofs that the rows before it left, moves them by its
/// impulse times its k entries of M^-1 J^T (change(j)), and adds its impulses to its two dofs'
/// (given, then applied by one sweep). Rows gives, for row j over the number type T: row(j),
/// gear(j), offset(j), q_a(j), q_b(j), slot_a(j), slot_b(j), dof_a(j), dof_b(j), change(j);
/// velocity() (k entries) and given(dof).
template <class T, class Rows>
void solve_rows(Rows& rows, int count, int k, bool velocity_iteration) {
  T* velocity = rows.velocity();
  for (int j = 0; j < count; ++j) {
    const T gear = rows.gear(j);
    const T error = rows.q_a(j) + gear * rows.q_b(j) + rows.offset(j);
    const T v = velocity[rows.slot_a(j)] + gear * velocity[rows.slot_b(j)];
    const T lambda = impulse(rows.row(j), error, v, velocity_iteration);
    T& a = rows.given(rows.dof_a(j));
    a = a + lambda;
    T& b = rows.given(rows.dof_b(j));
    b = b + gear * lambda;
    const T* change = rows.change(j);
    for (int s = 0; s < k; ++s) velocity[s] = velocity[s] + lambda * change[s];
  }
}

}  // namespace mimic_law

}  // namespace featherdrive
