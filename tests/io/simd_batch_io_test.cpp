// The SIMD Batch on the robots of the examples, loaded through io: within 1e-12 of the scalar
// Simulation over 1000 steps (different operation order: docs/simd_batch.md, "Determinism").
#include <gtest/gtest.h>

#include <cstdio>

#include "featherdrive/io/scene.hpp"
#include "featherdrive/io/urdf.hpp"
#include "featherdrive/sim/link_parameters.hpp"
#include "featherdrive/sim/simd_batch.hpp"
#include "support/compare.hpp"
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

// Returns the largest |velocity limit force| of the first 100 steps (scalar).
double expect_within_1e12(Simulation sim, int steps, const std::string& what) {
  double velocity_limited = 0.0;
  for (SimdIsa isa : available_simd_isas()) {
    SimdBatch simd(sim, 3, isa);
    simd.step(steps);
    Simulation scalar = sim;
    for (int s = 0; s < steps; ++s) {
      scalar.step();
      if (s < 100)
        velocity_limited =
            std::max(velocity_limited, scalar.velocity_limit_force().cwiseAbs().maxCoeff());
    }
    EXPECT_LE(worst_against(simd.q(), scalar.q()), 1e-12) << what << ", " << to_string(isa);
    EXPECT_LE(worst_against(simd.qd(), scalar.qd()), 1e-12) << what << ", " << to_string(isa);
    EXPECT_LE(worst_against(simd.drive_force(), scalar.drive_force()), 1e-12)
        << what << ", " << to_string(isa);
    EXPECT_LE(worst_against(simd.limit_force(), scalar.limit_force()), 1e-12)
        << what << ", " << to_string(isa);
    EXPECT_LE(worst_against(simd.friction_force(), scalar.friction_force()), 1e-12)
        << what << ", " << to_string(isa);
    EXPECT_LE(worst_against(simd.velocity_limit_force(), scalar.velocity_limit_force()), 1e-12)
        << what << ", " << to_string(isa);
    if (isa == SimdIsa::sse2)  // every width gives the same bits (simd_batch_test.cpp)
      std::printf(
          "%s: q, qd %.1e, drive force %.1e (docs/simd_batch.md)\n", what.c_str(),
          std::max(worst_against(simd.q(), scalar.q()), worst_against(simd.qd(), scalar.qd())),
          worst_against(simd.drive_force(), scalar.drive_force()));
  }
  return velocity_limited;
}

// A robot as loaded, stepped at 1/240 s by the solver.
Simulation at_240_hz(const UrdfRobot& robot, SolverType solver) {
  SimulationOptions o;
  o.dt = 1.0 / 240.0;
  o.solver = solver;
  return Simulation(robot.model, o);
}

// examples/arm7.urdf as loaded: its joint limits, friction (URDF <dynamics>), effort and
// velocity limits; targets near the limits, PGS and TGS, 1000 steps of 1/240 s.
TEST(SimdBatchRobots, Arm7WithinTolOfSimulation) {
  const UrdfRobot robot = load_urdf(test::kExamples + "arm7.urdf");
  for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    Simulation sim = at_240_hz(robot, solver);
    for (int d = 0; d < robot.model->nv; ++d) {
      const double upper = sim.upper_limit(d);
      sim.set_drive(d,
                    Drive{d % 2 ? DriveType::acceleration : DriveType::force, d % 2 ? 400.0 : 2e4,
                          d % 2 ? 40.0 : 300.0, 150.0, 0.9 * upper * (d % 3 ? 1.0 : -1.0), 0.0});
    }
    // The drives pull the joints faster than their URDF velocity limits allow.
    EXPECT_GT(expect_within_1e12(sim, 1000, std::string("arm7 ") + to_string(solver)), 1.0);
  }
}

// DART's KUKA KR5 and Barrett WAM as loaded (their URDF velocity and effort limits on), force
// drives (their URDF efforts as max_force) towards a pose 0.5 rad away, PGS and TGS, 1000 steps of
// 1/240 s.
TEST(SimdBatchRobots, DartArmsAsLoadedWithinTolOfSimulation) {
  const std::string dart = "/usr/share/doc/dart/data/urdf/";
  for (const std::string file : {"KR5/KR5 sixx R650.urdf", "wam/wam.urdf"}) {
    const UrdfRobot robot = load_urdf(dart + file);
    for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
      Simulation sim = at_240_hz(robot, solver);
      for (int d = 0; d < robot.model->nv; ++d) {
        const double effort = robot.model->effort_limit[d];  // KR5's are 0: none
        sim.set_drive(d, Drive{DriveType::force, 2e3, 100.0, effort > 0.0 ? effort : test::kInf,
                               d % 2 ? 0.5 : -0.5, 0.0});
      }
      const double limited = expect_within_1e12(sim, 1000, file + " " + to_string(solver));
      std::printf("%s %s: largest velocity limit force %.3g\n", file.c_str(), to_string(solver),
                  limited);
    }
  }
}

// The same arms with PhysX 5.6.1's defaults for what a URDF does not say (physx_default: every
// link's cfm_scale, damping and velocity limits, every joint's friction coefficient), the values
// an Isaac Lab robot carries, without compat physx's departures: the lanes as Simulation.
TEST(SimdBatchRobots, DartArmsWithPhysxDefaultsWithinTolOfSimulation) {
  const std::string dart = "/usr/share/doc/dart/data/urdf/";
  for (const std::string file : {"KR5/KR5 sixx R650.urdf", "wam/wam.urdf"}) {
    const UrdfRobot robot = load_urdf(dart + file);
    for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
      Simulation sim = at_240_hz(robot, solver);
      for (int i = 0; i < robot.model->num_links(); ++i)
        sim.set_link_parameters(i, physx_default::link());
      for (int d = 0; d < robot.model->nv; ++d) {
        sim.set_friction_coefficient(d, physx_default::friction_coefficient);
        sim.set_drive(d, Drive{DriveType::force, 2e3, 100.0, test::kInf, d % 2 ? 0.5 : -0.5, 0.0});
      }
      expect_within_1e12(sim, 1000, file + " with PhysX's defaults " + to_string(solver));
    }
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
