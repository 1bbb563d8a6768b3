// TGS drives (spec eq. 40-45): sub-steps against implicit-Euler recurrences, frozen impulses in the
// velocity iterations, and convergence to the frozen-inertia spring-damper ODE.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <cstdio>

#include "support/drives.hpp"
#include "support/models.hpp"
#include "support/compare.hpp"

namespace featherdrive {
namespace {

using test::kInf;

TEST(TgsDrives, OneDofEqualsImplicitEulerSubsteps) {
  const double m = 1.7, tau = 1.0 / 60.0, kp = 900.0, kd = 12.0;
  auto model = test::make_slider(m, Vec3(0, 1, 0), Vec3(0, 0, -9.81));  // gravity across the axis
  for (DriveType type : {DriveType::force, DriveType::acceleration}) {
    for (int n : {1, 2, 4, 8, 32}) {
      SimulationOptions o;
      o.dt = tau;
      o.solver = SolverType::tgs;
      o.position_iterations = n;
      o.velocity_iterations = 0;
      Simulation sim(model, o);
      test::OneDofState s{0.0, 0.0};
      for (int k = 0; k < 200; ++k) {
        // A moving target, sampled at the end of each step.
        const double t = (k + 1) * tau;
        const double xT = 0.4 * std::sin(3.0 * t), vT = 1.2 * std::cos(3.0 * t);
        sim.set_drive("slide", Drive{type, kp, kd, kInf, xT, vT});
        sim.step();
        const double impulse = test::tgs_one_dof_step(s, m, kp, kd, xT, vT, 0.0, tau, n,
                                                      type == DriveType::acceleration);
        ASSERT_NEAR(sim.q()[0], s.x, 1e-12) << to_string(type) << " n " << n << " step " << k;
        ASSERT_NEAR(sim.qd()[0], s.v, 1e-12) << to_string(type) << " n " << n << " step " << k;
        ASSERT_NEAR(sim.drive_force()[0], impulse / tau, 1e-9 * (1 + std::abs(impulse / tau)));
      }
    }
  }
}

TEST(TgsDrives, VelocityIterationsDoNotChangeTheDriveForce) {
  auto model = test::make_planar_chain(4, 1.0, 0.4);
  std::vector<VecX> forces, positions, velocities;
  for (int velocity_iterations : {1, 8}) {
    SimulationOptions o;
    o.solver = SolverType::tgs;
    o.position_iterations = 4;
    o.velocity_iterations = velocity_iterations;
    Simulation sim(model, o);
    std::mt19937 rng(4);
    test::drive_every_joint(sim, rng, 2000.0, 40.0);
    sim.step(60);
    forces.push_back(sim.drive_force());
    positions.push_back(sim.q());
    velocities.push_back(sim.qd());
  }
  EXPECT_GT(forces[0].cwiseAbs().maxCoeff(), 1.0);
  EXPECT_EQ(forces[0], forces[1]);
  EXPECT_EQ(positions[0], positions[1]);
  EXPECT_EQ(velocities[0], velocities[1]);
}

// What the sub-steps integrate: over one step, with M and the bias frozen at the start,
//   M0 dv/dt = K (x_T(t) - x) + D (v_T - v),  dx/dt = v,  x_T(t) = x_T - (tau - t) v_T,
// from x0 and the free velocity v*. Integrated finely with RK4.
TEST(TgsDrives, StepApproachesTheFrozenInertiaOde) {
  auto model = test::make_planar_chain(4, 1.0, 0.4);
  const int nv = model->nv;
  const double tau = 1.0 / 60.0, kp = 100.0, kd = 4.0;
  VecX q0(nv), v0(nv), xT(nv), vT(nv);
  q0 << 0.2, -0.3, 0.4, 0.1;
  v0 << 0.5, -0.2, 0.1, 0.3;
  xT << 0.6, 0.2, -0.1, 0.3;
  vT << 0.4, -0.3, 0.2, 0.1;
  Data data(*model);
  const MatX M = crba(*model, data, q0);
  const Eigen::LDLT<MatX> Mf(M);
  const VecX vstar = test::free_velocity(*model, q0, v0, VecX::Zero(nv), tau);
  auto rhs = [&](double t, const VecX& x, const VecX& v) {
    return VecX(Mf.solve(kp * (xT - (tau - t) * vT - x) + kd * (vT - v)));
  };
  VecX x = q0, v = vstar;
  const int fine = 20000;
  const double h = tau / fine;
  for (int k = 0; k < fine; ++k) {
    const double t = k * h;
    const VecX k1x = v, k1v = rhs(t, x, v);
    const VecX k2x = v + 0.5 * h * k1v, k2v = rhs(t + 0.5 * h, x + 0.5 * h * k1x, v + 0.5 * h * k1v);
    const VecX k3x = v + 0.5 * h * k2v, k3v = rhs(t + 0.5 * h, x + 0.5 * h * k2x, v + 0.5 * h * k2v);
    const VecX k4x = v + h * k3v, k4v = rhs(t + h, x + h * k3x, v + h * k3v);
    x += h / 6 * (k1x + 2 * k2x + 2 * k3x + k4x);
    v += h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v);
  }
  std::vector<double> errors;
  for (int n : {1, 2, 4, 8, 16, 32, 64, 128, 256, 512, 1024}) {
    SimulationOptions o;
    o.dt = tau;
    o.solver = SolverType::tgs;
    o.position_iterations = n;
    o.velocity_iterations = 0;
    Simulation sim(model, o);
    for (int j = 0; j < nv; ++j) sim.set_drive(j, Drive{DriveType::force, kp, kd, kInf, xT[j], vT[j]});
    sim.set_q(q0);
    sim.set_qd(v0);
    sim.step();
    const double e = std::max((sim.q() - x).cwiseAbs().maxCoeff() / tau,
                              (sim.qd() - v).cwiseAbs().maxCoeff());
    errors.push_back(e);
    std::printf("TGS n = %3d: max(|q - q_ode| / tau, |qd - qd_ode|) = %.3e\n", n, e);
  }
  for (size_t i = 1; i < errors.size(); ++i) {
    EXPECT_LT(errors[i], errors[i - 1]);
    const double order = std::log2(errors[i - 1] / errors[i]);
    if (i >= 4) {  // asymptotically first order (implicit Euler sub-steps)
      EXPECT_NEAR(order, 1.0, 0.15) << "between n = " << (1 << (i - 1)) << " and " << (1 << i);
    }
  }
  EXPECT_LT(errors.back(), 2e-3 * errors.front());
}

}  // namespace
}  // namespace featherdrive
