// Mimic rows in Batch's SIMD lanes against each environment stepped alone as a Simulation (the
// scalar path, another operation order): docs/simd_batch.md, docs/math/mimic_joints.md.
#include <gtest/gtest.h>

#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "featherdrive/sim/batch.hpp"
#include "support/compare.hpp"
#include "support/drives.hpp"
#include "support/lanes.hpp"
#include "support/models.hpp"
#include "support/scoped_env.hpp"

namespace featherdrive {
namespace {

using test::relative_difference;

// A random fixed-base tree of revolute and prismatic joints with drives on every dof, joint
// limits and friction on some, and three mimic rows: two rigid, one soft.
Simulation mimic_prototype(unsigned seed, SolverType solver) {
  auto model = test::make_random_tree(seed, 9, false, false, 0.01);
  Simulation sim(model, test::lane_test_options(solver));
  std::mt19937 rng(seed);
  test::drive_every_joint(sim, rng, 300.0, 20.0);
  const int nv = model->nv;
  for (int d = 0; d < nv; ++d) {
    if (d % 3 == 0) sim.set_joint_limits(d, -0.3, 0.4);
    // Viscous friction keeps the free tree from chaos, which would grow the two step orders'
    // last bits past 1e-12 in 1000 steps.
    sim.set_joint_friction(d, JointFriction{0.0, 0.0, 0.2});
  }
  test::set_three_mimic_rows(sim);
  sim.set_qd(test::random_vector(nv, rng, 0.5));
  return sim;
}

// Every environment's q, qd and output forces against its own Simulation stepped alone.
void expect_lanes_within_1e12(Batch& lanes, Batch& alone, int steps, const std::string& what) {
  ASSERT_NE(lanes.step_path().find("lanes"), std::string::npos) << lanes.step_path();
  alone.set_lanes(false);
  lanes.step(steps);
  alone.step(steps);
  double worst = 0.0;
  for (const auto& [a, b] : {std::pair{&lanes.q(), &alone.q()}, {&lanes.qd(), &alone.qd()},
                             {&lanes.drive_force(), &alone.drive_force()},
                             {&lanes.limit_force(), &alone.limit_force()},
                             {&lanes.friction_force(), &alone.friction_force()}})
    worst = std::max(worst, relative_difference(*a, *b));
  EXPECT_LE(worst, 1e-12) << what;
  std::printf("%s: largest relative difference %.1e (docs/simd_batch.md)\n", what.c_str(), worst);
}

TEST(LaneMimic, RandomTreeWithRigidAndSoftRowsAsSimulation) {
  for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    const Simulation proto = mimic_prototype(5, solver);
    Batch lanes(proto, 11), alone(proto, 11);
    // Each environment its own gear ratios and offsets; the rows' dofs are the same in all.
    for (int e = 0; e < 11; ++e) {
      std::vector<MimicJoint> rows = proto.mimic_joints();
      rows[0].gear_ratio *= 1.0 + 0.05 * e;
      rows[1].offset += 0.01 * e;
      rows[2].natural_frequency += e;
      lanes.sim(e).set_mimic_joints(rows);
      alone.sim(e).set_mimic_joints(rows);
    }
    expect_lanes_within_1e12(lanes, alone, 1000,
                             std::string("random tree, mimic rows, ") + to_string(solver));
    // The rows hold: a rigid row's error C = q_a + G q_b + o at rest is far below its start's.
    const MimicJoint& m = lanes.sim(3).mimic_joints()[1];
    const VecX q = lanes.q().row(3).transpose();
    const auto qi = [&](int dof) {
      return q[lanes.model().links[static_cast<size_t>(lanes.model().dof_link[dof])].q_index];
    };
    EXPECT_LT(std::abs(qi(m.dof_a) + m.gear_ratio * qi(m.dof_b) + m.offset), 1e-3);
  }
}

// One environment's bits do not depend on its lane or the batch size, mimic rows included.
TEST(LaneMimic, BitsIndependentOfLaneAndBatchSize) {
  const Simulation proto = mimic_prototype(5, SolverType::tgs);
  Batch one(proto, 1), many(proto, 13);
  one.step(200);
  many.step(200);
  for (int e = 0; e < many.size(); ++e)
    EXPECT_TRUE(test::same_bits(many.q().row(e), one.q().row(0))) << "environment " << e;
}

// Rows on other dofs in one environment: a plan of rows is a lane group's, so that environment
// steps in a group of its own (docs/simd_batch.md, "Lane groups"), as its Simulation.
TEST(LaneMimic, RowsOnOtherDofsStepInAGroupOfTheirOwn) {
  const test::AutomaticSimd automatic;  // the path checked is the automatic one
  const Simulation proto = mimic_prototype(5, SolverType::pgs);
  Batch batch(proto, 4);
  std::vector<MimicJoint> rows = proto.mimic_joints();
  rows.pop_back();
  batch.sim(2).set_mimic_joints(rows);
  EXPECT_NE(batch.step_path().find(" lanes: 2 groups (3, 1 environments; 1 at one lane)"),
            std::string::npos)
      << batch.step_path();
  EXPECT_NE(batch.env_path(2).find(" lanes, group 1 (one lane)"), std::string::npos)
      << batch.env_path(2);
  Simulation alone = batch.sim(2);
  batch.step(50);
  alone.step(50);
  EXPECT_LE(relative_difference(batch.q().row(2).transpose(), alone.q()), 1e-12);
  // Every environment's rows changed to match: one group again, with a new plan.
  for (int e : {0, 1, 3}) batch.sim(e).set_mimic_joints(rows);
  EXPECT_EQ(batch.step_path().find("lanes"), batch.step_path().size() - 5) << batch.step_path();
}

}  // namespace
}  // namespace featherdrive
