// compat: physx in Batch's SIMD lanes, each environment against its Simulation stepped alone
// (another operation order), within 1e-12 over 1000 steps. On a fixed base PhysX's defaults are
// settings (wrapped revolute joints, link cfm, damping and velocity limits, friction coefficient
// 0.05) and its departures act at prismatic joints only (docs/math/physx_departures.md, PD-1 to
// PD-3): a revolute row's link bias is 0.
#include <gtest/gtest.h>

#include <cstdio>
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

// DART's KUKA KR5 and Barrett WAM as loaded (their URDF velocity and effort limits), compat physx
// with PhysX's defaults for the rest, force drives towards a pose 0.5 rad away, PGS and TGS.
TEST(LaneCompatPhysx, DartArmsAsSimulation) {
  const std::string dart = "/usr/share/doc/dart/data/urdf/";
  for (const std::string file : {"KR5/KR5 sixx R650.urdf", "wam/wam.urdf"}) {
    const UrdfRobot robot = load_urdf(dart + file);
    for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
      SimulationOptions o;
      o.dt = 1.0 / 240.0;
      o.solver = solver;
      o.compat = Compat::physx;
      Simulation sim(robot.model, o);
      // The defaults compat physx brings are on: wrapped revolute joints, link damping.
      ASSERT_EQ(sim.settings().revolute_wrap[0], RevoluteWrap::wrapped);
      ASSERT_GT(sim.link_parameters(1).angular_damping, 0.0);
      for (int d = 0; d < robot.model->nv; ++d) {
        const double effort = robot.model->effort_limit[d];  // KR5's are 0: none
        sim.set_drive(d, Drive{DriveType::force, 2e3, 100.0, effort > 0.0 ? effort : test::kInf,
                               d % 2 ? 0.5 : -0.5, 0.0});
      }
      expect_lanes_as_alone(sim, 1000, file + ", compat physx, " + to_string(solver));
    }
  }
}

// examples/humanoid_hold.yaml (MuJoCo's humanoid, torso welded, 21 hinges) with compat physx.
TEST(LaneCompatPhysx, HumanoidHoldAsSimulation) {
  Scene scene = load_scene(test::kExamples + "humanoid_hold.yaml");
  scene.options.compat = Compat::physx;
  expect_lanes_as_alone(make_simulation(scene), 1000, "humanoid_hold, compat physx");
}

}  // namespace
}  // namespace featherdrive
