// Revolute wrap and applied joint forces against PhysX 5.6.1 itself (issue 17; the harness runs
// eREVOLUTE or eREVOLUTE_UNWRAPPED per joint and sets the articulation cache's jointForce), free-
// running: within 1e-4 of PhysX's largest |q| and |qd| (docs/physx_parity.md).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>

#include "featherdrive/io/physx_runner.hpp"
#include "featherdrive/io/physx_scene.hpp"
#include "featherdrive/model/model_builder.hpp"
#include "support/compare.hpp"
#include "support/models.hpp"

namespace featherdrive {
namespace {

// Two wheels on a fixed base, turning about z (their centres of mass on the axis: gravity does
// not turn them), and a slider.
std::shared_ptr<const Model> wheels_and_slider() {
  ModelBuilder b;
  b.set_gravity(Vec3(0, 0, -9.81));
  b.add_link(make_link("base", "", 2.0, Vec3::Zero(), test::box_inertia(2.0, Vec3(0.3, 0.3, 0.1)),
                       fixed_joint("fix")));
  b.add_link(make_link("wheel", "base", 1.0, Vec3::Zero(), Vec3(0.02, 0.02, 0.04).asDiagonal(),
                       revolute_joint("spin", Vec3::UnitZ(), Vec3(0.2, 0, 0))));
  b.add_link(make_link("wheel2", "base", 0.5, Vec3::Zero(), Vec3(0.01, 0.01, 0.015).asDiagonal(),
                       revolute_joint("spin2", Vec3::UnitZ(), Vec3(-0.2, 0, 0))));
  b.add_link(make_link("carriage", "base", 1.5, Vec3::Zero(),
                       test::box_inertia(1.5, Vec3(0.1, 0.1, 0.1)),
                       prismatic_joint("slide", Vec3::UnitX(), Vec3(0, 0.3, 0))));
  return std::make_shared<const Model>(b.build());
}

struct FreeRun {
  double q = 0, qd = 0;          // largest differences relative to PhysX's scale
  double q_end = 0, px_end = 0;  // the wheel's final position, featherdrive and PhysX
};

// Runs sim free for `steps` steps beside PhysX; forces[k] are step k + 1's joint forces.
FreeRun free_run(const Simulation& initial, int steps,
                 const std::vector<ForcesByJoint>& forces = {}, const std::string& watch = "spin") {
  const JointTrajectory px = run_physx(PhysxInstall{FEATHERDRIVE_NODE, FEATHERDRIVE_PHYSX_DIR},
                                       initial, steps, {}, forces);
  const Model& model = initial.model();
  double scale_q = 0, scale_qd = 0;
  for (size_t k = 0; k < px.rows(); ++k)
    for (size_t j = 0; j < px.joints.size(); ++j) {
      scale_q = std::max(scale_q, std::abs(px.q[k][j]));
      scale_qd = std::max(scale_qd, std::abs(px.qd[k][j]));
    }
  Simulation sim = initial;
  FreeRun r;
  for (int k = 0; k < steps; ++k) {
    if (static_cast<size_t>(k) < forces.size()) {
      VecX tau = sim.applied_force();
      for (const auto& [joint, f] : forces[static_cast<size_t>(k)])
        tau[model.links[model.joint_link_index(joint)].v_index] = f;
      sim.set_applied_force(tau);
    }
    sim.step();
    for (size_t j = 0; j < px.joints.size(); ++j) {
      const Link& l = model.links[model.joint_link_index(px.joints[j])];
      r.q = std::max(r.q, std::abs(sim.q()[l.q_index] - px.q[k + 1][j]) / scale_q);
      r.qd = std::max(r.qd, std::abs(sim.qd()[l.v_index] - px.qd[k + 1][j]) / scale_qd);
      if (px.joints[j] == watch && k + 1 == steps) {
        r.q_end = sim.q()[l.q_index];
        r.px_end = px.q[k + 1][j];
      }
    }
  }
  return r;
}

SimulationOptions solver(SolverType type, int position_iterations) {
  SimulationOptions o;
  o.solver = type;
  o.position_iterations = position_iterations;
  return o;
}

// A wheel driven to 7 rad (TGS 4/1): unwrapped it settles at 7; wrapped (PhysX's eREVOLUTE) its
// position returns to -2 pi + (q - 2 pi) past 2 pi, the target is never reached and it spins up.
TEST(PhysxJoints, WheelDrivenTo7RadWrappedAndUnwrapped) {
  for (const RevoluteWrap wrap : {RevoluteWrap::unwrapped, RevoluteWrap::wrapped}) {
    Simulation sim(wheels_and_slider(), solver(SolverType::tgs, 4));
    sim.set_drive("spin", Drive{DriveType::force, 2.0, 0.3, test::kInf, 7.0, 0.0});
    sim.set_revolute_wrap("spin", wrap);
    const FreeRun r = free_run(sim, 240);
    std::printf("wheel to 7 rad, %s: q %.1e qd %.1e, q(240) %.6f (PhysX %.6f)\n", to_string(wrap),
                r.q, r.qd, r.q_end, r.px_end);
    EXPECT_LT(r.q, 1e-4);
    EXPECT_LT(r.qd, 1e-4);
    if (wrap == RevoluteWrap::unwrapped)
      EXPECT_NEAR(r.q_end, 7.0, 0.2);
    else
      EXPECT_LE(std::abs(r.q_end), 2.0 * std::numbers::pi);
  }
}

// A wheel velocity-driven at 4 rad/s past 2 pi (PGS 4/1), both joint types.
TEST(PhysxJoints, WheelVelocityDrivenPastTwoPiWrappedAndUnwrapped) {
  for (const RevoluteWrap wrap : {RevoluteWrap::unwrapped, RevoluteWrap::wrapped}) {
    Simulation sim(wheels_and_slider(), solver(SolverType::pgs, 4));
    sim.set_drive("spin", Drive{DriveType::force, 0.0, 2.0, test::kInf, 0.0, 4.0});
    sim.set_revolute_wrap("spin", wrap);
    const FreeRun r = free_run(sim, 240);  // 4 s: about 16 rad
    std::printf("wheel at 4 rad/s, %s: q %.1e qd %.1e, q(240) %.6f (PhysX %.6f)\n", to_string(wrap),
                r.q, r.qd, r.q_end, r.px_end);
    EXPECT_LT(r.q, 1e-4);
    EXPECT_LT(r.qd, 1e-4);
    if (wrap == RevoluteWrap::unwrapped)
      EXPECT_GT(r.q_end, 4.0 * std::numbers::pi);
    else
      EXPECT_LE(std::abs(r.q_end), 2.0 * std::numbers::pi);
  }
}

// Applied joint forces (PhysX's cache jointForce): a constant torque on a driven wheel, a sine
// torque on an undriven one and a constant force on the slider, under PGS and TGS.
TEST(PhysxJoints, AppliedForcesConstantAndSineOnDrivenAndUndrivenJoints) {
  for (const SolverType type : {SolverType::pgs, SolverType::tgs}) {
    Simulation sim(wheels_and_slider(), solver(type, 4));
    sim.set_drive("spin", Drive{DriveType::force, 5.0, 0.5, test::kInf, 0.5, 0.0});
    VecX tau = VecX::Zero(sim.model().nv);
    tau[sim.model().dof_index("spin")] = 0.4;
    tau[sim.model().dof_index("slide")] = 1.2;
    sim.set_applied_force(tau);
    const int steps = 240;
    const double dt = sim.options().dt;
    std::vector<ForcesByJoint> forces(steps);
    for (int k = 0; k < steps; ++k)
      forces[static_cast<size_t>(k)]["spin2"] = 0.05 * std::sin(3.0 * k * dt);
    const FreeRun r = free_run(sim, steps, forces, "spin2");
    std::printf("applied forces, %s: q %.1e qd %.1e\n", to_string(type), r.q, r.qd);
    EXPECT_LT(r.q, 1e-4);
    EXPECT_LT(r.qd, 1e-4);
  }
}

}  // namespace
}  // namespace featherdrive
