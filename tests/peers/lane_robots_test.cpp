// Batch's SIMD lanes on real robots with a floating base (and the same robots fixed), each
// environment against the prototype stepped alone as a Simulation (another operation order),
// within 1e-12 over 1000 steps: docs/simd_batch.md, "Floating bases". In the main build only
// (seconds there, minutes under the sanitizers); the random floating trees of
// tests/sim/lane_floating_test.cpp run in both.
#include <gtest/gtest.h>

#include <string>

#include "featherdrive/io/scene.hpp"
#include "featherdrive/io/urdf.hpp"
#include "featherdrive/sim/batch.hpp"
#include "support/compare.hpp"
#include "support/lanes.hpp"
#include "support/source_tree.hpp"

namespace featherdrive {
namespace {

using test::expect_lanes_as_alone;

// DART's Atlas (v3, no head) and DRC-Hubo as loaded (their URDF velocity limits on), fixed and
// floating (no ground: a floating robot falls), every dof driven to hold its start pose with
// PD gains of the robot's size, at 5 ms: floating with PGS and TGS, fixed with TGS.
TEST(LaneFloatingRobots, AtlasAndDrcHuboAsSimulation) {
  const std::string dart = "/usr/share/doc/dart/data/";
  for (const std::string file : {"sdf/atlas/atlas_v3_no_head.urdf", "urdf/drchubo/drchubo.urdf"})
    for (const bool fixed : {true, false})
      for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
        if (fixed && solver == SolverType::pgs) continue;
        UrdfOptions options;
        options.fixed_base = fixed;
        const UrdfRobot robot = load_urdf(dart + file, options);
        ASSERT_EQ(robot.model->floating_base(), !fixed);
        SimulationOptions o = test::lane_test_options(solver);
        Simulation sim(robot.model, o);
        for (const Link& link : robot.model->links)
          if (link.joint_type == JointType::revolute || link.joint_type == JointType::prismatic)
            sim.set_drive(link.v_index, Drive{DriveType::force, 800.0, 40.0, test::kInf,
                                              0.1 * ((link.v_index % 3) - 1), 0.0});
        expect_lanes_as_alone(sim, 1000,
                              file + (fixed ? ", fixed, " : ", floating, ") + to_string(solver));
      }
}

// MuJoCo's humanoid (MJCF through MuJoCo's compiler) on its free joint, falling with every hinge
// held by a force drive (examples/humanoid_hold.yaml with the torso free).
TEST(LaneFloatingRobots, MujocoHumanoidFreeAsSimulation) {
  Scene scene = load_scene(test::kSourceDir + "/tests/data/humanoid_free.yaml");
  for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    scene.options.solver = solver;
    const Simulation sim = make_simulation(scene);
    ASSERT_TRUE(sim.model().floating_base());
    expect_lanes_as_alone(sim, 1000, std::string("humanoid, free, ") + to_string(solver));
  }
}

// compat physx: PhysX's defaults and its floating-root departures (momentum corrections, the root
// moved about its centre of mass: docs/math/physx_departures.md, section 2). Atlas without
// gravity (tests/sim/lane_floating_test.cpp says why: falling, it drifts 6.9e-12 in PGS).
TEST(LaneFloatingRobots, CompatPhysxAsSimulation) {
  const std::string dart = "/usr/share/doc/dart/data/";
  for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    UrdfOptions options;
    options.fixed_base = false;
    options.gravity = Vec3::Zero();
    const UrdfRobot robot = load_urdf(dart + "sdf/atlas/atlas_v3_no_head.urdf", options);
    SimulationOptions o = test::lane_test_options(solver);
    o.compat = Compat::physx;
    Simulation sim(robot.model, o);
    for (const Link& link : robot.model->links)
      if (link.joint_type == JointType::revolute)
        sim.set_drive(link.v_index, Drive{DriveType::force, 800.0, 40.0, test::kInf,
                                          0.1 * ((link.v_index % 3) - 1), 0.0});
    expect_lanes_as_alone(sim, 1000,
                          "atlas, floating, compat physx, " + std::string(to_string(solver)));
    Scene scene = load_scene(test::kSourceDir + "/tests/data/humanoid_free.yaml");
    scene.options.solver = solver;
    scene.options.compat = Compat::physx;
    expect_lanes_as_alone(make_simulation(scene), 1000,
                          "humanoid, free, compat physx, " + std::string(to_string(solver)));
  }
}

}  // namespace
}  // namespace featherdrive
