// The robots of the benchmarks, built once and shared by every engine: the N-link spatial chain,
// the 7-dof arm of examples/arm7.urdf and a floating 30-dof humanoid-like tree. docs/benchmarks.md.
#pragma once

#include <memory>
#include <string>

#include "featherdrive/sim/simulation.hpp"

namespace featherdrive::bench {

/// Every benchmark steps with this time step, every engine alike.
constexpr double kDt = 1.0e-3;
/// Drive gains on every revolute joint, every engine alike.
constexpr double kStiffness = 1000.0;  // Nm/rad
constexpr double kDamping = 50.0;      // Nms/rad
/// All engines restart from the initial state every kResetInterval steps (the floating humanoid
/// falls under gravity and no engine's cost depends on where it is, but numbers stay ordinary).
constexpr int kResetInterval = 1000;

struct BenchRobot {
  std::string name;
  std::shared_ptr<const Model> model;
  VecX q0;       ///< initial configuration (nq)
  VecX target;   ///< drive target per dof (nv); 0 on the floating root's dofs (no drive)
};

/// N links of 1 kg and 0.5 m (solid cylinders of radius 0.05 along -z, centre of mass at the
/// middle) hanging from a fixed base, revolute axes cycling y, z, x; targets uniform in
/// [-0.5, 0.5] rad from a fixed seed.
BenchRobot make_chain(int n);

/// examples/arm7.urdf (FEATHERDRIVE_SOURCE_DIR) through featherdrive_io, with the URDF's joint
/// limits, damping, friction and velocity limits removed so that every engine simulates the same
/// drives-only model. Fixed base.
BenchRobot make_arm7();

/// A floating torso (6 dofs) with a 2-dof waist, a 2-dof neck, two 6-dof legs and two 4-dof arms:
/// 24 revolute joints, 30 dofs, 25 links, about 70 kg.
BenchRobot make_humanoid();

/// Drives of kStiffness / kDamping towards robot.target on every revolute joint.
void add_drives(Simulation& sim, const BenchRobot& robot);

/// The benchmarks' Simulation of robot: the solver with 4 position and 1 velocity iterations at
/// kDt, add_drives, at q0.
Simulation bench_simulation(const BenchRobot& robot, SolverType solver = SolverType::pgs);

/// Is the dof a driven revolute joint?
bool is_driven(const Model& model, int dof);

}  // namespace featherdrive::bench
