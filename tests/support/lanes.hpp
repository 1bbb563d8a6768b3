// Batch's SIMD lanes against the scalar step: every environment of a lane Batch of a prototype
// against the prototype stepped alone as a Simulation (another operation order).
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <string>

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

}  // namespace featherdrive::test
