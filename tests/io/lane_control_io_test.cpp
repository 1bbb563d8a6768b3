// Batch's SIMD lanes with drive delays and explicit actuators on a robot as loaded (DART's
// Barrett WAM, its URDF velocity and effort limits on), and implicit actuators on
// examples/arm7.urdf: each environment within 1e-12 of its Simulation stepped alone over 1000
// steps (docs/simd_batch.md, "Control stages").
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "featherdrive/io/urdf.hpp"
#include "featherdrive/sim/batch.hpp"
#include "support/lanes.hpp"
#include "support/source_tree.hpp"

namespace featherdrive {
namespace {

// The largest |a - b| / max(1, |b|).
template <class A, class B>
double lane_control_difference(const A& a, const B& b) {
  double worst = 0.0;
  for (Eigen::Index k = 0; k < a.size(); ++k)
    worst = std::max(worst, std::abs(a[k] - b[k]) / std::max(1.0, std::abs(b[k])));
  return worst;
}

// Environment e: explicit actuators on the shoulder's joints 2 and 4 (a DC motor within the URDF
// effort, an ideal PD clipped to it; environment 2's delayed by a step), force drives (the URDF
// effort as max_force) delayed by (d + e) % 3 steps on the others. An explicit law is stable
// only where kd dt / I and kp dt^2 / I stay small: on the wrist's links (I ~ 5e-5 kg m^2) it
// chatters between its effort bounds, chaos that no two operation orders share to 1e-12.
void wam_control(Simulation& s, int e) {
  const Model& m = s.model();
  for (int d = 0; d < m.nv; ++d) {
    const double effort = m.effort_limit[d];
    if (d % 2 == 0 || d > 3) {
      s.set_drive(d, Drive{DriveType::force, 2e3, 100.0, effort, 0.0, 0.0});
      s.set_drive_delay(d, (d + e) % 3);
      continue;
    }
    ExplicitActuator a;
    a.stiffness = 100.0;
    a.damping = 4.0;
    a.effort_limit = effort;
    a.delay = e == 2 ? 1 : 0;
    if (d % 4 == 1) {
      a.kind = ActuatorKind::dc_motor;
      a.saturation_effort = 1.5 * effort;
      a.velocity_limit = 2.0;
    } else {
      a.kind = ActuatorKind::ideal_pd;
    }
    s.set_drive(d, Drive{});
    s.set_actuator(d, a);
  }
}

TEST(LaneControlRobots, WamAsLoadedWithDelaysAndActuatorsWithinTolOfSimulation) {
  const UrdfRobot robot = load_urdf("/usr/share/doc/dart/data/urdf/wam/wam.urdf");
  for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    SimulationOptions o;
    o.dt = 1.0 / 240.0;
    o.solver = solver;
    const Simulation prototype(robot.model, o);
    const int n = 3, nv = robot.model->nv;
    Batch batch(prototype, n);
    std::vector<Simulation> alone(n, prototype);
    for (int e = 0; e < n; ++e) {
      wam_control(batch.sim(e), e);
      wam_control(alone[static_cast<size_t>(e)], e);
    }
    EXPECT_NE(batch.step_path().find(" lanes"), std::string::npos) << batch.step_path();
    for (int k = 0; k < 20; ++k) {  // a new pose every 50 steps
      for (int e = 0; e < n; ++e)
        for (int d = 0; d < nv; ++d) {
          const double x = 0.4 * std::sin(0.3 * k + d + 0.5 * e);
          batch.sim(e).set_drive_target(d, x, 0.0);
          alone[static_cast<size_t>(e)].set_drive_target(d, x, 0.0);
        }
      batch.step(50);
      for (Simulation& s : alone) s.step(50);
    }
    double state = 0.0, force = 0.0, effort = 0.0;
    for (int e = 0; e < n; ++e) {
      const Simulation& b = batch.sim(e);
      const Simulation& a = alone[static_cast<size_t>(e)];
      state = std::max({state, lane_control_difference(b.q(), a.q()),
                        lane_control_difference(b.qd(), a.qd())});
      force = std::max({force, lane_control_difference(b.drive_force(), a.drive_force()),
                        lane_control_difference(b.limit_force(), a.limit_force()),
                        lane_control_difference(b.velocity_limit_force(), a.velocity_limit_force()),
                        lane_control_difference(b.actuator_force(), a.actuator_force())});
      effort = std::max(effort, a.actuator_force().cwiseAbs().maxCoeff());
      EXPECT_EQ(b.step_count(), 1000);
    }
    EXPECT_LE(state, 1e-12) << to_string(solver);
    EXPECT_LE(force, 1e-12) << to_string(solver);
    EXPECT_GT(effort, 1.0);
    std::printf("wam.urdf with delays and actuators, %s: q, qd %.1e, forces %.1e "
                "(docs/simd_batch.md)\n",
                to_string(solver), state, force);
  }
}

// Environment e of a robot as loaded: an implicit actuator on every dof (kind (d + e) % 3, within
// the URDF effort: an ideal PD, a DC motor stalling at 1.5 times it, a remotized PD whose table
// falls to half of it towards the joint's limits), gains of its own, environment 2's delayed by a
// step; convergence tracking on in environment 1.
void implicit_robot_control(Simulation& s, int e) {
  const Model& m = s.model();
  for (int d = 0; d < m.nv; ++d) {
    ExplicitActuator a;
    a.integration = ActuatorIntegration::implicit_law;
    a.effort_limit = m.effort_limit[d];
    a.stiffness = 20.0 * a.effort_limit * (1.0 + 0.1 * e);
    a.damping = a.effort_limit;
    a.delay = e == 2 ? 1 : 0;
    switch ((d + e) % 3) {
      case 0:
        a.kind = ActuatorKind::ideal_pd;
        break;
      case 1:
        a.kind = ActuatorKind::dc_motor;
        a.saturation_effort = 1.5 * a.effort_limit;
        a.velocity_limit = 2.0;
        break;
      default:
        a.kind = ActuatorKind::remotized_pd;
        a.lookup = {{s.lower_limit(d), 0.5 * a.effort_limit},
                    {0.0, a.effort_limit},
                    {s.upper_limit(d), 0.5 * a.effort_limit}};
        a.effort_limit = test::kInf;  // the table's alone
        break;
    }
    s.set_drive(d, Drive{});
    s.set_actuator(d, a);
  }
  s.set_track_convergence(e == 1);
}

// examples/arm7.urdf as loaded (its limits, friction, velocity limits) with implicit actuators of
// every kind. (DART's WAM with them on its shoulder and drives on its wrist, links of 5e-5 kg m^2,
// drifted to 1e-12 to 5e-12 in 1000 steps on most trajectories tried, where one step differs by
// 8e-15; plain force drives clipped at its URDF effort, 20 E gains, TGS, drift to 3e-6 on one:
// knife edges of its velocity limits, not of the actuators.)
TEST(LaneControlRobots, Arm7WithImplicitActuatorsWithinTolOfSimulation) {
  const UrdfRobot robot = load_urdf(test::kExamples + "arm7.urdf");
  for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    SimulationOptions o;
    o.dt = 1.0 / 240.0;
    o.solver = solver;
    const Simulation prototype(robot.model, o);
    Batch batch(prototype, 3);
    std::vector<Simulation> alone = test::give_each(batch, prototype, implicit_robot_control);
    EXPECT_NE(batch.step_path().find(" lanes"), std::string::npos) << batch.step_path();
    // A new pose every other call (of 1 to 9 steps).
    test::step_with_commands(batch, alone, 1000, [](Simulation& s, int e, int k) {
      if (k % 2) return;
      for (int d = 0; d < s.model().nv; ++d)
        s.set_drive_target(d, 0.4 * std::sin(0.3 * k + d + 0.5 * e), 0.0);
    });
    test::LaneWorst worst;
    for (int e = 0; e < 3; ++e)
      test::compare_with_alone(batch, e, alone[static_cast<size_t>(e)], worst, "arm7");
    EXPECT_LE(worst.state, 1e-12) << to_string(solver);
    EXPECT_LE(worst.force, 1e-12) << to_string(solver);
    EXPECT_LE(worst.change, 1e-12) << to_string(solver);
    EXPECT_GT(alone[0].actuator_force().cwiseAbs().maxCoeff(), 1.0) << to_string(solver);
    std::printf("arm7.urdf with implicit actuators, %s: q, qd %.1e, forces %.1e, drive changes "
                "%.1e (docs/simd_batch.md)\n",
                to_string(solver), worst.state, worst.force, worst.change);
  }
}

}  // namespace
}  // namespace featherdrive
