// PGS drives (spec eq. 1-39) against closed forms, a dense direct solve of the coupled implicit
// step, and conservation of momentum.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>

#include "featherdrive/algorithm/energy.hpp"
#include "featherdrive/algorithm/inverse_mass_diagonal.hpp"
#include "featherdrive/algorithm/kinematics.hpp"
#include "support/drives.hpp"
#include "support/models.hpp"
#include "support/compare.hpp"

namespace featherdrive {
namespace {

using test::kInf;

struct SliderCase {
  DriveType type;
  bool gravity_along_axis;
  int position_iterations;
  int velocity_iterations;
};

// The implicit-Euler recurrence of eq. (9)/(28) for one dof:
//   m (v1 - v0) = tau (kp (xT - x0 - tau v1) + kd (vT - v1)) * (m for acceleration drives)
//                 + tau F_ext,    x1 = x0 + tau v1.
class OneDofPgs : public ::testing::TestWithParam<SliderCase> {};

TEST_P(OneDofPgs, EveryStepEqualsTheImplicitEulerRecurrence) {
  const SliderCase c = GetParam();
  const double m = 2.5, g = 9.81, tau = 1.0 / 60.0, kp = 400.0, kd = 20.0, xT = 0.3, vT = 0.1;
  auto model = test::make_slider(m, Vec3(0, 0, 1),
                                 c.gravity_along_axis ? Vec3(0, 0, -g) : Vec3(0, -g, 0));
  SimulationOptions o;
  o.dt = tau;
  o.position_iterations = c.position_iterations;
  o.velocity_iterations = c.velocity_iterations;
  Simulation sim(model, o);
  sim.set_drive("slide", Drive{c.type, kp, kd, kInf, xT, vT});
  const double F = c.gravity_along_axis ? -m * g : 0.0;
  const double scale = c.type == DriveType::acceleration ? m : 1.0;
  double x = 0.0, v = 0.0;
  for (int k = 0; k < 200; ++k) {
    sim.step();
    const double v1 = (m * v + tau * scale * (kp * (xT - x) + kd * vT) + tau * F) /
                      (m + scale * (tau * tau * kp + tau * kd));
    const double force = scale * (kp * (xT - x - tau * v1) + kd * (vT - v1));
    x += tau * v1;
    v = v1;
    ASSERT_NEAR(sim.q()[0], x, 1e-12) << "step " << k;
    ASSERT_NEAR(sim.qd()[0], v, 1e-12) << "step " << k;
    ASSERT_NEAR(sim.drive_force()[0], force, 1e-9 * (1 + std::abs(force))) << "step " << k;
  }
}

INSTANTIATE_TEST_SUITE_P(
    Drives, OneDofPgs,
    ::testing::Values(SliderCase{DriveType::force, false, 1, 1}, SliderCase{DriveType::force, true, 1, 1},
                      SliderCase{DriveType::acceleration, false, 1, 1},
                      SliderCase{DriveType::acceleration, true, 1, 1},
                      SliderCase{DriveType::force, true, 8, 4},
                      SliderCase{DriveType::acceleration, true, 8, 4},
                      SliderCase{DriveType::force, true, 1, 0}),
    [](const auto& p) {
      return std::string(to_string(p.param.type)) + (p.param.gravity_along_axis ? "_gravity" : "_free") +
             "_" + std::to_string(p.param.position_iterations) + "_" +
             std::to_string(p.param.velocity_iterations);
    });

// The Gauss-Seidel sweep converges on the coupled implicit step
//   (M + tau D + tau^2 K) (v1 - v*) = tau (K (xT - x0 - tau v*) + D (vT - v*)),
// solved here densely.
struct CoupledCase {
  unsigned seed;
  int links;
  bool floating;
};

class CoupledPgs : public ::testing::TestWithParam<CoupledCase> {};

TEST_P(CoupledPgs, ConvergesToTheDirectSolution) {
  const CoupledCase c = GetParam();
  auto model = test::make_random_tree(c.seed, c.links, c.floating, true, 0.01);
  std::mt19937 rng(c.seed);
  const VecX q0 = test::random_configuration(*model, rng);
  const VecX v0 = test::random_vector(model->nv, rng, 1.0);
  const double tau = 1.0 / 60.0;
  // Dense reference.
  Simulation probe(model);
  test::drive_every_joint(probe, rng, 300.0, 15.0);
  MatX K = MatX::Zero(model->nv, model->nv), D = K;
  VecX xT = VecX::Zero(model->nv), vT = xT, x0 = xT;
  for (int j = 0; j < model->nv; ++j) {
    const Drive& d = probe.drive(j);
    if (d.type == DriveType::none) continue;
    K(j, j) = d.stiffness;
    D(j, j) = d.damping;
    xT[j] = d.target_position;
    vT[j] = d.target_velocity;
    x0[j] = q0[model->links[model->dof_link[j]].q_index];
  }
  Data data(*model);
  const MatX M = crba(*model, data, q0);
  const VecX vstar = test::with_classical_root(
      *model, v0, tau, test::free_velocity(*model, q0, v0, VecX::Zero(model->nv), tau));
  const VecX rhs = tau * (K * (xT - x0 - tau * vstar) + D * (vT - vstar));
  const VecX v1 = vstar + (M + tau * D + tau * tau * K).ldlt().solve(rhs);
  double previous = kInf;
  for (int iterations : {1, 4, 16, 64, 256}) {
    SimulationOptions o;
    o.dt = tau;
    o.position_iterations = iterations;
    o.velocity_iterations = 0;
    Simulation sim(model, o);
    for (int j = 0; j < model->nv; ++j) sim.set_drive(j, probe.drive(j));
    sim.set_q(q0);
    sim.set_qd(v0);
    sim.step();
    const VecX v = test::in_start_axes(*model, q0, sim.q(), sim.qd());
    const double error = (v - v1).cwiseAbs().maxCoeff();
    EXPECT_LE(error, previous * 1.0000001 + 1e-13) << iterations << " iterations";
    previous = error;
    if (iterations == 256) {
      EXPECT_LT(error, 1e-9);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Trees, CoupledPgs,
                         ::testing::Values(CoupledCase{1, 4, false}, CoupledCase{2, 8, false},
                                           CoupledCase{3, 12, false}, CoupledCase{4, 6, true},
                                           CoupledCase{5, 10, true}, CoupledCase{6, 16, true}),
                         [](const auto& p) {
                           return "seed" + std::to_string(p.param.seed) + "_n" +
                                  std::to_string(p.param.links) +
                                  (p.param.floating ? "_floating" : "_fixed");
                         });

// On a uniform chain the sweep converges slowly (the rows couple through M^-1, whose conditioning
// grows with the chain's length) but monotonically.
TEST(PgsDrives, ChainConvergesMonotonicallyToTheDirectSolution) {
  auto model = test::make_planar_chain(6, 1.0, 0.4);
  const double tau = 1.0 / 60.0;
  VecX q0(6), xT(6);
  q0 << 0.1, -0.2, 0.3, 0.1, 0.0, -0.4;
  xT << 0.5, 0.4, -0.3, 0.2, 0.1, 0.0;
  Data data(*model);
  const MatX M = crba(*model, data, q0);
  const VecX vstar = test::free_velocity(*model, q0, VecX::Zero(6), VecX::Zero(6), tau);
  const double kp = 1000, kd = 50;
  const MatX A = M + (tau * kd + tau * tau * kp) * MatX::Identity(6, 6);
  const VecX v1 = vstar + A.ldlt().solve(tau * (kp * (xT - q0 - tau * vstar) - kd * vstar));
  double previous = kInf;
  for (int iterations : {1, 4, 16, 64, 256, 1024}) {
    SimulationOptions o;
    o.dt = tau;
    o.position_iterations = iterations;
    o.velocity_iterations = 0;
    Simulation sim(model, o);
    for (int j = 0; j < 6; ++j) sim.set_drive(j, Drive{DriveType::force, kp, kd, kInf, xT[j], 0.0});
    sim.set_q(q0);
    sim.step();
    const double error = (sim.qd() - v1).cwiseAbs().maxCoeff();
    EXPECT_LT(error, previous) << iterations;
    previous = error;
  }
  EXPECT_LT(previous, 1e-9);  // 1024 sweeps
}

// Drive impulses are internal: at the start-of-step configuration, the momentum of the velocity
// after the solver equals that of the free velocity.
TEST(PgsDrives, FloatingTreeDriveImpulsesConserveMomentum) {
  for (unsigned seed : {7u, 8u, 9u}) {
    Model zero_g = *test::make_random_tree(seed, 10, true, true, 0.0);
    zero_g.gravity = Vec3::Zero();
    auto model = std::make_shared<const Model>(zero_g);
    std::mt19937 rng(seed);
    const VecX q0 = test::random_configuration(*model, rng);
    const VecX v0 = test::random_vector(model->nv, rng, 1.0);
    SimulationOptions o;
    o.position_iterations = 4;
    o.velocity_iterations = 2;
    Simulation sim(model, o);
    test::drive_every_joint(sim, rng, 5000.0, 50.0);
    sim.set_q(q0);
    sim.set_qd(v0);
    sim.step();
    const VecX vstar = test::with_classical_root(
        *model, v0, o.dt, test::free_velocity(*model, q0, v0, VecX::Zero(model->nv), o.dt));
    Data data(*model);
    forward_kinematics(*model, data, q0, vstar);
    const Vec6 h_free = momentum(*model, data);
    forward_kinematics(*model, data, q0, test::in_start_axes(*model, q0, sim.q(), sim.qd()));
    const Vec6 h_solved = momentum(*model, data);
    EXPECT_GT(sim.drive_force().cwiseAbs().maxCoeff(), 1.0);  // the drives did act
    EXPECT_LT((h_solved - h_free).norm(), 1e-9 * (1 + h_free.norm())) << "seed " << seed;
  }
}

// Stability: critically damped drives at any stiffness stay finite and settle at the static sag.
TEST(PgsDrives, SliderIsStableAtAnyStiffness) {
  const double m = 2.0, g = 9.81, tau = 1.0 / 60.0, xT = 0.5;
  auto model = test::make_slider(m, Vec3(0, 0, 1), Vec3(0, 0, -g));
  for (double kp = 1e2; kp <= 1e12 * 1.0001; kp *= 10) {
    for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
      SimulationOptions o;
      o.dt = tau;
      o.solver = solver;
      Simulation sim(model, o);
      sim.set_drive("slide", Drive{DriveType::force, kp, 2 * std::sqrt(kp * m), kInf, xT, 0.0});
      for (int k = 0; k < 600; ++k) {
        sim.step();
        ASSERT_TRUE(std::isfinite(sim.q()[0]) && std::isfinite(sim.qd()[0])) << kp << " step " << k;
      }
      if (solver == SolverType::pgs) {
        // Static sag: kp (xT - x) = m g, and the drive holds the weight.
        const double sag = m * g / kp;
        EXPECT_NEAR(sim.q()[0], xT - sag, 1e-9 * (1 + sag)) << "kp " << kp;
        EXPECT_NEAR(sim.qd()[0], 0.0, 1e-9) << "kp " << kp;
        EXPECT_NEAR(sim.drive_force()[0], m * g, 1e-6 * m * g) << "kp " << kp;
      } else {
        // TGS settles on an orbit that repeats every step (gravity enters once per step, the
        // spring over the sub-steps): its fixed point, from the sub-step recurrence.
        const auto orbit = test::tgs_one_dof_orbit(m, kp, 2 * std::sqrt(kp * m), xT, 0.0, -m * g,
                                                   tau, o.position_iterations);
        EXPECT_NEAR(sim.q()[0], orbit.x, 1e-9 * (1 + std::abs(orbit.x))) << "kp " << kp;
        EXPECT_NEAR(sim.qd()[0], orbit.v, 1e-7 * (1 + std::abs(orbit.v))) << "kp " << kp;
      }
    }
  }
}

TEST(PgsDrives, ChainIsStableAtAnyStiffness) {
  auto model = test::make_planar_chain(3, 1.0, 0.5);
  VecX xT(3);
  xT << 0.8, -0.6, 0.4;
  Data data(*model);
  for (double kp = 1e2; kp <= 1e12 * 1.0001; kp *= 10) {
    for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
      SimulationOptions o;
      o.solver = solver;
      o.position_iterations = 32;
      // Without velocity iterations PGS rests with qd = 0 exactly; with them the extra sweep
      // leaves a small velocity that repeats every step while q stays put.
      o.velocity_iterations = solver == SolverType::pgs ? 0 : 1;
      Simulation sim(model, o);
      for (int j = 0; j < 3; ++j) {
        // Critical damping for the dof's own effective inertia 1 / (M^-1)_jj at the target.
        const double r = inverse_mass_diagonal(*model, data, xT)[j];
        sim.set_drive(j, Drive{DriveType::force, kp, 2 * std::sqrt(kp / r), kInf, xT[j], 0.0});
      }
      for (int k = 0; k < 600; ++k) {
        sim.step();
        ASSERT_TRUE(sim.q().allFinite() && sim.qd().allFinite()) << kp << " step " << k;
      }
      // Settled where the static sag allows: kp (xT - q) balances gravity at q, up to what 32
      // sweeps leave unsolved (the rows couple through M^-1; the residual does not shrink with
      // stiffness, docs/math/implicit_drives.md).
      const VecX gravity = rnea(*model, data, sim.q(), VecX::Zero(3), VecX::Zero(3));
      const VecX sag = gravity / kp;
      const double gs_residual = solver == SolverType::pgs ? 5e-5 : 2e-3;
      EXPECT_LT((sim.q() - (xT - sag)).cwiseAbs().maxCoeff(), gs_residual)
          << "kp " << kp << " " << to_string(solver);
      if (solver == SolverType::pgs) {
        // At rest the drives hold the chain's weight exactly, whatever the iteration count.
        EXPECT_LT(sim.qd().cwiseAbs().maxCoeff(), 1e-8) << "kp " << kp;
        EXPECT_LT((sim.drive_force() - gravity).cwiseAbs().maxCoeff(), 1e-6 * gravity.norm())
            << "kp " << kp;
      }
    }
  }
}

TEST(PgsDrives, SaturatedDriveReportsMaxForceAndFollowsConstantForce) {
  const double m = 3.0, tau = 1.0 / 60.0, max_force = 50.0;
  auto model = test::make_slider(m, Vec3(1, 0, 0), Vec3(0, 0, -9.81));
  for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    SimulationOptions o;
    o.dt = tau;
    o.solver = solver;
    Simulation sim(model, o);
    sim.set_drive("slide", Drive{DriveType::force, 1e5, 1e3, max_force, 10.0, 0.0});
    double x = 0.0, v = 0.0;
    for (int k = 0; k < 30; ++k) {  // x stays far below the target
      sim.step();
      v += tau * max_force / m;
      x += tau * v;
      EXPECT_DOUBLE_EQ(sim.drive_force()[0], max_force) << "step " << k;
      EXPECT_NEAR(sim.qd()[0], v, 1e-12);
      if (solver == SolverType::pgs) {
        EXPECT_NEAR(sim.q()[0], x, 1e-12);
      }
    }
    if (solver == SolverType::tgs) {
      // TGS moves the position by sub-steps with the same constant force.
      EXPECT_NEAR(sim.qd()[0], v, 1e-12);
    }
  }
}

TEST(PgsDrives, VelocityDriveReachesItsTarget) {
  auto model = test::make_slider(1.5, Vec3(0, 1, 0), Vec3(0, 0, -9.81));
  Simulation sim(model);
  sim.set_drive("slide", Drive{DriveType::force, 0.0, 30.0, kInf, 0.0, 0.75});
  sim.step(300);
  EXPECT_NEAR(sim.qd()[0], 0.75, 1e-9);
  EXPECT_NEAR(sim.drive_force()[0], 0.0, 1e-6);
}

TEST(PgsDrives, PendulumAtRestReportsGravityTorque) {
  const double m = 1.5, l = 0.6, g = 9.81, kp = 200.0, xT = 1.2;
  auto model = test::make_pendulum(m, l, 1e-3);
  Simulation sim(model);
  sim.set_drive("hinge", Drive{DriveType::force, kp, 30.0, kInf, xT, 0.0});
  sim.step(2000);
  const double x = sim.q()[0];
  const double gravity_torque = m * g * l * std::sin(x);  // holds the bob up at angle x
  EXPECT_NEAR(sim.qd()[0], 0.0, 1e-10);
  EXPECT_NEAR(sim.drive_force()[0], gravity_torque, 1e-8);
  EXPECT_NEAR(xT - x, gravity_torque / kp, 1e-10);
}

}  // namespace
}  // namespace featherdrive
