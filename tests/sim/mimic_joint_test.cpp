// Mimic joints and revolute wrap (issue 17) against closed forms: the rigid row held to 1e-9,
// a gear pair's momentum exchange (the momentum the row cannot change is conserved), the soft
// row's natural frequency and damping ratio measured from a free response, PhysX's wrap rule.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "featherdrive/model/model_builder.hpp"
#include "featherdrive/sim/simulation.hpp"
#include "support/compare.hpp"
#include "support/models.hpp"

namespace featherdrive::mimic_joint_test {
namespace {

constexpr double kPi = std::numbers::pi;

// Two wheels about parallel z axes on a fixed base, centres of mass on their axes: M is
// diag(inertia_a, inertia_b) whatever q, and gravity does not turn them.
std::shared_ptr<const Model> two_wheels(double inertia_a, double inertia_b) {
  ModelBuilder b;
  b.add_link(make_link("base", "", 1.0, Vec3::Zero(), test::box_inertia(1.0, Vec3(0.1, 0.1, 0.1)),
                       fixed_joint("fix")));
  b.add_link(make_link("a", "base", 1.0, Vec3::Zero(),
                       Vec3(0.6 * inertia_a, 0.6 * inertia_a, inertia_a).asDiagonal(),
                       revolute_joint("wheel_a", Vec3::UnitZ(), Vec3(0.2, 0, 0))));
  b.add_link(make_link("b", "base", 1.0, Vec3::Zero(),
                       Vec3(0.6 * inertia_b, 0.6 * inertia_b, inertia_b).asDiagonal(),
                       revolute_joint("wheel_b", Vec3::UnitZ(), Vec3(-0.2, 0, 0))));
  return std::make_shared<const Model>(b.build());
}

// Two pendulum branches under gravity, the second with a link below it: the rows couple dofs
// in different branches and a dof with a child.
std::shared_ptr<const Model> two_branches() {
  ModelBuilder b;
  b.set_gravity(Vec3(0, 0, -9.81));
  b.add_link(make_link("base", "", 1.0, Vec3::Zero(), test::box_inertia(1.0, Vec3(0.1, 0.1, 0.1)),
                       fixed_joint("fix")));
  b.add_link(make_link("arm", "base", 1.0, Vec3(0, 0, -0.25),
                       test::box_inertia(1.0, Vec3(0.05, 0.05, 0.5)),
                       revolute_joint("leader", Vec3::UnitY(), Vec3(0.3, 0, 0))));
  b.add_link(make_link("jaw", "base", 0.6, Vec3(0, 0, -0.15),
                       test::box_inertia(0.6, Vec3(0.04, 0.04, 0.3)),
                       revolute_joint("follower", Vec3::UnitY(), Vec3(-0.3, 0, 0))));
  b.add_link(make_link("tip", "jaw", 0.3, Vec3(0, 0, -0.1),
                       test::box_inertia(0.3, Vec3(0.03, 0.03, 0.2)),
                       prismatic_joint("tip_slide", Vec3::UnitZ(), Vec3(0, 0, -0.3))));
  return std::make_shared<const Model>(b.build());
}

double mimic_error(const Simulation& sim, const MimicJoint& m) {
  const Model& model = sim.model();
  return sim.q()[model.links[model.dof_link[m.dof_a]].q_index] +
         m.gear_ratio * sim.q()[model.links[model.dof_link[m.dof_b]].q_index] + m.offset;
}

// The rigid row under a drive tracking a sine, gravity and a limit that the row drives the
// follower into: PGS's iterations converge on the coupled rows, TGS with the row alone.
TEST(MimicJoint, RigidRowHeldUnderDrivesGravityAndLimits) {
  auto model = two_branches();
  for (const SolverType type : {SolverType::pgs, SolverType::tgs}) {
    SimulationOptions o;
    o.solver = type;
    o.position_iterations = type == SolverType::pgs ? 64 : 8;
    o.velocity_iterations = 4;
    Simulation sim(model, o);
    const MimicJoint m{model->dof_index("follower"), model->dof_index("leader"), -1.5, 0.05};
    sim.set_mimic_joints({m});
    VecX q = sim.q();
    q[model->dof_index("leader")] = 0.1;
    q[model->dof_index("follower")] = 1.5 * 0.1 - 0.05;  // on the constraint
    sim.set_q(q);
    if (type == SolverType::pgs) {
      sim.set_drive("leader", Drive{DriveType::force, 40.0, 2.0, test::kInf, 0.0, 0.0});
      sim.set_joint_limits("follower", -0.4, 0.5);
      sim.set_drive("tip_slide", Drive{DriveType::force, 100.0, 5.0, test::kInf, 0.05, 0.0});
    }
    double worst = 0.0, lowest = 0.0;
    for (int k = 0; k < 240; ++k) {
      if (type == SolverType::pgs)
        sim.set_drive_target("leader", 0.6 * std::sin(2.0 * k * o.dt),
                             1.2 * std::cos(2.0 * k * o.dt));
      sim.step();
      worst = std::max(worst, std::abs(mimic_error(sim, m)));
      lowest = std::min(lowest, sim.q()[model->dof_index("follower")]);
    }
    std::printf("%s: largest |C| %.2e, lowest follower %.4f\n", to_string(type), worst, lowest);
    EXPECT_LT(worst, 1e-9);
    if (type == SolverType::pgs) EXPECT_LT(lowest, -0.39);  // the limit was reached
  }
}

// Gear pair a + G b = 0, wheel a spinning at w0 and b at rest, then a torque tau on a. The row's
// impulses (lambda, G lambda) leave G I_a w_a - I_b w_b to tau alone: d/dt = G tau. With
// w_b = -w_a / G: w_a(t) = G^2 (I_a w0 + tau t) / (G^2 I_a + I_b).
TEST(MimicJoint, GearPairExchangesMomentumAsTheClosedForm) {
  const double Ia = 0.05, Ib = 0.2, G = -2.0, w0 = 3.0, tau = 0.4;
  auto model = two_wheels(Ia, Ib);
  SimulationOptions o;
  o.dt = 0.01;
  Simulation sim(model, o);
  const int a = model->dof_index("wheel_a"), b = model->dof_index("wheel_b");
  sim.set_mimic_joints({{a, b, G, 0.0}});
  VecX qd = VecX::Zero(2);
  qd[a] = w0;
  sim.set_qd(qd);
  VecX force = VecX::Zero(2);
  force[a] = tau;
  sim.set_applied_force(force);
  double worst = 0.0;
  for (int k = 1; k <= 100; ++k) {
    sim.step();
    const double expected = G * G * (Ia * w0 + tau * k * o.dt) / (G * G * Ia + Ib);
    worst =
        std::max({worst, std::abs(sim.qd()[a] - expected), std::abs(sim.qd()[b] + expected / G)});
  }
  std::printf("gear pair: largest velocity error %.2e\n", worst);
  EXPECT_LT(worst, 1e-12);
}

// The soft row is PhysX's implicit spring-damper on the effective mass 1 / r: with one position
// iteration and no velocity iteration (which would solve it rigid), the free response of C has
// natural frequency omega_n and damping ratio zeta. Measured from two successive downward zero
// crossings (the damped period) and the decay between the two peaks after them.
TEST(MimicJoint, SoftRowHasItsNaturalFrequencyAndDampingRatio) {
  const double omega = 10.0, zeta = 0.2;
  auto model = two_wheels(0.05, 0.2);
  SimulationOptions o;
  o.dt = 1e-4;
  o.position_iterations = 1;
  o.velocity_iterations = 0;
  Simulation sim(model, o);
  const MimicJoint m{0, 1, 0.5, 0.0, omega, zeta};
  sim.set_mimic_joints({m});
  VecX q = VecX::Zero(2);
  q[0] = 0.1;  // C(0) = 0.1
  sim.set_q(q);
  std::vector<double> down, peaks;  // zero-crossing times, peak values after the first crossing
  double previous = mimic_error(sim, m), before = previous;
  for (int k = 1; k <= 20000 && down.size() < 3; ++k) {
    sim.step();
    const double c = mimic_error(sim, m);
    if (previous > 0.0 && c <= 0.0) down.push_back((k - c / (c - previous)) * o.dt);
    if (!down.empty() && previous > before && previous >= c) peaks.push_back(previous);
    before = previous;
    previous = c;
  }
  ASSERT_EQ(down.size(), 3u);
  ASSERT_GE(peaks.size(), 2u);
  const double period = down[2] - down[1];
  const double sigma = std::log(peaks[0] / peaks[1]) / period;  // zeta omega_n
  const double omega_d = 2.0 * kPi / period;
  const double omega_n = std::hypot(omega_d, sigma);
  std::printf("soft row: omega_n %.5f (%.5f), zeta %.5f (%.5f)\n", omega_n, omega, sigma / omega_n,
              zeta);
  EXPECT_NEAR(omega_n, omega, 0.01 * omega);
  EXPECT_NEAR(sigma / omega_n, zeta, 0.01 * zeta);
}

// PhysX's eREVOLUTE (propagateLinksDown, computeAndEnforceJointPositions): 6.344 becomes -6.222.
TEST(RevoluteWrap, PhysxRule) {
  EXPECT_NEAR(wrap_revolute_position(6.344), 6.344 - 4.0 * kPi, 1e-15);
  EXPECT_NEAR(wrap_revolute_position(6.344), -6.222, 1e-3);
  EXPECT_EQ(wrap_revolute_position(-7.0), -7.0 + 4.0 * kPi);
  EXPECT_EQ(wrap_revolute_position(2.0 * kPi), 2.0 * kPi);  // not past 2 pi
  EXPECT_EQ(wrap_revolute_position(1.0), 1.0);
  EXPECT_EQ(wrap_revolute_position(30.0), 4.0 * kPi);  // one turn back, then clamped
  EXPECT_EQ(parse_revolute_wrap("wrapped"), RevoluteWrap::wrapped);
  EXPECT_THROW(parse_revolute_wrap("wrap"), std::invalid_argument);
}

// A free wheel at 5 rad/s: wrapped, q is the unwrapped position brought back by 4 pi whenever it
// passes 2 pi; the velocities are the same bits. Compat physx wraps by default.
TEST(RevoluteWrap, FreeWheelWrapsEveryTwoTurnsAndKeepsItsVelocity) {
  auto model = two_wheels(0.05, 0.2);
  Simulation unwrapped(model), wrapped(model);
  wrapped.set_revolute_wrap("wheel_a", RevoluteWrap::wrapped);
  EXPECT_EQ(unwrapped.revolute_wrap(0), RevoluteWrap::unwrapped);
  VecX qd = VecX::Constant(2, 5.0);
  unwrapped.set_qd(qd);
  wrapped.set_qd(qd);
  int wraps = 0;
  for (int k = 0; k < 600; ++k) {
    unwrapped.step();
    const double before = wrapped.q()[0];
    wrapped.step();
    wraps += wrapped.q()[0] < before;
    EXPECT_LE(std::abs(wrapped.q()[0]), 2.0 * kPi);
    EXPECT_NEAR(wrapped.q()[0] + 4.0 * kPi * wraps, unwrapped.q()[0], 1e-12);
    EXPECT_EQ(wrapped.q()[1], unwrapped.q()[1]);  // wheel_b stays unwrapped
    ASSERT_TRUE(test::same_bits(wrapped.qd(), unwrapped.qd()));
  }
  EXPECT_EQ(wraps, 4);  // 50 rad: past 2 pi, 6 pi, 10 pi and 14 pi
  SimulationOptions physx;
  physx.compat = Compat::physx;
  EXPECT_EQ(Simulation(model, physx).revolute_wrap(0), RevoluteWrap::wrapped);
}

TEST(MimicJoint, BadRowsGiveOneLineErrorsAndChangeNothing) {
  auto model = two_branches();
  Simulation sim(model);
  const int leader = model->dof_index("leader"), follower = model->dof_index("follower"),
            tip = model->dof_index("tip_slide");
  auto message = [&](const std::vector<MimicJoint>& rows) -> std::string {
    try {
      sim.set_mimic_joints(rows);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(message({{follower, follower, 1.0, 0.0}}).find("cannot mimic itself"),
            std::string::npos);
  EXPECT_NE(message({{follower, leader, 0.0, 0.0}}).find("gear_ratio = 0"), std::string::npos);
  EXPECT_NE(message({{follower, leader, std::nan(""), 0.0}}).find("gear_ratio = nan"),
            std::string::npos);
  EXPECT_NE(
      message({{follower, leader, 1.0, 0.0}, {tip, follower, 1.0, 0.0}, {leader, tip, 1.0, 0.0}})
          .find("closes a cycle"),
      std::string::npos);
  EXPECT_NE(message({{follower, 7, 1.0, 0.0}}).find("out of range"), std::string::npos);
  EXPECT_TRUE(sim.mimic_joints().empty());
  EXPECT_EQ(message({{follower, leader, 1.0, 0.0}}), "");
  EXPECT_EQ(sim.mimic_joints().size(), 1u);
  EXPECT_THROW(sim.set_revolute_wrap("tip_slide", RevoluteWrap::wrapped), std::invalid_argument);
}

}  // namespace
}  // namespace featherdrive::mimic_joint_test
