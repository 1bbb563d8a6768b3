// Batch's lane groups (docs/simd_batch.md, "Lane groups"): environments that differ in what a
// lane plan fixes (dt, solver, iteration counts, mimic dofs, the links with shapes) step in
// groups of their own, gravity per lane, and one the lanes refuse steps as its Simulation, while
// the rest stay in lanes; each against itself stepped alone, and its bits against themselves in
// groups of other compositions.
#include <gtest/gtest.h>

#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "featherdrive/sim/batch.hpp"
#include "support/compare.hpp"
#include "support/drives.hpp"
#include "support/lane_contact_models.hpp"
#include "support/lanes.hpp"
#include "support/scoped_env.hpp"
#include "support/models.hpp"

namespace featherdrive {
namespace {

// A random fixed-base tree with drives on every dof, limits on some, viscous friction on all
// (it keeps the tree from chaos, which would grow the two step orders' last bits past 1e-12)
// and three mimic rows.
Simulation group_prototype(unsigned seed, SolverType solver, Compat compat = Compat::none) {
  auto model = test::make_random_tree(seed, 9, false, false, 0.01);
  SimulationOptions o = test::lane_test_options(solver);
  o.compat = compat;
  Simulation sim(model, o);
  std::mt19937 rng(seed);
  test::drive_every_joint(sim, rng, 300.0, 20.0);
  for (int d = 0; d < model->nv; ++d) {
    if (d % 3 == 0) sim.set_joint_limits(d, -0.3, 0.4);
    sim.set_joint_friction(d, JointFriction{0.0, 0.0, 0.2});
  }
  test::set_three_mimic_rows(sim);
  sim.set_qd(test::random_vector(model->nv, rng, 0.5));
  return sim;
}

SimulationOptions with(SimulationOptions o, double dt, SolverType solver, int position,
                       int velocity) {
  o.dt = dt, o.solver = solver, o.position_iterations = position, o.velocity_iterations = velocity;
  return o;
}

// Ten environments: 0, 1, 2 and 9 the prototype's plan (1 and 9 with gravity of their own),
// 3 and 4 another dt, 5 the other solver, 6 other iteration counts, 7 mimic rows on fewer dofs,
// 8 the step guard.
Batch mixed_batch(const Simulation& proto) {
  Batch batch(proto, 10);
  const SimulationOptions o = proto.options();
  const SolverType other = o.solver == SolverType::pgs ? SolverType::tgs : SolverType::pgs;
  RowMatrix g(2, 3);
  g << 0.0, 0.0, -3.0, 0.5, 0.0, -12.0;
  const int heavy[] = {1, 9};
  batch.set_gravity(heavy, g);
  for (int e : {3, 4}) batch.sim(e).set_options(with(o, 0.004, o.solver, 4, 1));
  batch.sim(5).set_options(with(o, o.dt, other, 4, 1));
  batch.sim(6).set_options(with(o, o.dt, o.solver, 6, 2));
  std::vector<MimicJoint> rows = proto.mimic_joints();
  rows.erase(rows.begin() + 1);
  batch.sim(7).set_mimic_joints(rows);
  SimulationOptions guarded = o;
  guarded.guard.enabled = true;
  batch.sim(8).set_options(guarded);
  return batch;
}

// Every environment of the mixed batch within 1e-12 of itself stepped alone over 1000 steps,
// PGS and TGS, the guarded one (its guard tests the lanes' steps) included.
TEST(LaneGroups, MixedPlansEachAsItsSimulation) {
  for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    const Simulation proto = group_prototype(5, solver);
    Batch batch = mixed_batch(proto);
    batch.set_isa(SimdIsa::sse2);
    EXPECT_EQ(batch.step_path(), "sse2 lanes: 6 groups (4, 2, 1, 1, 1, 1 environments)");
    EXPECT_EQ(batch.env_path(9), "sse2 lanes, group 0");
    EXPECT_EQ(batch.env_path(4), "sse2 lanes, group 1");
    EXPECT_EQ(batch.env_path(8), "sse2 lanes, group 5");  // guarded: one step a run
    EXPECT_THROW(batch.env_path(10), std::invalid_argument);
    batch.set_isa(std::nullopt);
    std::vector<Simulation> alone;
    for (int e = 0; e < batch.size(); ++e) alone.push_back(batch.simulation(e));
    double worst = 0.0;
    for (int call = 0; call < 10; ++call) {
      batch.step(100);
      for (Simulation& s : alone) s.step(100);
    }
    for (int e = 0; e < batch.size(); ++e) {
      const double d = test::lane_difference(batch, e, alone[static_cast<size_t>(e)]);
      EXPECT_LE(d, 1e-12) << to_string(solver) << ", environment " << e;
      EXPECT_EQ(batch.sim(e).step_count(), 1000);
      EXPECT_EQ(batch.sim(e).time(), alone[static_cast<size_t>(e)].time());
      worst = std::max(worst, d);
    }
    // Gravity is each lane's: the environments under other gravity went elsewhere.
    EXPECT_GT((batch.sim(1).q() - batch.sim(0).q()).cwiseAbs().maxCoeff(), 1e-3);
    std::printf("lane groups, %s: largest relative difference %.1e (docs/simd_batch.md)\n",
                to_string(solver), worst);
  }
}

// An environment's bits are the same in any group: alone in a batch, among others of its plan,
// at another position of another group in a mixed batch (other groups and a guarded
// environment beside it), at every width and on one or two threads.
TEST(LaneGroups, BitsIndependentOfTheGroupsComposition) {
  const Simulation proto = group_prototype(7, SolverType::tgs);
  Simulation x = proto;
  x.set_options(with(proto.options(), 0.004, SolverType::tgs, 4, 1));
  Drive stiff = x.drive(2);
  stiff.stiffness = 700.0;
  x.set_drive(2, stiff);
  auto bits = [&](Batch& b, int e) {
    b.step(30);
    for (int k = 0; k < 10; ++k) b.step(1);
    VecX out(x.model().nq + x.model().nv);
    out << b.sim(e).q(), b.sim(e).qd();
    return out;
  };
  Batch one(x, 1);
  const VecX reference = bits(one, 0);
  for (SimdIsa isa : available_simd_isas())
    for (int threads : {1, 2}) {
      Batch same(x, 11);  // among copies of its plan
      same.set_isa(isa);
      same.set_num_threads(threads);
      EXPECT_TRUE(test::same_bits(bits(same, 6), reference)) << to_string(isa) << " " << threads;
      Batch mixed = mixed_batch(proto);  // x at environment 2, in the group of 3 and 4
      mixed.sim(2) = x;
      mixed.set_isa(isa);
      mixed.set_num_threads(threads);
      EXPECT_NE(mixed.env_path(2).find("group 1"), std::string::npos) << mixed.env_path(2);
      EXPECT_TRUE(test::same_bits(bits(mixed, 2), reference)) << to_string(isa) << " " << threads;
    }
}

// Every row kind the lanes have on one floating tree over the ground: a spherical joint, drives,
// limits, static and viscous friction and velocity limits on some 1-dof joints, two mimic rows
// between others, ground contacts; compat and the step guard as given.
Simulation every_row_kind(unsigned seed, SolverType solver, Compat compat, bool guarded) {
  Simulation sim = test::grounded_tree(seed, solver, /*spherical=*/true, compat);
  const Model& m = sim.model();
  std::vector<int> single;  // the dofs of 1-dof joints
  for (const Link& link : m.links)
    if (link.joint_type == JointType::revolute || link.joint_type == JointType::prismatic)
      single.push_back(link.v_index);
  EXPECT_GE(single.size(), 6u);
  for (size_t k = 0; k < single.size(); ++k) {
    const int d = single[k];
    if (k % 3 == 0) sim.set_joint_limits(d, -0.3, 0.4);
    if (k % 3 == 1) sim.set_joint_friction(d, JointFriction{0.3, 0.2, 0.1});
    if (k % 4 == 2) sim.set_max_joint_velocity(d, 0.3);
  }
  sim.set_mimic_joints({{single[1], single[0], -1.5, 0.05},
                        {single.back(), single[2], -1.0, 0.0, 30.0, 0.7}});
  SimulationOptions o = sim.options();
  o.guard.enabled = guarded;
  sim.set_options(o);
  return sim;
}

// One-lane blocks (docs/simd_batch.md, "One-lane blocks"): an environment alone in its group,
// a plain double a lane, gives the bits it gives among copies of its plan in vector lanes at
// every width, with every row kind, under compat none and physx, with and without the guard.
TEST(LaneGroups, OneLaneSameBitsAsVectorLanes) {
  const test::AutomaticSimd automatic;  // the path checked is the automatic one
  for (const bool guarded : {false, true})
    for (const auto& [solver, compat] : {std::pair{SolverType::pgs, Compat::none},
                                         std::pair{SolverType::tgs, Compat::physx}}) {
      const std::string what = std::string(to_string(solver)) +
                               (compat == Compat::physx ? ", physx" : ", none") +
                               (guarded ? ", guarded" : "");
      const Simulation proto = every_row_kind(11, solver, compat, guarded);
      auto dropped = [&](int size) {  // each environment from a height of its own
        Batch b(proto, size);
        std::mt19937 rng(11);
        test::drop_from_own_heights(b, rng);
        return b;
      };
      size_t touched = 0;  // contacts reported after the calls
      auto bits = [&](Batch& b, int e) {
        const Simulation& s = static_cast<const Batch&>(b).sim(e);
        touched = 0;
        for (int k = 0; k < 19; ++k) {
          b.step(k < 9 ? 10 : 1);
          touched += s.contacts().size();
        }
        VecX out(s.model().nq + 5 * s.model().nv + 3 * s.model().num_links());
        out << s.q(), s.qd(), s.drive_force(), s.limit_force(), s.friction_force(),
            s.velocity_limit_force(), Eigen::Map<const VecX>(s.link_contact_force()[0].data(),
                                                              3 * s.model().num_links());
        return out;
      };
      const Simulation x = dropped(7).simulation(0);  // environment 0 of seven, the lowest
      Batch one(x, 1);
      ASSERT_EQ(one.step_path(), "sse2 lanes (1 at one lane)") << what;
      ASSERT_EQ(one.env_path(0), "sse2 lanes, group 0 (one lane)") << what;
      const VecX reference = bits(one, 0);
      EXPECT_GT(touched, 0u) << what;
      for (SimdIsa isa : available_simd_isas()) {
        Batch among = dropped(7);
        among.set_isa(isa);
        ASSERT_EQ(among.step_path(), std::string(to_string(isa)) + " lanes") << what;
        EXPECT_TRUE(test::same_bits(bits(among, 0), reference)) << what << ", " << to_string(isa);
      }
    }
}

// Environments that diverge in two groups stop with their state from before that step and the
// scalar step's message, the lowest one named; the others make all their steps; a partial reset starts them again.
TEST(LaneGroups, DivergenceInTwoGroups) {
  Simulation proto = group_prototype(5, SolverType::pgs);
  Batch batch = mixed_batch(proto);
  batch.step(3);
  const int bad[] = {4, 6};
  const VecX q4 = batch.sim(4).q(), q6 = batch.sim(6).q();
  batch.set_qd(bad, RowMatrix::Constant(1, proto.model().nv, 1e200));
  Simulation alone = batch.simulation(4);
  const std::string scalar_message = test::divergence_of(alone);
  ASSERT_FALSE(scalar_message.empty());
  const std::string batch_message = test::divergence_of(batch, 5);
  EXPECT_NE(batch_message.find("batch copy 4 (2 of 10"), std::string::npos) << batch_message;
  ASSERT_TRUE(batch.divergences()[4].has_value() && batch.divergences()[6].has_value());
  EXPECT_EQ(batch.divergences()[4]->message, scalar_message);
  EXPECT_EQ(batch.divergences()[6]->step, 4);
  EXPECT_TRUE(test::same_bits(batch.sim(4).q(), q4));
  EXPECT_TRUE(test::same_bits(batch.sim(6).q(), q6));
  for (int e = 0; e < batch.size(); ++e)
    if (e != 4 && e != 6) {
      EXPECT_FALSE(batch.divergences()[static_cast<size_t>(e)].has_value()) << e;
      EXPECT_EQ(batch.step_count()[static_cast<size_t>(e)], 8) << e;
    }
  batch.reset(bad);
  batch.step(2);
  EXPECT_EQ(batch.step_count()[4], 2);
  EXPECT_EQ(batch.step_count()[6], 2);
  EXPECT_FALSE(batch.divergences()[6].has_value());
}

// A settings change moves an environment from group to group (the guard too):
// the lanes regroup before the next step and it goes on as its Simulation.
TEST(LaneGroups, RegroupedWhenAPlanChanges) {
  const test::AutomaticSimd automatic;  // the path checked is the automatic one
  const Simulation proto = group_prototype(9, SolverType::pgs);
  Batch batch(proto, 5);
  std::vector<Simulation> alone(5, proto);
  auto step_all = [&](int steps) {
    batch.step(steps);
    for (Simulation& s : alone) s.step(steps);
  };
  auto change = [&](int e, const SimulationOptions& o) {
    batch.sim(e).set_options(o);
    alone[static_cast<size_t>(e)].set_options(o);
  };
  step_all(20);
  EXPECT_EQ(batch.step_path().find("lanes"), batch.step_path().size() - 5) << batch.step_path();
  const SimulationOptions o = proto.options();
  change(3, with(o, 0.004, SolverType::pgs, 4, 1));
  EXPECT_NE(batch.step_path().find("2 groups (4, 1 environments; 1 at one lane)"),
            std::string::npos)
      << batch.step_path();
  step_all(20);
  SimulationOptions guarded = o;
  guarded.guard.enabled = true;
  change(1, guarded);
  EXPECT_NE(batch.step_path().find("3 groups (3, 1, 1 environments; 2 at one lane)"),
            std::string::npos)
      << batch.step_path();
  step_all(20);
  change(1, o);
  change(3, o);
  batch.set_options(o);  // every environment the prototype's options again: one group
  for (Simulation& s : alone) s.set_options(o);
  EXPECT_EQ(batch.step_path().find("lanes"), batch.step_path().size() - 5) << batch.step_path();
  step_all(20);
  for (int e = 0; e < 5; ++e)
    EXPECT_LE(test::lane_difference(batch, e, alone[static_cast<size_t>(e)]), 1e-12) << e;
  batch.set_lanes(false);
  EXPECT_EQ(batch.step_path(), "scalar: lanes off (set_lanes)");
  EXPECT_EQ(batch.env_path(0), "scalar: lanes off (set_lanes)");
}

// compat is a plan's setting (its departures are stages of their own): an environment under
// compat physx (chosen at construction: a Simulation assigned to it) in a batch under none steps
// in a group of its own, as its Simulation.
TEST(LaneGroups, CompatSplitsTheGroups) {
  const test::AutomaticSimd automatic;  // the path checked is the automatic one
  for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    const Simulation proto = group_prototype(5, solver);
    Batch batch(proto, 4);
    batch.sim(1) = group_prototype(5, solver, Compat::physx);
    EXPECT_NE(batch.step_path().find("2 groups (3, 1 environments; 1 at one lane)"),
              std::string::npos)
        << batch.step_path();
    std::vector<Simulation> alone;
    for (int e = 0; e < batch.size(); ++e) alone.push_back(batch.simulation(e));
    for (int call = 0; call < 3; ++call) {
      batch.step(100);
      for (Simulation& s : alone) s.step(100);
    }
    for (int e = 0; e < batch.size(); ++e)
      EXPECT_LE(test::lane_difference(batch, e, alone[static_cast<size_t>(e)]), 1e-12)
          << to_string(solver) << ", environment " << e;
    EXPECT_GT((batch.sim(1).q() - batch.sim(0).q()).cwiseAbs().maxCoeff(), 1e-6);
  }
}

// A grounded batch whose environments carry shapes on different links: a group per set of
// shape links, each environment's contacts as its Simulation's, within the sampled sensitivity
// of the contact cases (tests/support/lanes.hpp); 300 steps here, 1000 in
// tests/peers/lane_contact_long_test.cpp.
TEST(LaneGroups, ShapesOnOtherLinksInGroupsOfTheirOwn) {
  const test::AutomaticSimd automatic;  // the path checked is the automatic one
  for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    Batch batch = test::shapes_on_three_link_sets(solver);
    EXPECT_NE(batch.step_path().find("3 groups (3, 2, 1 environments; 1 at one lane)"),
              std::string::npos)
        << batch.step_path();
    const std::string what = std::string("shapes on other links, ") + to_string(solver);
    const test::LaneFigures f = test::batch_against_alone(batch, 300, 3, what);
    EXPECT_LE(f.ratio, test::kSensitivityFactor) << what;
    EXPECT_GT(batch.link_contact_force().cwiseAbs().maxCoeff(), 0.0);
  }
}

}  // namespace
}  // namespace featherdrive
