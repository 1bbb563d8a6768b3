// Spherical joints in Batch's SIMD lanes against each environment stepped alone as a Simulation
// (the scalar path, another operation order): docs/simd_batch.md, "Spherical joints".
#include <gtest/gtest.h>

#include <random>
#include <string>
#include <vector>

#include "featherdrive/sim/batch.hpp"
#include "support/compare.hpp"
#include "support/drives.hpp"
#include "support/lanes.hpp"
#include "support/models.hpp"

namespace featherdrive {
namespace {

using test::expect_lanes_as_alone;

// The first random tree of `n` links (revolute, prismatic, spherical, fixed joints) with at least
// two spherical joints, on a fixed or floating root.
std::shared_ptr<const Model> tree_with_balls(int n, bool floating) {
  for (unsigned seed = 1;; ++seed) {
    auto model = test::make_random_tree(seed, n, floating, true, 0.01);
    int balls = 0;
    for (const Link& l : model->links) balls += l.joint_type == JointType::spherical;
    if (balls >= 2) return model;
  }
}

// Drives on every axis (force and acceleration), limits on some axes within (-pi, pi), viscous
// friction on every dof that takes rows, two mimic rows; the start velocity random.
Simulation ball_prototype(bool floating, SolverType solver) {
  auto model = tree_with_balls(9, floating);
  Simulation sim(model, test::lane_test_options(solver));
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (const Link& l : model->links) {
    const int axes = l.joint_type == JointType::spherical ? 3
                     : l.joint_type == JointType::revolute || l.joint_type == JointType::prismatic
                         ? 1
                         : 0;
    for (int a = 0; a < axes; ++a) {
      const int d = l.v_index + a;
      sim.set_drive(d, Drive{a == 1 ? DriveType::acceleration : DriveType::force, 200.0, 15.0,
                             test::kInf, 0.5 * u(rng), 0.2 * u(rng)});
      // Limits the targets stay clear of (a joint resting on its limit is a knife edge:
      // docs/simd_batch.md, "Against the scalar Simulation").
      if (d % 3 == 0) sim.set_joint_limits(d, -1.2, 1.3);
      sim.set_joint_friction(d, JointFriction{0.0, 0.0, 0.2});
    }
  }
  // Two mimic rows between 1-dof joints: their sweeps of given impulses pass the spherical joints.
  std::vector<MimicJoint> rows;
  int previous = -1;
  for (const Link& l : model->links) {
    if (l.nv != 1) continue;
    if (previous >= 0 && rows.size() < 2) rows.push_back({l.v_index, previous, -0.5, 0.01});
    previous = l.v_index;
  }
  EXPECT_EQ(rows.size(), 2u);
  sim.set_mimic_joints(rows);
  sim.set_qd(test::random_vector(model->nv, rng, 0.5));
  return sim;
}

TEST(LaneSpherical, RandomTreesAsSimulation) {
  for (const bool floating : {false, true})
    for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
      const Simulation proto = ball_prototype(floating, solver);
      expect_lanes_as_alone(proto, 1000,
                            std::string("random tree with spherical joints, ") +
                                (floating ? "floating, " : "fixed, ") + to_string(solver));
    }
}

// The lanes take each axis's position and drive error from the quaternion, as PhysX has them:
// per environment targets far from the start (so the errors' geometry acts) and bits that do not
// depend on the batch's size.
TEST(LaneSpherical, PerEnvironmentTargetsAndBitsOfAnyBatchSize) {
  const Simulation proto = ball_prototype(false, SolverType::tgs);
  Batch small(proto, 3), large(proto, 11), alone(proto, 3);
  alone.set_lanes(false);
  for (Batch* b : {&small, &large, &alone})
    for (int e = 0; e < 3; ++e)
      for (const Link& l : proto.model().links)
        if (l.joint_type == JointType::spherical)
          b->sim(e).set_drive_target(l.v_index + 2, 0.4 + 0.3 * e, 0.0);
  ASSERT_NE(small.step_path().find("lanes"), std::string::npos) << small.step_path();
  small.step(500);
  large.step(500);
  alone.step(500);
  for (int e = 0; e < 3; ++e)
    EXPECT_TRUE(test::same_bits(small.q().row(e), large.q().row(e))) << e;
  const double worst = std::max(test::relative_difference(small.q(), alone.q()),
                                test::relative_difference(small.qd(), alone.qd()));
  EXPECT_LE(worst, 1e-12);
}

// compat physx: PhysX's defaults (friction coefficients on every axis: transmitted-force friction),
// each axis's row seeing its link bias (S-8), the link turned in the world with it
// (docs/math/spherical_joints.md), fixed and floating.
TEST(LaneSpherical, RandomTreesCompatPhysxAsSimulation) {
  for (const bool floating : {false, true})
    for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
      const Simulation none = ball_prototype(floating, solver);
      SimulationOptions o = none.options();
      o.compat = Compat::physx;
      auto model = std::make_shared<Model>(none.model());
      model->gravity.setZero();  // a free fall is ill-conditioned under compat physx (lane_floating_test.cpp)
      Simulation proto(model, o);
      for (int d = 0; d < model->nv; ++d) {
        if (none.drive(d).type == DriveType::none) continue;
        proto.set_drive(d, none.drive(d));
        proto.set_joint_limits(d, none.lower_limit(d), none.upper_limit(d));
        proto.set_joint_friction(d, none.joint_friction(d));
      }
      proto.set_mimic_joints(none.mimic_joints());
      proto.set_qd(none.qd());
      expect_lanes_as_alone(proto, 1000,
                            std::string("random tree with spherical joints, compat physx, ") +
                                (floating ? "floating, " : "fixed, ") + to_string(solver));
    }
}

}  // namespace
}  // namespace featherdrive
