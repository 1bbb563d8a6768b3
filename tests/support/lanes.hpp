// Batch's SIMD lanes against the scalar step: every environment of a lane Batch of a prototype
// against the prototype stepped alone as a Simulation (another operation order).
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include "featherdrive/sim/batch.hpp"
#include "support/compare.hpp"

namespace featherdrive::test {

/// The random trees' options in the lane tests: dt 5 ms, 4 position and 1 velocity iterations.
inline SimulationOptions lane_test_options(SolverType solver) {
  SimulationOptions o;
  o.dt = 0.005;
  o.solver = solver;
  o.position_iterations = 4;
  o.velocity_iterations = 1;
  return o;
}

/// Steps `count` copies of sim in lanes (asserting they do) and sim alone `steps` times; returns
/// the largest relative difference of q, qd and the output forces, printed as "what: ...".
inline double lanes_against_alone(const Simulation& sim, int steps, const std::string& what,
                                  int count = 5) {
  Batch lanes(sim, count);
  EXPECT_NE(lanes.step_path().find("lanes"), std::string::npos) << what << lanes.step_path();
  Simulation alone = sim;
  lanes.step(steps);
  alone.step(steps);
  double worst = 0.0;
  auto compare = [&](const RowMatrix& a, const VecView& b) {
    for (int e = 0; e < lanes.size(); ++e)
      worst = std::max(worst, relative_difference(a.row(e), b.transpose()));
  };
  compare(lanes.q(), alone.q());
  compare(lanes.qd(), alone.qd());
  compare(lanes.drive_force(), alone.drive_force());
  compare(lanes.limit_force(), alone.limit_force());
  compare(lanes.friction_force(), alone.friction_force());
  compare(lanes.velocity_limit_force(), alone.velocity_limit_force());
  std::printf("%s: largest relative difference %.1e (docs/simd_batch.md)\n", what.c_str(), worst);
  return worst;
}

/// Three mimic rows on a random tree of at least 6 dofs: two rigid, one soft.
inline void set_three_mimic_rows(Simulation& sim) {
  const int nv = sim.model().nv;
  EXPECT_GE(nv, 6);
  sim.set_mimic_joints({{1, 0, -1.5, 0.05},
                        {4, 2, 0.8, -0.1},
                        {nv - 1, 3, -1.0, 0.0, /*natural_frequency=*/30.0, /*damping_ratio=*/0.7}});
}

/// give(sim, e) applied to every environment e of the batch and to a copy of the prototype per
/// environment, which are returned: the environments to step alone.
template <class Give>
std::vector<Simulation> give_each(Batch& batch, const Simulation& prototype, Give give) {
  std::vector<Simulation> alone;
  for (int e = 0; e < batch.size(); ++e) {
    give(batch.sim(e), e);
    alone.push_back(prototype);
    give(alone.back(), e);
  }
  return alone;
}

/// `steps` steps of the batch and of each environment's Simulation alone, in calls of 1 to 9
/// steps, call k's targets from command(sim, environment, k) in both.
template <class Command>
void step_with_commands(Batch& batch, std::vector<Simulation>& alone, int steps,
                        Command command) {
  for (int k = 0, done = 0; done < steps; ++k) {
    const int n = std::min(1 + k % 9, steps - done);
    for (int e = 0; e < batch.size(); ++e) {
      command(batch.sim(e), e, k);
      command(alone[static_cast<size_t>(e)], e, k);
    }
    batch.step(n);
    for (Simulation& s : alone) s.step(n);
    done += n;
  }
}

/// The largest differences of a batch's environments from their Simulations stepped alone.
struct LaneWorst {
  double state = 0.0;   ///< q, qd
  double force = 0.0;   ///< every output force, the actuators' too
  double change = 0.0;  ///< last_drive_impulse_change (convergence tracking)
};

/// Environment e of the batch against `alone` (its settings, stepped alone): q, qd, every output
/// force and the tracked drive changes into `worst` (|a - b| / max(1, |b|)); the clock and the
/// delay and actuator histories (what a checkpoint of sim(e) writes) exactly.
inline void compare_with_alone(const Batch& batch, int e, const Simulation& alone,
                               LaneWorst& worst, const std::string& what) {
  const Simulation& s = batch.sim(e);
  worst.state = std::max({worst.state, relative_difference(s.q(), alone.q()),
                          relative_difference(s.qd(), alone.qd())});
  worst.force =
      std::max({worst.force, relative_difference(s.drive_force(), alone.drive_force()),
                relative_difference(s.limit_force(), alone.limit_force()),
                relative_difference(s.friction_force(), alone.friction_force()),
                relative_difference(s.velocity_limit_force(), alone.velocity_limit_force()),
                relative_difference(s.actuator_force(), alone.actuator_force())});
  worst.change = std::max(worst.change, relative_difference(s.last_drive_impulse_change(),
                                                            alone.last_drive_impulse_change()));
  // relative_difference passes NaN over: every compared value must be finite.
  ASSERT_TRUE(s.q().allFinite() && s.qd().allFinite() && s.actuator_force().allFinite() &&
              s.last_drive_impulse_change().allFinite())
      << what << " env " << e;
  ASSERT_EQ(s.step_count(), alone.step_count()) << what << " env " << e;
  ASSERT_EQ(s.track_convergence(), alone.track_convergence()) << what << " env " << e;
  for (int d = 0; d < s.model().nv; ++d) {
    ASSERT_EQ(s.drive_delays().pushes(d), alone.drive_delays().pushes(d)) << what << " dof " << d;
    if (alone.drive_delays().delayed(d))
      for (size_t k = 0; k < alone.drive_delays().ring(d).size(); ++k) {
        EXPECT_EQ(s.drive_delays().ring(d)[k].position, alone.drive_delays().ring(d)[k].position);
        EXPECT_EQ(s.drive_delays().ring(d)[k].velocity, alone.drive_delays().ring(d)[k].velocity);
      }
    ASSERT_EQ(s.actuators().pushes(d), alone.actuators().pushes(d)) << what << " dof " << d;
    if (alone.has_actuator(d))  // the commands as set: the same bits
      for (size_t k = 0; k < alone.actuators().ring(d).size(); ++k) {
        EXPECT_EQ(s.actuators().ring(d)[k].position, alone.actuators().ring(d)[k].position);
        EXPECT_EQ(s.actuators().ring(d)[k].effort, alone.actuators().ring(d)[k].effort);
      }
  }
}

}  // namespace featherdrive::test
