// examples/spherical_wrist.yaml (an arm with a spherical wrist driven per axis, limits on two
// axes) in Batch's SIMD lanes against the prototype stepped alone as a Simulation, within 1e-12
// over 1000 steps: docs/simd_batch.md, "Spherical joints".
#include <gtest/gtest.h>

#include <string>

#include "featherdrive/io/scene.hpp"
#include "featherdrive/sim/batch.hpp"
#include "support/lanes.hpp"
#include "support/source_tree.hpp"

namespace featherdrive {
namespace {

TEST(LaneSphericalRobots, SphericalWristAsSimulation) {
  Scene scene = load_scene(test::kExamples + "spherical_wrist.yaml");
  for (Compat compat : {Compat::none, Compat::physx})  // the file's is physx
    for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
      scene.options.compat = compat;
      scene.options.solver = solver;
      test::expect_lanes_as_alone(
          make_simulation(scene), 1000,
          "spherical_wrist, compat " + std::string(to_string(compat)) + ", " + to_string(solver));
    }
}

}  // namespace
}  // namespace featherdrive
