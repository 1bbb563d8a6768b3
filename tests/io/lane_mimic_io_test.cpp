// Mimic rows in Batch's SIMD lanes on robots loaded through io, against each environment stepped
// alone as a Simulation (another operation order): within 1e-12 over 1000 steps.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "featherdrive/io/urdf.hpp"
#include "featherdrive/sim/batch.hpp"
#include "support/compare.hpp"
#include "support/lanes.hpp"
#include "support/source_tree.hpp"

namespace featherdrive {
namespace {

using test::expect_lanes_as_alone;

// Issue 32's case: examples/arm7.urdf as loaded (its limits, friction, effort and velocity
// limits) with joint3 following joint2 (q3 = 1.5 q2), force drives on the others towards +-0.2
// rad. The lanes once stepped this uncoupled, 0.55 rad away from Simulation in 120 steps. (Towards
// +-0.5 rad the row drives joint3 into its velocity limit, and TGS's path there grows any 1e-15
// to 1e-12 within 37 steps: Simulation's own path, not the lanes'.)
TEST(LaneMimicRobots, Arm7WithAMimicJointAsSimulation) {
  const UrdfRobot robot = load_urdf(test::kExamples + "arm7.urdf");
  const Model& m = *robot.model;
  for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    SimulationOptions o;
    o.dt = 1.0 / 240.0;
    o.solver = solver;
    Simulation sim(robot.model, o);
    const int follower = m.dof_index("joint3"), leader = m.dof_index("joint2");
    for (int d = 0; d < m.nv; ++d)
      if (d != follower)
        sim.set_drive(d, Drive{DriveType::force, 2e3, 100.0, 150.0, d % 2 ? 0.2 : -0.2, 0.0});
    sim.set_mimic_joints({{follower, leader, -1.5, 0.0}});
    expect_lanes_as_alone(sim, 1000,
                          std::string("arm7, joint3 = 1.5 joint2, ") + to_string(solver));
  }
}

// tests/data/mimic_gripper.urdf as loaded: two <mimic> rows (a prismatic pair; a knuckle whose
// velocity limit contradicts its row), the wrist swinging and the left finger driven; compat none
// and physx, whose prismatic fingers' rows see PhysX's link bias (PD-1, PD-2), whose TGS position
// change is measured from the links' centres of mass (PD-3) and whose positions are clamped to
// their limits.
TEST(LaneMimicRobots, UrdfGripperAsSimulation) {
  const UrdfRobot robot = load_urdf(test::kSourceDir + "/tests/data/mimic_gripper.urdf");
  const Model& m = *robot.model;
  for (Compat compat : {Compat::none, Compat::physx})
    for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
      SimulationOptions o;
      o.dt = 0.01;
      o.solver = solver;
      o.position_iterations = 8;
      o.velocity_iterations = 2;
      o.compat = compat;
      Simulation sim(robot.model, o);
      sim.set_mimic_joints(robot.mimic_joints);
      sim.set_drive(m.dof_index("wrist"), Drive{DriveType::force, 5.0, 0.5, test::kInf, 0.8, 0.0});
      sim.set_drive(m.dof_index("left_finger"),
                    Drive{DriveType::force, 400.0, 20.0, test::kInf, 0.03, 0.0});
      VecX qd = VecX::Zero(m.nv);
      qd[m.dof_index("wrist")] = 3.0;  // a swinging hand: the fingers' link bias is not 0
      sim.set_qd(qd);
      expect_lanes_as_alone(
          sim, 1000,
          std::string("mimic gripper, compat ") + to_string(compat) + ", " + to_string(solver));
    }
}

}  // namespace
}  // namespace featherdrive
