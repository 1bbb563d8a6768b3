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

// ---- Implicit actuators (docs/math/implicit_actuators.md) ----------------------------------
// On a slider of mass 2.5 kg with armature 0.3 kg (M = 2.8 kg along the slide), gravity across
// it: one PGS step is an implicit Euler step of the law linearised at the step's end (eq. I3),
//   v1 = (M v0 + h (kp (q* - q0) + kd v* + ff)) / (M + h kd + h^2 kp),  q1 = q0 + h v1,
// and TGS's n sub-steps are n such steps of rho = h / n towards the target interpolated as
// q*_i = q* - v* (h - i rho) (implicit_drives.md eq. 41).

constexpr double kArmature = 0.3;
constexpr double kM = kMass + kArmature;

std::shared_ptr<const Model> armature_slider() {
  ModelBuilder b;
  b.set_gravity(Vec3(0, -kG, 0));
  b.add_link(make_link("base", "", 1.0, Vec3::Zero(), test::box_inertia(1.0, Vec3(0.1, 0.1, 0.1)),
                       fixed_joint("world_joint")));
  LinkSpec slider = make_link("slider", "base", kMass, Vec3::Zero(),
                              test::box_inertia(kMass, Vec3(0.1, 0.1, 0.1)),
                              prismatic_joint("slide", Vec3::UnitZ()));
  slider.joint.armature = {kArmature};
  b.add_link(slider);
  return std::make_shared<const Model>(b.build());
}

Simulation implicit_slider(double dt, SolverType solver = SolverType::pgs, int iterations = 4) {
  SimulationOptions o;
  o.dt = dt;
  o.solver = solver;
  o.position_iterations = iterations;
  return Simulation(armature_slider(), o);
}

ExplicitActuator implicit(ExplicitActuator a) {
  a.integration = ActuatorIntegration::implicit_law;
  return a;
}

void set_state(Simulation& sim, double q, double qd) {
  sim.set_q(VecX::Constant(1, q));
  sim.set_qd(VecX::Constant(1, qd));
}

// |a - b| within rel of the larger magnitude (and of 1 for values near zero).
void expect_close(double a, double b, double rel, const std::string& what) {
  ASSERT_LE(std::abs(a - b), rel * std::max({1.0, std::abs(a), std::abs(b)})) << what;
}

TEST(ImplicitActuator, IntegrationDefaultsToExplicitAndNamesItself) {
  EXPECT_EQ(ExplicitActuator{}.integration, ActuatorIntegration::explicit_law);
  EXPECT_STREQ(to_string(ActuatorIntegration::explicit_law), "explicit");
  EXPECT_STREQ(to_string(ActuatorIntegration::implicit_law), "implicit");
}

// The default (explicit) law against numbers stored from its closed form (semi-implicit Euler
// under the effort of the step-start state; M = 2.8, kp 200, kd 5, ff 1, target 0.1, h 0.01,
// from q = 0, qd = 0.5): step 1: F = 20 - 2.5 + 1 = 18.5, v1 = 0.5 + 0.01 * 18.5 / 2.8,
// q1 = 0.01 v1; step 2: F = 200 (0.1 - q1) - 5 v1 + 1 = 17.0375, likewise.
TEST(ImplicitActuator, TheDefaultStaysTheExplicitLaw) {
  Simulation sim = implicit_slider(0.01);
  sim.set_actuator(0, ideal(200.0, 5.0));
  sim.set_actuator_feedforward(0, 1.0);
  sim.set_drive_target(0, 0.1, 0.0);
  set_state(sim, 0.0, 0.5);
  const double v1 = 0.5660714285714286, q1 = 0.005660714285714285;
  const double v2 = 0.6269196428571429, q2 = 0.011929910714285714;
  sim.step();
  expect_close(sim.actuator_force()[0], 18.5, 1e-14, "F1");
  expect_close(sim.qd()[0], v1, 1e-14, "v1");
  expect_close(sim.q()[0], q1, 1e-14, "q1");
  sim.step();
  expect_close(sim.actuator_force()[0], 200.0 * (0.1 - q1) - 5.0 * v1 + 1.0, 1e-14, "F2");
  expect_close(sim.qd()[0], v2, 1e-14, "v2");
  expect_close(sim.q()[0], q2, 1e-14, "q2");
}

TEST(ImplicitActuator, PgsStepIsImplicitEulerOfTheLinearisedLaw) {
  const double h = 1.0 / 60.0, kp = 400.0, kd = 12.0, ff = 1.5;
  for (ActuatorKind kind :
       {ActuatorKind::ideal_pd, ActuatorKind::dc_motor, ActuatorKind::remotized_pd}) {
    Simulation sim = implicit_slider(h);
    // Clips far beyond what the law asks: the row is the linear law alone.
    ExplicitActuator a = kind == ActuatorKind::ideal_pd   ? ideal(kp, kd, 1e6)
                         : kind == ActuatorKind::dc_motor ? dc_motor(kp, kd, 1e6, 1e6, 1e4)
                                                          : remotized(kp, kd, {{0.0, 1e6}});
    sim.set_actuator(0, implicit(a));
    sim.set_actuator_feedforward(0, ff);
    double q = 0.05, v = -0.3;
    set_state(sim, q, v);
    for (int k = 0; k < 50; ++k) {
      const double target = 0.3 * std::sin(0.1 * k), target_v = 0.5 * std::cos(0.1 * k);
      sim.set_drive_target(0, target, target_v);
      sim.step();
      const double v1 = (kM * v + h * (kp * (target - q) + kd * target_v + ff)) /
                        (kM + h * kd + h * h * kp);
      q += h * v1;
      v = v1;
      const std::string at = std::string(to_string(kind)) + " step " + std::to_string(k);
      expect_close(sim.qd()[0], v, 1e-12, at + " qd");
      expect_close(sim.q()[0], q, 1e-12, at + " q");
      // The force is the law at the step's end state (eq. I2), reported as the actuator's.
      expect_close(sim.actuator_force()[0], kp * (target - q) + kd * (target_v - v) + ff, 1e-10,
                   at + " force");
      ASSERT_EQ(sim.drive_force()[0], 0.0) << at;
    }
  }
}

TEST(ImplicitActuator, TgsSubStepsAreImplicitEulerSubSteps) {
  const double h = 1.0 / 30.0, kp = 900.0, kd = 20.0, ff = -2.0;
  for (int n : {1, 3, 8}) {
    Simulation sim = implicit_slider(h, SolverType::tgs, n);
    sim.set_actuator(0, implicit(ideal(kp, kd)));
    sim.set_actuator_feedforward(0, ff);
    double q = 0.0, v = 0.2;
    set_state(sim, q, v);
    const double rho = h / n;
    for (int k = 0; k < 50; ++k) {
      const double target = 0.2 + 0.1 * k / 50.0, target_v = 0.4 - 0.01 * k;
      sim.set_drive_target(0, target, target_v);
      sim.step();
      const double v_start = v;
      for (int i = 1; i <= n; ++i) {
        const double target_i = target - target_v * (h - i * rho);
        v = (kM * v + rho * (kp * (target_i - q) + kd * target_v + ff)) /
            (kM + rho * kd + rho * rho * kp);
        q += rho * v;
      }
      const std::string at = "n " + std::to_string(n) + " step " + std::to_string(k);
      expect_close(sim.qd()[0], v, 1e-12, at + " qd");
      expect_close(sim.q()[0], q, 1e-12, at + " q");
      expect_close(sim.actuator_force()[0], kM * (v - v_start) / h, 1e-10, at + " force");
    }
  }
}

// Each clip active, on its closed form.
TEST(ImplicitActuator, EachClipActsOnTheImpulse) {
  const double h = 0.01;
  {  // ideal_pd at E: a far target, |effort| = E, v1 = v0 + h E / M.
    Simulation sim = implicit_slider(h);
    sim.set_actuator(0, implicit(ideal(1e5, 10.0, 7.0)));
    sim.set_drive_target(0, 5.0, 0.0);
    double v = 0.0;
    for (int k = 0; k < 20; ++k) {
      sim.step();
      v += h * 7.0 / kM;
      expect_close(sim.actuator_force()[0], 7.0, 1e-12, "ideal force " + std::to_string(k));
      expect_close(sim.qd()[0], v, 1e-12, "ideal qd " + std::to_string(k));
    }
  }
  {  // dc_motor on its torque-speed line from rest: v1 = (v0 + h S / M) / (1 + h S / (M vmax)),
     // eq. I12, which tends to v_max without overshoot (S = 400 N, v_max = 0.5 m/s: h S / (M
     // v_max) = 2.9, where the explicit line overshoots and rings).
    const double S = 400.0, v_max = 0.5;
    Simulation sim = implicit_slider(h);
    sim.set_actuator(0, implicit(dc_motor(1e4, 0.0, kInf, S, v_max)));
    sim.set_drive_target(0, 100.0, 0.0);
    double v = 0.0;
    for (int k = 0; k < 15; ++k) {
      const double v0 = v;
      sim.step();
      v = (v + h * S / kM) / (1.0 + h * S / (kM * v_max));
      expect_close(sim.qd()[0], v, 1e-12, "dc qd " + std::to_string(k));
      expect_close(sim.actuator_force()[0], S * (1.0 - v / v_max), 1e-9,
                   "dc force on the line at the end velocity " + std::to_string(k));
      ASSERT_GT(v, v0);
      ASSERT_LT(v, v_max);
    }
    EXPECT_NEAR(v, v_max, 1e-6);  // (v_max - v) shrinks by 1 / 3.9 a step
    // Driven backwards from beyond the no-load speed, the lower bound S (-1 - v / v_max).
    set_state(sim, 0.0, 0.2);
    sim.set_drive_target(0, -100.0, 0.0);
    sim.step();
    const double v1 = (0.2 - h * S / kM) / (1.0 + h * S / (kM * v_max));
    expect_close(sim.qd()[0], v1, 1e-12, "dc lower bound");
    // TGS bounds the impulse summed over the sub-steps at each sub-step's velocity: the first
    // sub-step takes the whole of (I10) and the later ones hold it, so every sub-step ends at
    // the PGS step's v1 and q1 = q0 + h v1.
    for (int n : {2, 5}) {
      Simulation tgs = implicit_slider(h, SolverType::tgs, n);
      tgs.set_actuator(0, implicit(dc_motor(1e4, 0.0, kInf, S, v_max)));
      tgs.set_drive_target(0, 100.0, 0.0);
      double vt = 0.0, qt = 0.0;
      for (int k = 0; k < 10; ++k) {
        tgs.step();
        vt = (vt + h * S / kM) / (1.0 + h * S / (kM * v_max));
        qt += h * vt;
        expect_close(tgs.qd()[0], vt, 1e-12, "dc tgs qd " + std::to_string(k));
        expect_close(tgs.q()[0], qt, 1e-12, "dc tgs q " + std::to_string(k));
      }
    }
    // And cut at E: with E = 30 below the line's S (1 - v / v_max), the step is E's.
    Simulation cut = implicit_slider(h);
    cut.set_actuator(0, implicit(dc_motor(1e4, 0.0, 30.0, S, v_max)));
    cut.set_drive_target(0, 100.0, 0.0);
    cut.step();
    expect_close(cut.actuator_force()[0], 30.0, 1e-12, "dc at E");
  }
  {  // remotized_pd on a flat table: |effort| = L.
    Simulation sim = implicit_slider(h);
    sim.set_actuator(0, implicit(remotized(1e5, 10.0, {{-1.0, 4.0}, {1.0, 4.0}})));
    sim.set_drive_target(0, -5.0, 0.0);
    double v = 0.0;
    for (int k = 0; k < 20; ++k) {
      sim.step();
      v -= h * 4.0 / kM;
      expect_close(sim.actuator_force()[0], -4.0, 1e-12, "remotized force " + std::to_string(k));
      expect_close(sim.qd()[0], v, 1e-12, "remotized qd " + std::to_string(k));
    }
    // On a sloped table the limit is read at the iterate's end position, a fixed point (eq.
    // I13): after the step's iterations it matches the table at the step's end closely.
    Simulation slope = implicit_slider(h);
    const std::vector<std::pair<double, double>> table = {{-1.0, 2.0}, {1.0, 12.0}};
    slope.set_actuator(0, implicit(remotized(1e5, 10.0, table)));
    slope.set_drive_target(0, 5.0, 0.0);
    for (int k = 0; k < 30; ++k) {
      slope.step();
      expect_close(slope.actuator_force()[0], 7.0 + 5.0 * slope.q()[0], 1e-9,
                   "sloped table " + std::to_string(k));
    }
  }
}

// kp dt^2 / M from 0.1 to 1e4: the implicit law stays bounded and settles on its target (implicit
// Euler never adds energy, eq. I14: |q - q*| never exceeds its start); the explicit one diverges
// at the high end (symplectic Euler on kp alone is stable only below kp dt^2 / M = 4).
TEST(ImplicitActuator, StableAtEveryGainWhereTheExplicitLawDiverges) {
  const double h = 0.01, target = 0.1;
  for (ActuatorKind kind :
       {ActuatorKind::ideal_pd, ActuatorKind::dc_motor, ActuatorKind::remotized_pd}) {
    for (double ratio : {0.1, 1.0, 10.0, 100.0, 1e3, 1e4}) {
      const double kp = ratio * kM / (h * h), kd = 0.0;
      const ExplicitActuator a = kind == ActuatorKind::ideal_pd ? ideal(kp, kd)
                                 : kind == ActuatorKind::dc_motor
                                     ? dc_motor(kp, kd, 60.0, 80.0, 2.0)
                                     : remotized(kp, kd, {{-1.0, 50.0}, {1.0, 70.0}});
      const std::string at = std::string(to_string(kind)) + " kp dt^2/M " + std::to_string(ratio);
      Simulation sim = implicit_slider(h);
      sim.set_actuator(0, implicit(a));
      sim.set_drive_target(0, target, 0.0);
      double worst = 0.0;
      for (int k = 0; k < 1000; ++k) {
        sim.step();
        worst = std::max(worst, std::abs(sim.q()[0] - target));
      }
      EXPECT_LE(worst, target * (1.0 + 1e-9)) << at;
      // Undamped, implicit Euler's loss per step is small at low gains: settled at the high ones.
      if (ratio >= 10.0) {
        EXPECT_LT(std::abs(sim.q()[0] - target), 1e-6) << at;
        EXPECT_LT(std::abs(sim.qd()[0]), 1e-4) << at;
      }
      Simulation expl = implicit_slider(h);
      expl.set_actuator(0, a);
      expl.set_drive_target(0, target, 0.0);
      double expl_worst = 0.0;
      try {
        for (int k = 0; k < 1000; ++k) {
          expl.step();
          expl_worst = std::max(expl_worst, std::abs(expl.q()[0] - target));
        }
      } catch (const DivergenceError&) {
        expl_worst = kInf;
      }
      // Below 4 symplectic Euler rings within a bounded envelope.
      if (ratio <= 1.0) EXPECT_LE(expl_worst, 3.0 * target) << at;
      // The ideal PD diverges; the clipped kinds stay bounded by their clip but keep ringing.
      if (ratio >= 1e3 && kind == ActuatorKind::ideal_pd) EXPECT_EQ(expl_worst, kInf) << at;
      if (ratio >= 1e3 && kind != ActuatorKind::ideal_pd)
        EXPECT_GT(std::abs(expl.q()[0] - target) + h * std::abs(expl.qd()[0]), 1e-3) << at;
    }
  }
}

// At low gains the two laws agree to O(dt): both are first-order integrators of the same ODE, so
// their difference at a fixed time is c dt + O(dt^2) and halves with dt (ratio 2 up to O(dt)).
TEST(ImplicitActuator, AgreesWithTheExplicitLawToFirstOrderInDt) {
  const double kp = 30.0, kd = 2.0, T = 1.0;
  std::vector<double> gaps;
  for (double h : {1.0 / 100.0, 1.0 / 200.0, 1.0 / 400.0}) {
    double q[2] = {0.0, 0.0};
    for (int which = 0; which < 2; ++which) {
      Simulation sim = implicit_slider(h);
      ExplicitActuator a = ideal(kp, kd);
      if (which == 1) a = implicit(a);
      sim.set_actuator(0, a);
      sim.set_actuator_feedforward(0, 0.5);
      const int steps = static_cast<int>(std::lround(T / h));
      for (int k = 0; k < steps; ++k) {
        const double t = k * h;
        sim.set_drive_target(0, 0.2 * std::sin(3.0 * t), 0.6 * std::cos(3.0 * t));
        sim.step();
      }
      q[which] = sim.q()[0];
    }
    gaps.push_back(std::abs(q[1] - q[0]));
  }
  EXPECT_GT(gaps[0], 1e-5);  // the laws differ
  for (int i = 0; i + 1 < 3; ++i) {
    const double ratio = gaps[static_cast<size_t>(i)] / gaps[static_cast<size_t>(i) + 1];
    EXPECT_GE(ratio, 1.8) << "dt halving " << i;
    EXPECT_LE(ratio, 2.2) << "dt halving " << i;
  }
}

// Delay d: step k's row uses the command of step max(k - d, 0) (explicit_actuators.md eq. 8-9).
TEST(ImplicitActuator, DelayFeedsTheRowTheCommandOfDStepsAgo) {
  const double h = 0.02, kp = 250.0, kd = 6.0;
  for (int d : {0, 2, 5}) {
    Simulation sim = implicit_slider(h);
    sim.set_actuator(0, implicit(ideal(kp, kd, kInf, d)));
    std::vector<ActuatorCommand> commands;
    double q = 0.0, v = 0.0;
    for (int k = 0; k < 30; ++k) {
      commands.push_back({0.1 * std::sin(0.3 * k), 0.2 * std::cos(0.5 * k), 0.4 * k - 3.0});
      sim.set_drive_target(0, commands.back().position, commands.back().velocity);
      sim.set_actuator_feedforward(0, commands.back().effort);
      sim.step();
      const ActuatorCommand& c = commands[static_cast<size_t>(std::max(k - d, 0))];
      v = (kM * v + h * (kp * (c.position - q) + kd * c.velocity + c.effort)) /
          (kM + h * kd + h * h * kp);
      q += h * v;
      expect_close(sim.q()[0], q, 1e-12, "delay " + std::to_string(d) + " step " +
                                             std::to_string(k));
    }
  }
}

// An implicit actuator beside rows of its own dof (a limit) and switching between the laws.
TEST(ImplicitActuator, SharesItsDofWithALimitAndSwitchesBack) {
  Simulation sim = implicit_slider(0.01);
  sim.set_joint_limits(0, -0.05, 0.05);
  sim.set_actuator(0, implicit(ideal(1e4, 0.0)));
  sim.set_drive_target(0, 1.0, 0.0);
  for (int k = 0; k < 50; ++k) sim.step();
  // Held at the limit against the far target: at rest, the limit takes what the actuator gives.
  EXPECT_NEAR(sim.q()[0], 0.05, 1e-3);
  EXPECT_GT(sim.actuator_force()[0], 1e3);
  EXPECT_NEAR(sim.actuator_force()[0], -sim.limit_force()[0],
              1e-6 * std::abs(sim.limit_force()[0]));
  // Back to explicit: the force is the step-start law again, and the row is gone.
  sim.set_joint_limits(0, -kInf, kInf);
  sim.set_actuator(0, ideal(100.0, 0.0));
  set_state(sim, 0.0, 0.0);
  sim.step();
  EXPECT_EQ(sim.actuator_force()[0], 100.0);
  EXPECT_EQ(sim.drive_force()[0], 0.0);
}

}  // namespace
}  // namespace featherdrive
