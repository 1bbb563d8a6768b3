// The stability check (docs/stability_check.md): the one-joint maps against their closed forms.
// The verdict against actual runs is tests/peers/long_runs_test.cpp (the main build's).
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <cstdio>

#include "featherdrive/sim/stability_check.hpp"
#include "support/models.hpp"

namespace featherdrive {
namespace {

// The explicit PD map's eigenvalues from its trace and determinant written out by hand
// (a = h^2 kp / m, b = h kd / m: tr = 2 - a - b, det = 1 - b).
double explicit_radius_closed_form(double a, double b) {
  const double tr = 2.0 - a - b, det = 1.0 - b;
  const std::complex<double> d = std::sqrt(std::complex<double>(tr * tr - 4.0 * det));
  return std::max(std::abs((tr + d) / 2.0), std::abs((tr - d) / 2.0));
}

// A slider of mass m stepped at dt with an undamped ideal PD actuator of stiffness kp.
Simulation undamped_pd_slider(double m, double dt, double kp, ActuatorIntegration integration) {
  SimulationOptions o;
  o.dt = dt;
  Simulation sim(test::make_slider(m, Vec3::UnitX(), Vec3::Zero()), o);
  ExplicitActuator pd;
  pd.kind = ActuatorKind::ideal_pd;
  pd.stiffness = kp;
  pd.integration = integration;
  sim.set_actuator(0, pd);
  sim.set_drive_target(0, 0.1, 0.0);
  return sim;
}

TEST(StabilityCheck, ExplicitMapRadiusMatchesClosedForm) {
  const double m = 2.5, h = 0.01;
  for (double a : {0.01, 0.5, 1.0, 3.0, 3.99, 4.5, 20.0})
    for (double b : {0.0, 0.1, 1.0, 1.9, 2.5}) {
      const Eigen::Matrix2d A = explicit_pd_step_matrix(m, a * m / (h * h), b * m / h, h);
      EXPECT_NEAR(A.trace(), 2.0 - a - b, 1e-12);
      EXPECT_NEAR(A.determinant(), 1.0 - b, 1e-12);
      EXPECT_NEAR(step_spectral_radius(A), explicit_radius_closed_form(a, b), 1e-9)
          << "a " << a << " b " << b;
      // Jury's conditions for a 2x2 map: |det| < 1, |tr| < 1 + det.
      const bool jury = std::abs(1.0 - b) < 1.0 && std::abs(2.0 - a - b) < 2.0 - b;
      if (b > 0.0) {
        EXPECT_EQ(step_spectral_radius(A) < 1.0, jury) << "a " << a << " b " << b;
      }
    }
}

TEST(StabilityCheck, UndampedExplicitPdGoesUnstableAtFour) {
  // Semi-implicit Euler of m x'' = -kp x: det 1, both poles on the unit circle while
  // |tr| = |2 - kp h^2 / m| <= 2, i.e. kp h^2 / m <= 4; beyond, a real pole below -1.
  const double m = 0.7, h = 1.0 / 60.0;
  auto rho = [&](double ratio) {
    return step_spectral_radius(explicit_pd_step_matrix(m, ratio * m / (h * h), 0.0, h));
  };
  EXPECT_NEAR(rho(3.9), 1.0, 1e-12);
  EXPECT_NEAR(rho(4.0 * (1.0 - 1e-6)), 1.0, 1e-9);
  EXPECT_GT(rho(4.0 * (1.0 + 1e-6)), 1.0 + 1e-4);
  // Beyond 4 the poles are real: the larger in modulus is (a - 2 + sqrt(a^2 - 4a)) / 2.
  const double a = 10.0;
  EXPECT_NEAR(rho(a), (a - 2.0 + std::sqrt(a * a - 4.0 * a)) / 2.0, 1e-12);
}

TEST(StabilityCheck, ImplicitDrivesAreStableOverAGrid) {
  for (SolverType solver : {SolverType::pgs, SolverType::tgs})
    for (int n : {1, 4, 8})
      for (double ratio : {1e-3, 0.1, 4.0, 100.0, 1e4, 1e7})
        for (double zeta : {0.0, 0.3, 1.0, 10.0})
          for (DriveType type : {DriveType::force, DriveType::acceleration}) {
            SimulationOptions o;
            o.solver = solver;
            o.position_iterations = n;
            o.dt = 0.01;
            const double m = 3.0, inertia = type == DriveType::acceleration ? 1.0 : m;
            const double kp = ratio * inertia / (o.dt * o.dt);
            Drive d;
            d.type = type;
            d.stiffness = kp;
            d.damping = 2.0 * zeta * std::sqrt(kp * inertia);
            JointGains g;
            g.law = JointLaw::drive;
            g.drive = d;
            EXPECT_LT(step_spectral_radius(joint_step_matrix(m, g, o)), 1.0)
                << to_string(solver) << " " << n << " ratio " << ratio << " zeta " << zeta;
          }
}


TEST(StabilityCheck, FixesOfAnUndampedExplicitPdFollowTheThresholdOfFour) {
  // A 2 kg slider (effective inertia 2, no armature) with an undamped ideal PD at
  // a = kp dt^2 / m = 25: stable with n sub-steps once a / n^2 <= 4 (n = 3), with armature once
  // kp dt^2 / (m + armature) <= 4 (armature = kp dt^2 / 4 - m), never with more damping (at a > 4
  // every kd >= 0 leaves a pole below -1: tr = 2 - a - b < -(1 + det) = -(2 - b)).
  const double m = 2.0, dt = 0.01, a = 25.0, kp = a * m / (dt * dt);
  Simulation sim = undamped_pd_slider(m, dt, kp, ActuatorIntegration::explicit_law);
  const StabilityReport r = check_stability(sim);
  ASSERT_EQ(r.joints.size(), 1u);
  const JointStability& j = r.joints[0];
  EXPECT_EQ(j.law, JointLaw::explicit_pd);
  EXPECT_NEAR(j.mass, m, 1e-12);
  EXPECT_NEAR(j.stiffness_ratio, a, 1e-9);
  EXPECT_FALSE(j.stable);
  EXPECT_EQ(j.substeps, 3);
  EXPECT_NEAR(j.armature, kp * dt * dt / 4.0 - m, 1e-3 * m);
  EXPECT_LT(j.damping, 0.0);  // none
  EXPECT_FALSE(r.stable);
  EXPECT_EQ(r.verdict.rfind("unstable: slide (explicit_pd", 0), 0u) << r.verdict;
  EXPECT_FALSE(r.robot.trial_bounded);  // the run itself diverges
}

TEST(StabilityCheck, TheSameActuatorSolvedImplicitlyIsStable) {
  // The actuator above at a = 25 with integration implicit: its map is one implicit Euler step,
  // A = [1 - h c, h alpha; -c, alpha] with alpha = m / (m + h kd + h^2 kp), c = alpha h kp / m
  // (undamped: complex poles of modulus sqrt(det A) = sqrt(alpha) = 1 / sqrt(1 + a)).
  const double m = 2.0, dt = 0.01, a = 25.0, kp = a * m / (dt * dt);
  Simulation sim = undamped_pd_slider(m, dt, kp, ActuatorIntegration::implicit_law);
  const StabilityReport r = check_stability(sim);
  ASSERT_EQ(r.joints.size(), 1u);
  EXPECT_EQ(r.joints[0].law, JointLaw::implicit_pd);
  EXPECT_NEAR(r.joints[0].rho, 1.0 / std::sqrt(1.0 + a), 1e-12);
  EXPECT_TRUE(r.joints[0].stable);
  EXPECT_TRUE(r.stable) << r.verdict;
  EXPECT_EQ(r.verdict, "stable");
}

}  // namespace
}  // namespace featherdrive
