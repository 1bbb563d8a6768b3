// Batch's SIMD lanes with the step's control stages (drive delays, explicit actuators; docs/
// simd_batch.md, "Control stages") against each environment stepped alone as a Simulation: 1000
// steps within 1e-12 (the lanes' operation order differs), the delay and actuator histories and
// the actuators' efforts as the Simulation keeps them, a diverging environment's pushes taken back.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "featherdrive/sim/batch.hpp"
#include "support/compare.hpp"
#include "support/drives.hpp"
#include "support/lanes.hpp"
#include "support/models.hpp"

namespace featherdrive {
namespace lane_control {
namespace {

using test::kInf;

constexpr int kEnvironments = 7;  // not a whole number of blocks: padding lanes too

// An explicit actuator of each kind the library has, by index.
ExplicitActuator actuator_of_kind(int k, int delay) {
  ExplicitActuator a;
  a.stiffness = 60.0 + 10.0 * k;
  a.damping = 4.0;
  a.delay = delay;
  switch (k % 3) {
    case 0:
      a.kind = ActuatorKind::ideal_pd;
      a.effort_limit = 8.0;
      break;
    case 1:
      a.kind = ActuatorKind::dc_motor;
      a.saturation_effort = 12.0;
      a.velocity_limit = 3.0;
      a.effort_limit = 9.0;
      break;
    default:
      a.kind = ActuatorKind::remotized_pd;
      a.lookup = {{-1.0, 3.0}, {0.0, 9.0}, {1.0, 5.0}};
      break;
  }
  return a;
}

// A random fixed-base tree of 9 links: force drives (acceleration drives on every third dof, a
// force limit on every fourth), joint limits, friction and velocity limits on some dofs, viscous
// friction everywhere (no chaos: the last bits of two operation orders stay within 1e-12 over
// 1000 steps). No joint comes to rest on its limit, where the side a last bit picks decides.
Simulation control_prototype(unsigned seed, SolverType solver) {
  SimulationOptions options;
  options.dt = 0.005;
  options.solver = solver;
  options.position_iterations = 4;
  options.velocity_iterations = 1;
  Simulation sim(test::make_random_tree(seed, 9, false, false, 0.01), options);
  std::mt19937 rng(seed);
  test::drive_every_joint(sim, rng, 300.0, 20.0);
  const int nv = sim.model().nv;
  for (int d = 0; d < nv; ++d) {
    Drive drive = sim.drive(d);
    drive.type = d % 3 == 1 ? DriveType::acceleration : DriveType::force;
    drive.max_force = d % 4 == 2 ? 5.0 : kInf;
    sim.set_drive(d, drive);
    const bool rubbing = d % 4 == 1;
    sim.set_joint_friction(d, JointFriction{rubbing ? 0.3 : 0.0, rubbing ? 0.2 : 0.0, 0.5});
    if (d % 3 == 0) sim.set_joint_limits(d, -0.3, 0.4);
    if (d % 5 == 3) sim.set_max_joint_velocity(d, 0.3);
  }
  sim.set_qd(test::random_vector(nv, rng, 0.5));
  return sim;
}

// Environment e's control settings: its own drive delays (some none) and, on every third dof
// from e % 3, an explicit actuator (kinds in turn, some delayed) instead of the drive.
void give_control(Simulation& s, int e) {
  const int nv = s.model().nv;
  for (int d = 0; d < nv; ++d) {
    if ((d + e) % 3 == 0) {
      const Drive old = s.drive(d);
      s.set_drive(d, Drive{});
      s.set_actuator(d, actuator_of_kind(d + e, (d + e) % 2));
      s.set_drive_target(d, old.target_position, old.target_velocity);
      s.set_actuator_feedforward(d, 0.1 * (d % 2 ? 1.0 : -1.0));
    } else {
      s.set_drive_delay(d, (d * 7 + e) % 4);
    }
  }
}

// Targets of call k of environment e (the same for the batch and the lone Simulation).
void command(Simulation& s, int e, int k) {
  for (int d = 0; d < s.model().nv; ++d) {
    if (s.drive(d).type == DriveType::none && !s.has_actuator(d)) continue;
    const double x = 0.35 * std::sin(0.07 * k + 0.9 * d + 0.3 * e);
    s.set_drive_target(d, x, 0.2 * std::cos(0.05 * k + d));
  }
}

class LaneControl : public testing::TestWithParam<SolverType> {};

// Per-environment delays and actuators of every kind, targets changed between calls of 1 to 9
// steps: 1000 steps in the lanes within 1e-12 of each environment stepped alone.
TEST_P(LaneControl, DelaysAndActuatorsWithinTolOfSimulation) {
  const SolverType solver = GetParam();
  const Simulation prototype = control_prototype(11, solver);
  Batch batch(prototype, kEnvironments);
  batch.set_num_threads(2);
  std::vector<Simulation> alone = test::give_each(batch, prototype, give_control);
  EXPECT_NE(batch.step_path().find(" lanes"), std::string::npos) << batch.step_path();
  // Where a velocity limit holds a drive back, the two rows' forces are large and opposite and
  // their split carries any order's last bits: the scalar step started a last bit off moves them
  // by 0.4e-12 to 3.3e-12 where q, qd move by 1e-13. So the forces are bounded by twice that
  // spread of their own (at least 1e-12), q and qd by 1e-12.
  const double own = std::max(1e-12, test::own_force_spread(alone, 1000, command));
  test::LaneWorst worst;
  test::step_with_commands(batch, alone, 1000, command);
  for (int e = 0; e < kEnvironments; ++e)
    test::compare_with_alone(batch, e, alone[static_cast<size_t>(e)], worst, to_string(solver));
  EXPECT_LE(worst.state, 1e-12);
  EXPECT_LE(worst.force, 2.0 * own);
  EXPECT_GT(alone[0].actuator_force().cwiseAbs().maxCoeff(), 0.0);
  std::printf("lanes with delays and actuators, %s: q, qd %.1e, forces %.1e, the scalar step's "
              "own from a start a last bit off %.1e (docs/simd_batch.md)\n",
              to_string(solver), worst.state, worst.force, own);
}

// The same through Batch's own setters (set_drive_targets, set_drive_delay, reset), which never
// hand an environment out: the lanes' packed targets follow the delays set and removed.
TEST_P(LaneControl, BatchSettersAndResetWithinTolOfSimulation) {
  const SolverType solver = GetParam();
  const Simulation prototype = control_prototype(12, solver);
  const int nv = prototype.model().nv;
  Batch batch(prototype, kEnvironments);
  std::vector<Simulation> alone(kEnvironments, prototype);
  std::vector<int> all(kEnvironments);
  for (int e = 0; e < kEnvironments; ++e) all[static_cast<size_t>(e)] = e;
  RowMatrix delays(kEnvironments, nv);
  for (int e = 0; e < kEnvironments; ++e)
    for (int d = 0; d < nv; ++d) delays(e, d) = (e + 2 * d) % 5;
  auto set_delays = [&] {
    batch.set_drive_delay(all, delays);
    for (int e = 0; e < kEnvironments; ++e)
      for (int d = 0; d < nv; ++d)
        alone[static_cast<size_t>(e)].set_drive_delay(d, static_cast<int>(delays(e, d)));
  };
  set_delays();
  EXPECT_NE(batch.step_path().find(" lanes"), std::string::npos) << batch.step_path();
  RowMatrix xt(kEnvironments, nv), vt(kEnvironments, nv);
  test::LaneWorst worst;
  for (int k = 0; k < 100; ++k) {
    for (int e = 0; e < kEnvironments; ++e)
      for (int d = 0; d < nv; ++d) {
        xt(e, d) = 0.3 * std::sin(0.11 * k + d + e);
        vt(e, d) = 0.1 * std::cos(0.13 * k + d);
        alone[static_cast<size_t>(e)].set_drive_target(d, xt(e, d), vt(e, d));
      }
    batch.set_drive_targets(xt, vt);
    if (k == 40) {  // some delays removed, others changed: histories start over
      for (int d = 0; d < nv; d += 2) delays.col(d).setZero();
      delays.col(1).setConstant(2.0);
      set_delays();
    }
    if (k == 70) {  // an episode starting over for some environments
      const std::vector<int> reset = {1, 4};
      batch.reset(reset);
      for (int e : reset) {
        Simulation fresh = prototype;
        fresh.set_qd(VecX::Zero(nv));  // reset's default
        for (int d = 0; d < nv; ++d) {
          fresh.set_drive_delay(d, static_cast<int>(delays(e, d)));
          fresh.set_drive_target(d, xt(e, d), vt(e, d));
        }
        alone[static_cast<size_t>(e)] = fresh;
      }
    }
    batch.step(10);
    for (Simulation& s : alone) s.step(10);
  }
  // Environment 0 stepped only through the batch's setters: never handed out before this.
  for (int e = 0; e < kEnvironments; ++e)
    test::compare_with_alone(batch, e, alone[static_cast<size_t>(e)], worst, to_string(solver));
  EXPECT_LE(worst.state, 1e-12);
  EXPECT_LE(worst.force, 1e-12);
  std::printf("lanes with Batch's delay setters and reset, %s: q, qd %.1e, forces %.1e\n",
              to_string(solver), worst.state, worst.force);
}

// One environment diverges (an actuator far too stiff for dt): it stops at that step with the
// state before it and its pushes taken back, and pushes no more in the call; the others make
// every step; the batch throws as Batch::step does.
TEST_P(LaneControl, DivergingEnvironmentTakesItsPushesBack) {
  const SolverType solver = GetParam();
  const Simulation prototype = control_prototype(13, solver);
  Batch batch(prototype, kEnvironments);
  std::vector<Simulation> alone = test::give_each(batch, prototype, give_control);
  // Environment 3's dof 0: an unclipped ideal PD with one step of delay, which the batch and
  // the lone Simulation step 5 times before it is told a target it cannot follow.
  const int bad = 3;
  ExplicitActuator wild = actuator_of_kind(0, 1);
  wild.effort_limit = kInf;
  batch.sim(bad).set_actuator(0, wild);
  alone[bad].set_actuator(0, wild);
  for (int e = 0; e < kEnvironments; ++e) {
    command(batch.sim(e), e, 0);
    command(alone[static_cast<size_t>(e)], e, 0);
  }
  EXPECT_NE(batch.step_path().find(" lanes"), std::string::npos) << batch.step_path();
  batch.step(5);
  for (Simulation& s : alone) s.step(5);
  batch.sim(bad).set_drive_target(0, 1e308, 0.0);
  alone[bad].set_drive_target(0, 1e308, 0.0);
  std::string alone_error;
  for (int e = 0; e < kEnvironments; ++e) {
    try {
      alone[static_cast<size_t>(e)].step(30);
    } catch (const DivergenceError& error) {
      ASSERT_EQ(e, bad) << error.what();
      alone_error = error.what();
    }
  }
  ASSERT_FALSE(alone_error.empty());
  try {
    batch.step(30);
    ADD_FAILURE() << "no divergence";
  } catch (const DivergenceError& error) {
    EXPECT_EQ(std::string(error.what()),
              "batch copy 3 (1 of 7 copies diverged): " + alone_error);
  }
  // It made the step that pushed the target (seen a step later) and none after the next.
  EXPECT_EQ(alone[bad].step_count(), 6);
  EXPECT_EQ(alone[bad].actuators().pushes(0), 6);
  test::LaneWorst worst;
  for (int e = 0; e < kEnvironments; ++e)
    test::compare_with_alone(batch, e, alone[static_cast<size_t>(e)], worst, to_string(solver));
  EXPECT_LE(worst.state, 1e-12);
  EXPECT_LE(worst.force, 1e-12);
  EXPECT_EQ(batch.sim(0).step_count(), 35);
}

INSTANTIATE_TEST_SUITE_P(Solvers, LaneControl, testing::Values(SolverType::pgs, SolverType::tgs),
                         [](const testing::TestParamInfo<SolverType>& info) {
                           return std::string(to_string(info.param));
                         });

// The step guard with the control stages (docs/simd_batch.md, "The step guard"): guarded
// environments, whose joints now and then move more than its bound in a step, step in the lanes
// within 1e-12 of each stepped alone, redoing the same steps with the step's (delayed) commands
// and actuators re-evaluated per sub-step; unguarded ones beside them.
TEST(LaneControlGuard, GuardedEnvironmentsStepAsSimulation) {
  for (const SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    const Simulation prototype = control_prototype(14, solver);
    Batch batch(prototype, kEnvironments);
    std::vector<Simulation> alone = test::give_each(batch, prototype, [](Simulation& s, int e) {
      give_control(s, e);
      if (e % 2 == 1) return;
      SimulationOptions o = s.options();
      o.guard.enabled = true;
      o.guard.max_joint_step = 0.008;
      s.set_options(o);
    });
    EXPECT_NE(batch.step_path().find(" lanes"), std::string::npos) << batch.step_path();
    test::LaneWorst worst;
    test::step_with_commands(batch, alone, 300, command);
    long triggers = 0;
    for (int e = 0; e < kEnvironments; ++e) {
      const Simulation& a = alone[static_cast<size_t>(e)];
      test::compare_with_alone(batch, e, a, worst, to_string(solver));
      EXPECT_EQ(batch.sim(e).guard_triggers(), a.guard_triggers()) << e;
      EXPECT_NEAR(batch.sim(e).guard_account().scale, a.guard_account().scale,
                  1e-12 * std::max(1.0, a.guard_account().scale)) << e;
      triggers += a.guard_triggers();
    }
    std::printf("%s, guarded: state %.1e, forces %.1e, %ld steps redone (docs/simd_batch.md)\n",
                to_string(solver), worst.state, worst.force, triggers);
    EXPECT_GT(triggers, 0) << to_string(solver);
    EXPECT_LE(worst.state, 1e-12) << to_string(solver);
    EXPECT_LE(worst.force, 1e-12) << to_string(solver);
  }
}

}  // namespace
}  // namespace lane_control
}  // namespace featherdrive
