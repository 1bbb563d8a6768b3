// Explicit actuators (docs/math/explicit_actuators.md) against their closed forms, written out here
// independently of src/sim/explicit_actuator.cpp, on the 1-dof slider of examples/slider.urdf
// (2.5 kg, along z) and on two independent sliders.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "featherdrive/sim/simulation.hpp"
#include "support/models.hpp"
#include "support/compare.hpp"

namespace featherdrive {
namespace {

using test::kInf;
constexpr double kMass = 2.5;
constexpr double kG = 9.81;

ExplicitActuator ideal(double kp, double kd, double limit = kInf, int delay = 0) {
  ExplicitActuator a;
  a.kind = ActuatorKind::ideal_pd;
  a.stiffness = kp;
  a.damping = kd;
  a.effort_limit = limit;
  a.delay = delay;
  return a;
}

ExplicitActuator dc_motor(double kp, double kd, double limit, double saturation, double speed) {
  ExplicitActuator a = ideal(kp, kd, limit);
  a.kind = ActuatorKind::dc_motor;
  a.saturation_effort = saturation;
  a.velocity_limit = speed;
  return a;
}

ExplicitActuator remotized(double kp, double kd, std::vector<std::pair<double, double>> table) {
  ExplicitActuator a = ideal(kp, kd);
  a.kind = ActuatorKind::remotized_pd;
  a.lookup = std::move(table);
  return a;
}

double clip(double x, double lo, double hi) { return std::min(std::max(x, lo), hi); }

// A slider along z under gravity -z (examples/slider.urdf without its limits).
Simulation slider(double dt = 1.0 / 120.0, Vec3 gravity = Vec3(0, 0, -kG)) {
  SimulationOptions o;
  o.dt = dt;
  return Simulation(test::make_slider(kMass, Vec3::UnitZ(), gravity), o);
}

// The DC motor's torque-speed line (Isaac Lab's DCMotor): S = 10, v_max = 5, E = 6, so the
// corner speed is 5 (1 + 6 / 10) = 8. A huge demand gives the upper bound, a huge negative one
// the lower bound, read off the line S (+-1 - v / v_max) cut at +-E.
TEST(ExplicitActuatorEffort, DcMotorFollowsItsTorqueSpeedLine) {
  const ExplicitActuator a = dc_motor(1e6, 0.0, 6.0, 10.0, 5.0);
  struct Point {
    double v, high, low;
  };
  const Point points[] = {
      {0.0, 6.0, -6.0},    // both cut at E
      {2.5, 5.0, -6.0},    // S (1 - 0.5) = 5 on the line
      {-2.5, 6.0, -5.0},   // mirrored
      {4.0, 2.0, -6.0},    // S (1 - 0.8)
      {5.0, 0.0, -6.0},    // the no-load speed: nothing forward
      {8.0, -6.0, -6.0},   // the corner: only -E
      {20.0, -6.0, -6.0},  // beyond it the speed is held at the corner
      {-20.0, 6.0, 6.0},
  };
  for (const Point& p : points) {
    EXPECT_DOUBLE_EQ(actuator_effort(a, 0.0, p.v, {1.0, p.v, 0.0}), p.high) << "v = " << p.v;
    EXPECT_DOUBLE_EQ(actuator_effort(a, 0.0, p.v, {-1.0, p.v, 0.0}), p.low) << "v = " << p.v;
  }
  // Within the bounds the PD law is untouched: 1e6 * 1e-6 + 0.5 at v = 2.5.
  EXPECT_DOUBLE_EQ(actuator_effort(a, 0.0, 2.5, {1e-6, 2.5, 0.5}), 1e6 * 1e-6 + 0.5);
}

// The remotized table (-1, 2), (0, 10), (0.5, 4): linear between points, the end values beyond.
TEST(ExplicitActuatorEffort, RemotizedInterpolatesItsTable) {
  const std::vector<std::pair<double, double>> table = {{-1.0, 2.0}, {0.0, 10.0}, {0.5, 4.0}};
  struct Point {
    double q, limit;
  };
  const Point points[] = {{-3.0, 2.0}, {-1.0, 2.0}, {-0.5, 6.0},  {-0.25, 8.0}, {0.0, 10.0},
                          {0.25, 7.0}, {0.4, 5.2},  {0.5, 4.0},   {2.0, 4.0}};
  const ExplicitActuator a = remotized(1e9, 0.0, table);
  for (const Point& p : points) {
    EXPECT_NEAR(lookup_effort_limit(table, p.q), p.limit, 1e-14) << "q = " << p.q;
    // A demand far above the limit is cut to it, either way.
    EXPECT_NEAR(actuator_effort(a, p.q, 0.0, {p.q + 1.0, 0.0, 0.0}), p.limit, 1e-14);
    EXPECT_NEAR(actuator_effort(a, p.q, 0.0, {p.q - 1.0, 0.0, 0.0}), -p.limit, 1e-14);
  }
  // effort_limit cuts below the table.
  ExplicitActuator b = a;
  b.effort_limit = 3.0;
  EXPECT_DOUBLE_EQ(actuator_effort(b, 0.0, 0.0, {1.0, 0.0, 0.0}), 3.0);
}

// Every step's actuator force is the kind's formula at the step-start state, and the motion is
// the semi-implicit Euler step under it and gravity: v1 = v0 + h (F / m - g), x1 = x0 + h v1.
TEST(ExplicitActuatorSimulation, EachKindAppliesItsFormulaOnTheStepStartState) {
  const double kp = 300.0, kd = 8.0, h = 1.0 / 120.0;
  const std::vector<std::pair<double, double>> table = {{-0.2, 5.0}, {0.0, 40.0}, {0.3, 15.0}};
  for (ActuatorKind kind :
       {ActuatorKind::ideal_pd, ActuatorKind::dc_motor, ActuatorKind::remotized_pd}) {
    Simulation sim = slider(h);
    ExplicitActuator a = kind == ActuatorKind::ideal_pd   ? ideal(kp, kd, 30.0)
                         : kind == ActuatorKind::dc_motor ? dc_motor(kp, kd, 30.0, 45.0, 1.5)
                                                          : remotized(kp, kd, table);
    sim.set_actuator("slide", a);
    sim.set_actuator_feedforward(0, 2.0);
    double x = 0.0, v = 0.0;
    int clipped = 0;
    for (int k = 0; k < 240; ++k) {
      const double target = 0.4 * std::sin(0.05 * k);
      const double target_v = 0.4 * 0.05 / h * std::cos(0.05 * k);
      sim.set_drive_target(0, target, target_v);
      const double demand = kp * (target - x) + kd * (target_v - v) + 2.0;
      double lo = -30.0, hi = 30.0;
      if (kind == ActuatorKind::dc_motor) {
        const double corner = 1.5 * (1.0 + 30.0 / 45.0), w = clip(v, -corner, corner);
        hi = std::min(45.0 * (1.0 - w / 1.5), 30.0);
        lo = std::max(45.0 * (-1.0 - w / 1.5), -30.0);
      } else if (kind == ActuatorKind::remotized_pd) {
        // The table, linear in each of its two pieces.
        hi = x <= -0.2 ? 5.0
             : x <= 0.0 ? 5.0 + (x + 0.2) / 0.2 * 35.0
             : x <= 0.3 ? 40.0 + x / 0.3 * (15.0 - 40.0)
                        : 15.0;
        lo = -hi;
      }
      const double force = clip(demand, lo, hi);
      clipped += force != demand;
      sim.step();
      ASSERT_NEAR(sim.actuator_force()[0], force, 1e-12 * (1.0 + std::abs(force)))
          << to_string(kind) << " step " << k;
      v += h * (force / kMass - kG);
      x += h * v;
      ASSERT_NEAR(sim.qd()[0], v, 1e-12) << to_string(kind) << " step " << k;
      ASSERT_NEAR(sim.q()[0], x, 1e-12) << to_string(kind) << " step " << k;
      EXPECT_EQ(sim.drive_force()[0], 0.0);  // no implicit drive on the dof
    }
    EXPECT_GT(clipped, 10) << to_string(kind) << ": the clip must be exercised";
    EXPECT_LT(clipped, 230) << to_string(kind) << ": and the PD law too";
  }
}

// A free mass (gravity across the slide) pushed by a constant feed-forward effort F through an
// actuator without gains: the semi-implicit integrator gives v_n = v0 + n h F / m and
// x_n = x0 + h (v_1 + ... + v_n) = x0 + v0 t + F t (t + h) / (2 m), t = n h.
TEST(ExplicitActuatorSimulation, ConstantEffortOnAFreeMass) {
  const double h = 0.01, F = 3.0, x0 = 0.2, v0 = -0.5;
  Simulation sim = slider(h, Vec3(0, -kG, 0));
  sim.set_actuator(0, ideal(0.0, 0.0, 10.0));
  sim.set_actuator_feedforward(0, F);
  VecX q(1), qd(1);
  q << x0;
  qd << v0;
  sim.set_q(q);
  sim.set_qd(qd);
  for (int n = 1; n <= 300; ++n) {
    sim.step();
    const double t = n * h;
    ASSERT_NEAR(sim.q()[0], x0 + v0 * t + F * t * (t + h) / (2.0 * kMass), 1e-12) << n;
    ASSERT_NEAR(sim.qd()[0], v0 + t * F / kMass, 1e-12) << n;
    ASSERT_EQ(sim.actuator_force()[0], F);
  }
}

// Delay d: the command the actuator sees at step k is the one given at step max(k - d, 0)
// (eq. 8-9). With feed-forward alone the applied effort is that command itself.
TEST(ExplicitActuatorSimulation, DelayShiftsTheCommandsByExactlyDSteps) {
  std::vector<double> commands;
  for (int k = 0; k < 40; ++k) commands.push_back(std::sin(0.7 * k) + 0.01 * k);
  std::vector<std::vector<double>> applied;
  for (int d : {0, 1, 3, 7}) {
    Simulation sim = slider();
    sim.set_actuator(0, ideal(0.0, 0.0, kInf, d));
    std::vector<double> seen;
    for (double c : commands) {
      sim.set_actuator_feedforward(0, c);
      sim.step();
      seen.push_back(sim.actuator_force()[0]);
    }
    for (int k = 0; k < 40; ++k)
      ASSERT_EQ(seen[static_cast<size_t>(k)], commands[static_cast<size_t>(std::max(k - d, 0))])
          << "delay " << d << " step " << k;
    applied.push_back(seen);
  }
  // The targets are delayed with it: a PD actuator with delay 2 against one without, on the
  // same start state, sees the target of two steps before.
  Simulation now = slider(), late = slider();
  now.set_actuator(0, ideal(100.0, 5.0));
  late.set_actuator(0, ideal(100.0, 5.0, kInf, 2));
  for (int k = 0; k < 5; ++k) late.set_drive_target(0, 0.1 * k, -0.2 * k), late.step();
  now.set_q(late.q());
  now.set_qd(late.qd());
  now.set_drive_target(0, 0.1 * 3, -0.2 * 3);  // the command of step 5 - 2 = 3
  now.step();
  late.set_drive_target(0, 0.5, -1.0);
  late.step();
  EXPECT_EQ(late.actuator_force()[0], now.actuator_force()[0]);
  EXPECT_EQ(late.q()[0], now.q()[0]);
  // Setting the actuator again starts its history over (eq. 9).
  late.set_actuator(0, ideal(0.0, 0.0, kInf, 2));
  late.set_actuator_feedforward(0, 4.0);
  late.step();
  EXPECT_EQ(late.actuator_force()[0], 4.0);
}

// effort_limit is the actuator's clip, max_force the implicit drive's bound: on two independent
// sliders, one each, changing either leaves the other's force as it was.
TEST(ExplicitActuatorSimulation, EffortLimitAndMaxForceAreIndependent) {
  ModelBuilder b;
  b.set_gravity(Vec3::Zero());
  b.add_link(make_link("base", "", 1.0, Vec3::Zero(), test::box_inertia(1.0, Vec3(0.1, 0.1, 0.1)),
                       fixed_joint("world_joint")));
  for (const char* name : {"a", "b"})
    b.add_link(make_link(name, "base", kMass, Vec3::Zero(),
                         test::box_inertia(kMass, Vec3(0.1, 0.1, 0.1)),
                         prismatic_joint(std::string("slide_") + name, Vec3::UnitZ())));
  auto model = std::make_shared<const Model>(b.build());
  auto run = [&](double max_force, double effort_limit) {
    Simulation sim(model);
    sim.set_drive("slide_a", Drive{DriveType::force, 1e4, 10.0, max_force, 1.0, 0.0});
    sim.set_actuator("slide_b", ideal(1e4, 10.0, effort_limit));
    sim.set_drive_target("slide_b", 1.0, 0.0);
    sim.step();
    return std::pair{sim.drive_force()[0], sim.actuator_force()[1]};
  };
  const auto [drive, actuator] = run(30.0, 20.0);
  EXPECT_NEAR(drive, 30.0, 1e-12);     // the solver's bound
  EXPECT_EQ(actuator, 20.0);           // the actuator's clip
  EXPECT_EQ(run(30.0, 5.0).first, drive);       // a tighter clip leaves the drive alone
  EXPECT_EQ(run(30.0, 5.0).second, 5.0);
  EXPECT_EQ(run(12.0, 20.0).second, actuator);  // a tighter max_force leaves the actuator alone
  EXPECT_NEAR(run(12.0, 20.0).first, 12.0, 1e-12);
  EXPECT_EQ(run(kInf, 20.0).second, 20.0);      // and no max_force does not lift the clip
}

TEST(ExplicitActuatorSimulation, RefusesADriveAndAnActuatorOnOneDof) {
  Simulation sim = slider();
  sim.set_drive(0, Drive{DriveType::force, 10.0, 1.0});
  try {
    sim.set_actuator("slide", ideal(1.0, 0.0));
    FAIL() << "an actuator beside a drive";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "joint 'slide' has a force drive: an explicit ideal_pd actuator cannot "
                           "act beside it (set the drive's type to none)");
  }
  sim.set_drive(0, Drive{});  // type none, targets kept
  sim.set_actuator("slide", ideal(1.0, 0.0));
  EXPECT_TRUE(sim.has_actuator(0));
  try {
    sim.set_drive(0, Drive{DriveType::acceleration, 10.0, 1.0});
    FAIL() << "a drive beside an actuator";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("joint 'slide' has an explicit actuator (ideal_pd)"),
              std::string::npos)
        << e.what();
  }
  sim.set_drive_target(0, 0.3, 0.1);  // a drive of type none carries the actuator's targets
  EXPECT_EQ(sim.drive(0).target_position, 0.3);
  sim.clear_actuator(0);
  EXPECT_FALSE(sim.has_actuator(0));
  sim.set_drive(0, Drive{DriveType::acceleration, 10.0, 1.0});
  EXPECT_THROW(sim.set_actuator_feedforward(0, 1.0), std::invalid_argument);
}

TEST(ExplicitActuatorSimulation, BadActuatorsGetOneLineNamingTheField) {
  Simulation sim = slider();
  struct Bad {
    ExplicitActuator actuator;
    const char* message;
  };
  ExplicitActuator no_saturation = dc_motor(1, 0, kInf, 0.0, 2.0);
  ExplicitActuator stray_speed = ideal(1, 0);
  stray_speed.velocity_limit = 3.0;
  ExplicitActuator stray_table = ideal(1, 0);
  stray_table.lookup = {{0.0, 1.0}};
  const Bad bad[] = {
      {ideal(-1.0, 0.0), "actuator on joint 'slide': stiffness = -1 must be finite and >= 0"},
      {ideal(1.0, NAN), "actuator on joint 'slide': damping = nan must be finite and >= 0"},
      {ideal(1.0, 0.0, 0.0), "actuator on joint 'slide': effort_limit = 0 must be > 0"},
      {ideal(1.0, 0.0, kInf, -1),
       "actuator on joint 'slide': delay = -1 must be in [0, 100000] steps"},
      {no_saturation,
       "actuator on joint 'slide': saturation_effort = 0 must be finite and > 0 for a dc_motor"},
      {stray_speed, "actuator on joint 'slide': velocity_limit = 3 is for a dc_motor only, not "
                    "ideal_pd"},
      {stray_table, "actuator on joint 'slide': a lookup table (1 points) is for a remotized_pd "
                    "only, not ideal_pd"},
      {remotized(1, 0, {}),
       "actuator on joint 'slide': a remotized_pd needs a lookup table of (position, effort)"},
      {remotized(1, 0, {{0.0, 1.0}, {0.0, 2.0}}),
       "actuator on joint 'slide': lookup[1].position = 0 must be above the previous position 0"},
      {remotized(1, 0, {{0.0, -1.0}}),
       "actuator on joint 'slide': lookup[0].effort = -1 must be finite and >= 0"},
  };
  for (const Bad& b : bad) {
    try {
      sim.set_actuator(0, b.actuator);
      FAIL() << b.message;
    } catch (const std::invalid_argument& e) {
      EXPECT_STREQ(e.what(), b.message);
    }
    EXPECT_FALSE(sim.has_actuator(0));  // nothing changed
  }
  sim.set_actuator(0, ideal(1.0, 0.0));
  try {
    sim.set_actuator_feedforward("slide", kInf);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "actuator on joint 'slide': feedforward = inf must be finite");
  }
}

// A step that diverges leaves the state, the actuator force and the delay history as they were:
// the retried step gives what an undisturbed run gives.
TEST(ExplicitActuatorSimulation, ADivergedStepLeavesTheHistoryAsItWas) {
  // dt = 100 s: an applied 1e308 N makes the velocity overflow.
  Simulation sim = slider(100.0, Vec3(0, -kG, 0)), reference = slider(100.0, Vec3(0, -kG, 0));
  const double commands[] = {1.0, 2.0, 3.0, 4.0, 5.0};
  for (Simulation* s : {&sim, &reference}) {
    s->set_actuator(0, ideal(0.0, 0.0, kInf, 2));
    for (int k = 0; k < 3; ++k) s->set_actuator_feedforward(0, commands[k]), s->step();
  }
  VecX tau(1);
  tau << 1e308;
  sim.set_applied_force(tau);
  sim.set_actuator_feedforward(0, commands[3]);
  EXPECT_THROW(sim.step(), DivergenceError);
  EXPECT_EQ(sim.actuators().pushes(0), 3);
  EXPECT_EQ(sim.actuator_force()[0], reference.actuator_force()[0]);
  EXPECT_EQ(sim.q()[0], reference.q()[0]);
  sim.set_applied_force(VecX::Zero(1));
  for (int k = 3; k < 5; ++k)
    for (Simulation* s : {&sim, &reference}) s->set_actuator_feedforward(0, commands[k]), s->step();
  EXPECT_EQ(sim.actuator_force()[0], 3.0);  // the command of step 4 - 2 = 2
  EXPECT_EQ(sim.actuator_force()[0], reference.actuator_force()[0]);
  EXPECT_EQ(sim.q()[0], reference.q()[0]);
  EXPECT_EQ(sim.qd()[0], reference.qd()[0]);
}

}  // namespace
}  // namespace featherdrive
