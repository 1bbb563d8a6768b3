// Helpers for driven simulations in tests.
#pragma once

#include <limits>
#include <random>

#include "featherdrive/algorithm/crba.hpp"
#include "featherdrive/algorithm/rnea.hpp"
#include "featherdrive/sim/simulation.hpp"

namespace featherdrive::test {

/// v* = v + dt M^-1 (tau - c + g), from CRBA and RNEA (independent of ABA and of the step).
inline VecX free_velocity(const Model& model, const VecX& q, const VecX& v, const VecX& tau,
                          double dt) {
  Data data(model);
  const VecX bias = rnea(model, data, q, v, VecX::Zero(model.nv));
  const MatX M = crba(model, data, q);
  return v + dt * M.ldlt().solve(tau - bias);
}

/// The step's free velocity of a floating root with compat none (docs/math/contact.md, C26):
/// its body-frame linear velocity gains dt (omega_b x v_b) of the step's start.
inline VecX with_classical_root(const Model& model, const VecX& v0, double dt, VecX vstar) {
  if (model.floating_base())
    vstar.segment<3>(3) += dt * Vec3(v0.head<3>()).cross(Vec3(v0.segment<3>(3)));
  return vstar;
}

/// A step's end velocity with a floating root's linear part in the root's axes at the step's
/// start (q0) instead of its end (q1): C28 undone.
inline VecX in_start_axes(const Model& model, const VecX& q0, const VecX& q1, VecX qd1) {
  if (!model.floating_base()) return qd1;
  auto R = [](const VecX& q) { return Quat(q[3], q[4], q[5], q[6]).normalized().toRotationMatrix(); };
  qd1.segment<3>(3) = R(q0).transpose() * (R(q1) * qd1.segment<3>(3));
  return qd1;
}

/// Puts a force drive with random targets on every revolute and prismatic dof.
inline void drive_every_joint(Simulation& sim, std::mt19937& rng, double kp, double kd,
                              DriveType type = DriveType::force) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (const Link& l : sim.model().links)
    if (l.joint_type == JointType::revolute || l.joint_type == JointType::prismatic)
      sim.set_drive(l.v_index, Drive{type, kp, kd, std::numeric_limits<double>::infinity(),
                                     u(rng), 0.5 * u(rng)});
}

/// One TGS step of a 1-dof slider (mass m, constant force F along the axis), written from the spec:
/// the free velocity once, then n implicit-Euler sub-steps of rho = tau / n towards the interpolated
/// target x_T - (tau - i rho) v_T (eq. 41-44). Returns the accumulated impulse.
struct OneDofState {
  double x, v;
};
inline double tgs_one_dof_step(OneDofState& s, double m, double kp, double kd, double xT,
                               double vT, double F, double tau, int n, bool acceleration = false) {
  const double rho = tau / n, scale = acceleration ? m : 1.0;
  s.v += tau * F / m;
  double impulse = 0.0;
  for (int i = 1; i <= n; ++i) {
    const double target = xT - (tau - i * rho) * vT;
    const double v1 = (m * s.v + rho * scale * (kp * (target - s.x) + kd * vT)) /
                      (m + scale * (rho * rho * kp + rho * kd));
    impulse += m * (v1 - s.v);
    s.v = v1;
    s.x += rho * v1;
  }
  return impulse;
}

/// The state TGS repeats every step for a constant target, found by iterating the recurrence.
inline OneDofState tgs_one_dof_orbit(double m, double kp, double kd, double xT, double vT,
                                     double F, double tau, int n) {
  OneDofState s{xT, 0.0};
  for (int k = 0; k < 20000; ++k) tgs_one_dof_step(s, m, kp, kd, xT, vT, F, tau, n);
  return s;
}

/// The benchmark chain's drives (kp 1000, kd 50) towards targets uniform in +-0.5 rad, drawn from
/// the seed 42 + nv; returns the targets.
inline VecX drive_benchmark_chain(Simulation& sim) {
  std::mt19937 rng(42u + static_cast<unsigned>(sim.model().nv));
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  VecX target(sim.model().nv);
  for (int d = 0; d < sim.model().nv; ++d) {
    target[d] = u(rng);
    sim.set_drive(d, Drive{DriveType::force, 1000.0, 50.0,
                           std::numeric_limits<double>::infinity(), target[d], 0.0});
  }
  return target;
}

}  // namespace featherdrive::test
