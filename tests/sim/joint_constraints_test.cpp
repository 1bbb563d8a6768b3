// Limits, friction, velocity limits, actuator envelopes and armature, in PGS and TGS, against
// closed forms (docs/math/joint_constraints.md).
#include <gtest/gtest.h>

#include <cmath>

#include "featherdrive/sim/simulation.hpp"
#include "support/models.hpp"
#include "support/compare.hpp"

namespace featherdrive {
namespace {

using test::kInf;

class BothSolvers : public ::testing::TestWithParam<SolverType> {
 protected:
  SimulationOptions options(int position_iterations = 4, int velocity_iterations = 1) const {
    SimulationOptions o;
    o.solver = GetParam();
    o.position_iterations = position_iterations;
    o.velocity_iterations = velocity_iterations;
    return o;
  }
};

TEST_P(BothSolvers, DrivenSliderRestsAtItsLimit) {
  const double m = 2.0;
  auto model = test::make_slider(m, Vec3(1, 0, 0), Vec3(0, 0, -9.81));  // gravity across the axis
  for (double upper : {0.25, 0.5}) {
    Simulation sim(model, options());
    sim.set_joint_limits("slide", -0.5, upper);
    sim.set_drive("slide", Drive{DriveType::force, 2000.0, 100.0, kInf, 1.0, 0.0});  // beyond it
    double worst = -kInf;
    for (int k = 0; k < 100; ++k) {
      sim.step();
      worst = std::max(worst, sim.q()[0] - upper);
    }
    EXPECT_LT(sim.q()[0] - upper, 1e-6);
    EXPECT_GT(sim.q()[0] - upper, -1e-6);
    EXPECT_LT(worst, 1e-2);  // never far past it, even while arriving
    // At rest, the limit holds the drive. (How far the drive force gets towards
    // kp (xT - upper) depends on the iteration count: the drive row converges at the rate 1 - x
    // of eq. (22) while the limit holds the velocity.)
    EXPECT_GT(sim.drive_force()[0], 0.5 * 2000.0 * (1.0 - upper));
    EXPECT_LE(sim.drive_force()[0], 2000.0 * (1.0 - upper) * (1 + 1e-9));
    EXPECT_NEAR(sim.drive_force()[0] + sim.limit_force()[0], 0.0, 1e-6 * sim.drive_force()[0]);
    EXPECT_NEAR(sim.qd()[0], 0.0, 1e-9);
  }
}

TEST_P(BothSolvers, LowerLimitHoldsAFallingSlider) {
  const double m = 1.5, g = 9.81;
  auto model = test::make_slider(m, Vec3(0, 0, 1), Vec3(0, 0, -g));
  Simulation sim(model, options());
  sim.set_joint_limits("slide", -0.3, 1.0);
  sim.step(120);
  EXPECT_NEAR(sim.q()[0], -0.3, 1e-6);
  EXPECT_NEAR(sim.limit_force()[0], m * g, 1e-6 * m * g);
}

TEST_P(BothSolvers, StaticFrictionHoldsAPendulumBelowItsThreshold) {
  const double m = 1.0, l = 0.5, g = 9.81, angle = 0.4;
  auto model = test::make_pendulum(m, l, 1e-3);
  const double gravity_torque = m * g * l * std::sin(angle);
  for (double factor : {1.2, 0.8}) {
    Simulation sim(model, options());
    sim.set_joint_friction("hinge", JointFriction{factor * gravity_torque, 0.5 * gravity_torque, 0.0});
    VecX q(1);
    q << angle;
    sim.set_q(q);
    sim.step(60);
    if (factor > 1.0) {
      EXPECT_EQ(sim.q()[0], angle);  // held: not a bit of motion
      EXPECT_EQ(sim.qd()[0], 0.0);
      EXPECT_NEAR(sim.friction_force()[0], gravity_torque, 1e-9);
    } else {
      EXPECT_LT(sim.q()[0], angle - 0.05);  // slips and swings down
    }
  }
}

// A slider on a level table launched at v0 with dynamic friction F slows at F / m until it stops:
// the semi-implicit recurrence v_{k+1} = max(v_k - dt F / m, 0), x_{k+1} = x_k + dt v_{k+1}.
TEST_P(BothSolvers, DynamicFrictionMatchesTheConstantForceClosedForm) {
  const double m = 2.0, F = 3.0, v0 = 1.2, dt = 1.0 / 60.0;
  auto model = test::make_slider(m, Vec3(1, 0, 0), Vec3(0, 0, -9.81));
  Simulation sim(model, options());
  sim.set_joint_friction("slide", JointFriction{F, F, 0.0});
  VecX qd(1);
  qd << v0;
  sim.set_qd(qd);
  double x = 0.0, v = v0;
  for (int k = 0; k < 80; ++k) {
    sim.step();
    v = std::max(v - dt * F / m, 0.0);
    if (GetParam() == SolverType::pgs) x += dt * v;
    EXPECT_NEAR(sim.qd()[0], v, 1e-12) << "step " << k;
    if (GetParam() == SolverType::pgs) {
      EXPECT_NEAR(sim.q()[0], x, 1e-12) << "step " << k;
    }
    if (v > 0.0) {
      EXPECT_NEAR(sim.friction_force()[0], -F, 1e-9) << "step " << k;
    }
  }
  EXPECT_EQ(sim.qd()[0], 0.0);  // stopped, and stays stopped
  // Distance of the closed form's staircase: sum of dt v_k, the same for TGS's sub-steps of a
  // constant velocity.
  if (GetParam() == SolverType::tgs) {
    double distance = 0.0, w = v0;
    while (w > 0.0) {
      w = std::max(w - dt * F / m, 0.0);
      distance += dt * w;
    }
    EXPECT_NEAR(sim.q()[0], distance, 1e-12);
  }
}

TEST_P(BothSolvers, ViscousFrictionOpposesMotionInProportion) {
  const double m = 1.0, c = 4.0, v0 = 2.0, dt = 1.0 / 60.0;
  auto model = test::make_slider(m, Vec3(1, 0, 0), Vec3(0, 0, -9.81));
  Simulation sim(model, options(16, 1));  // the bound is explicit in v; iterations converge it
  sim.set_joint_friction("slide", JointFriction{0.0, 0.0, c});
  VecX qd(1);
  qd << v0;
  sim.set_qd(qd);
  sim.step();
  // Bounded by the viscous impulse c |v| dt at the velocity the row leaves: after the friction
  // row the joint has v1 = v0 - dt c v1 / m, i.e. v1 = v0 / (1 + dt c / m).
  EXPECT_NEAR(sim.qd()[0], v0 / (1 + dt * c / m), 1e-12);
}

TEST_P(BothSolvers, MaxJointVelocityIsNeverExceeded) {
  auto model = test::make_slider(1.0, Vec3(1, 0, 0), Vec3(0, 0, -9.81));
  Simulation sim(model, options());
  sim.set_max_joint_velocity("slide", 0.7);
  VecX f(1);
  f << 500.0;
  sim.set_applied_force(f);
  for (int k = 0; k < 100; ++k) {
    sim.step();
    ASSERT_LE(std::abs(sim.qd()[0]), 0.7 + 1e-12) << "step " << k;
  }
  EXPECT_NEAR(sim.qd()[0], 0.7, 1e-12);
}

// Velocities above their limits at the start of a step are scaled down together, keeping the
// direction of motion (PhysX 5.6.1). Two orthogonal sliders in series have a constant, diagonal
// M and no velocity-product terms, so without gravity the step keeps the scaled velocities.
TEST_P(BothSolvers, VelocitiesAboveTheirLimitsAreScaledTogether) {
  ModelBuilder b;
  b.set_gravity(Vec3::Zero());
  b.add_link(make_link("base", "", 1.0, Vec3::Zero(), Mat3::Identity() * 0.01, fixed_joint("fix")));
  b.add_link(make_link("a", "base", 1.0, Vec3::Zero(), Mat3::Identity() * 0.01,
                       prismatic_joint("x", Vec3::UnitX())));
  b.add_link(make_link("b", "a", 2.0, Vec3::Zero(), Mat3::Identity() * 0.01,
                       prismatic_joint("y", Vec3::UnitY())));
  Simulation sim(std::make_shared<const Model>(b.build()), options());
  sim.set_max_joint_velocity("x", 2.0);
  VecX qd(2);
  qd << 3.0, -1.5;  // x is 1.5 times over its limit; y has none
  sim.set_qd(qd);
  sim.step();
  EXPECT_NEAR(sim.qd()[0], 2.0, 1e-15);
  EXPECT_NEAR(sim.qd()[1], -1.0, 1e-15);
}

// Envelope, speed-effort curve |v| <= v_max - gradient |E|: a velocity drive asking for more
// than the motor can give against a load L settles where the curve meets the load:
// v = v_max - gradient L.
TEST_P(BothSolvers, EnvelopeSpeedEffortGradientSetsTheSteadySpeed) {
  const double m = 2.0, g = 9.81, L = m * g, v_max = 1.5, gradient = 0.02;
  auto model = test::make_slider(m, Vec3(0, 0, 1), Vec3(0, 0, -g));
  Simulation sim(model, options());
  sim.set_drive("slide", Drive{DriveType::force, 0.0, 500.0, kInf, 0.0, 5.0});
  sim.set_actuator_envelope("slide", ActuatorEnvelope{100.0, v_max, gradient, 0.0});
  sim.step(400);
  EXPECT_NEAR(sim.qd()[0], v_max - gradient * L, 1e-6);
  EXPECT_NEAR(sim.drive_force()[0], L, 1e-4 * L);
}

// Envelope, effort-speed curve |E| <= E_max - resistance |v|: the steady speed against a load L
// is v = (E_max - L) / resistance.
TEST_P(BothSolvers, EnvelopeVelocityDependentResistanceSetsTheSteadySpeed) {
  const double m = 2.0, g = 9.81, L = m * g, e_max = 30.0, resistance = 8.0;
  auto model = test::make_slider(m, Vec3(0, 0, 1), Vec3(0, 0, -g));
  Simulation sim(model, options());
  sim.set_drive("slide", Drive{DriveType::force, 0.0, 500.0, kInf, 0.0, 5.0});
  sim.set_actuator_envelope("slide", ActuatorEnvelope{e_max, kInf, 0.0, resistance});
  sim.step(400);
  EXPECT_NEAR(sim.qd()[0], (e_max - L) / resistance, 1e-6);
}

TEST_P(BothSolvers, EnvelopeCapsTheEffortAtStandstill) {
  auto model = test::make_slider(1.0, Vec3(1, 0, 0), Vec3(0, 0, -9.81));
  Simulation sim(model, options());
  sim.set_drive("slide", Drive{DriveType::force, 1e4, 100.0, kInf, 1.0, 0.0});
  sim.set_actuator_envelope("slide", ActuatorEnvelope{20.0, kInf, 0.0, 0.0});
  sim.step();
  EXPECT_NEAR(sim.drive_force()[0], 20.0, 1e-9);
}

INSTANTIATE_TEST_SUITE_P(Solvers, BothSolvers, ::testing::Values(SolverType::pgs, SolverType::tgs),
                         [](const auto& p) { return std::string(to_string(p.param)); });

// Armature enters the unit response: the small-angle period becomes 2 pi sqrt((I + a) / (m g l)).
TEST(Armature, PendulumPeriodIncludesArmature) {
  const double m = 1.0, l = 0.6, Ic = 2e-3, g = 9.81, armature = 0.15;
  ModelBuilder b;
  b.add_link(make_link("base", "", 1.0, Vec3::Zero(), Mat3::Identity() * 1e-2, fixed_joint("fix")));
  JointSpec hinge = revolute_joint("hinge", Vec3::UnitY());
  hinge.armature = {armature};
  b.add_link(make_link("bob", "base", m, Vec3(0, 0, -l), Mat3::Identity() * Ic, hinge));
  auto model = std::make_shared<const Model>(b.build());
  SimulationOptions o;
  o.dt = 1e-4;
  Simulation sim(model, o);
  VecX q(1);
  q << 1e-3;
  sim.set_q(q);
  const double expected = 2 * M_PI * std::sqrt((Ic + m * l * l + armature) / (m * g * l));
  std::vector<double> crossings;
  double prev = sim.q()[0];
  while (sim.time() < 5.0 * expected) {
    sim.step();
    const double now = sim.q()[0];
    if (prev < 0.0 && now >= 0.0) crossings.push_back(sim.time() - o.dt * now / (now - prev));
    prev = now;
  }
  const double period = (crossings.back() - crossings.front()) / (crossings.size() - 1);
  EXPECT_NEAR(period / expected, 1.0, 1e-3);
}

}  // namespace
}  // namespace featherdrive
