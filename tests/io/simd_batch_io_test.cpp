// The SIMD Batch on the robots of the examples, loaded through io: within 1e-12 of the scalar
// Simulation over 1000 steps (different operation order: docs/simd_batch.md, "Determinism").
#include <gtest/gtest.h>

#include <cstdio>

#include "featherdrive/io/scene.hpp"
#include "featherdrive/io/urdf.hpp"
#include "featherdrive/sim/simd_batch.hpp"
#include "support/source_tree.hpp"

namespace featherdrive {
namespace {

// The largest |a - b| / max(1, |b|) of every environment's row against the scalar vector.
double worst_against(const RowMatrix& a, const VecView& b) {
  double worst = 0.0;
  for (Eigen::Index e = 0; e < a.rows(); ++e)
    for (Eigen::Index k = 0; k < a.cols(); ++k)
      worst = std::max(worst, std::abs(a(e, k) - b[k]) / std::max(1.0, std::abs(b[k])));
  return worst;
}

void expect_within_1e12(Simulation sim, int steps, const std::string& what) {
  for (SimdIsa isa : available_simd_isas()) {
    SimdBatch simd(sim, 3, isa);
    simd.step(steps);
    Simulation scalar = sim;
    scalar.step(steps);
    EXPECT_LE(worst_against(simd.q(), scalar.q()), 1e-12) << what << ", " << to_string(isa);
    EXPECT_LE(worst_against(simd.qd(), scalar.qd()), 1e-12) << what << ", " << to_string(isa);
    EXPECT_LE(worst_against(simd.drive_force(), scalar.drive_force()), 1e-12)
        << what << ", " << to_string(isa);
    EXPECT_LE(worst_against(simd.limit_force(), scalar.limit_force()), 1e-12)
        << what << ", " << to_string(isa);
    EXPECT_LE(worst_against(simd.friction_force(), scalar.friction_force()), 1e-12)
        << what << ", " << to_string(isa);
    if (isa == SimdIsa::sse2)  // every width gives the same bits (simd_batch_test.cpp)
      std::printf(
          "%s: q, qd %.1e, drive force %.1e (docs/simd_batch.md)\n", what.c_str(),
          std::max(worst_against(simd.q(), scalar.q()), worst_against(simd.qd(), scalar.qd())),
          worst_against(simd.drive_force(), scalar.drive_force()));
  }
}

// examples/arm7.urdf with its joint limits and friction (URDF <dynamics>), without its velocity
// limits (which the SIMD Batch refuses), targets near the limits, PGS and TGS, 1000 steps of
// 1/240 s.
TEST(SimdBatchRobots, Arm7WithinTolOfSimulation) {
  const UrdfRobot robot = load_urdf(test::kExamples + "arm7.urdf");
  for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    SimulationOptions o;
    o.dt = 1.0 / 240.0;
    o.solver = solver;
    Simulation sim(robot.model, o);
    for (int d = 0; d < robot.model->nv; ++d) {
      sim.set_max_joint_velocity(d, std::numeric_limits<double>::infinity());
      const double upper = sim.upper_limit(d);
      sim.set_drive(d,
                    Drive{d % 2 ? DriveType::acceleration : DriveType::force, d % 2 ? 400.0 : 2e4,
                          d % 2 ? 40.0 : 300.0, 150.0, 0.9 * upper * (d % 3 ? 1.0 : -1.0), 0.0});
    }
    expect_within_1e12(sim, 1000, std::string("arm7 ") + to_string(solver));
  }
}

// examples/humanoid_hold.yaml: MuJoCo's humanoid (MJCF through MuJoCo's compiler), torso welded,
// force drives on its 21 hinges (general axes, branches), MJCF joint damping as viscous friction,
// TGS, 1000 steps.
TEST(SimdBatchRobots, HumanoidHoldWithinTolOfSimulation) {
  const Scene scene = load_scene(test::kExamples + "humanoid_hold.yaml");
  expect_within_1e12(make_simulation(scene), 1000, "humanoid_hold");
}

}  // namespace
}  // namespace featherdrive
