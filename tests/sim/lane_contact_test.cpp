// Ground contacts in Batch's SIMD lanes against each environment stepped alone as a Simulation
// (the scalar path, another operation order): q, qd, the output forces, the links' contact forces
// and every contact report. docs/simd_batch.md, "Contacts".
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "featherdrive/algorithm/kinematics.hpp"
#include "featherdrive/sim/batch.hpp"
#include "support/compare.hpp"
#include "support/contact_models.hpp"
#include "support/drives.hpp"
#include "support/lane_contact_models.hpp"
#include "support/lanes.hpp"
#include "support/models.hpp"

namespace featherdrive {
namespace {

// Each environment's bits are the same at any lane, in a batch of any size, at every width and
// on any number of threads.
TEST(LaneContact, SameBitsForAnyLaneWidthAndThreads) {
  const Simulation proto = test::grounded_tree(8, SolverType::tgs, false);
  // Environment k at lane (k + shift) % size, dropped from a height of its own.
  auto run = [&](int size, SimdIsa isa, int threads, int shift) {
    Batch b(proto, size);
    b.set_isa(isa);
    b.set_num_threads(threads);
    for (int k = 0; k < size; ++k) {
      VecX q = proto.q();
      q[2] = 0.3 + 0.1 * (k % 5);
      b.sim((k + shift) % size).set_q(q);
    }
    b.step(150);
    RowMatrix out(size, proto.model().nq + 3 * proto.model().num_links());
    for (int k = 0; k < size; ++k)
      out.row(k) << b.q().row((k + shift) % size), b.link_contact_force().row((k + shift) % size);
    return out;
  };
  const RowMatrix reference = run(5, SimdIsa::sse2, 1, 0);
  for (SimdIsa isa : available_simd_isas())
    for (int threads : {1, 2})
      for (int shift : {0, 7}) {
        const RowMatrix x = run(13, isa, threads, shift);
        EXPECT_TRUE(test::same_bits(RowMatrix(x.topRows(5)), reference))
            << to_string(isa) << " threads " << threads << " shift " << shift;
      }
}

// The ground switched on between calls (the plan takes the contact rows then), and off again in
// one environment: a lane without a ground beside grounded ones, as its Simulation.
TEST(LaneContact, GroundSwitchedBetweenCallsAsSimulation) {
  for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    const Simulation proto = test::grounded_tree(6, solver, false);
    Simulation airy = proto;
    Ground off = proto.ground();
    off.enabled = false;
    airy.set_ground(off);
    Batch lanes(airy, 5);
    for (int e = 0; e < lanes.size(); ++e) {
      VecX q = proto.q();
      q[2] = 0.3 + 0.05 * e;
      lanes.sim(e).set_q(q);
    }
    lanes.step(3);
    for (int e = 0; e < lanes.size(); ++e) lanes.sim(e).set_ground(e == 2 ? off : proto.ground());
    const std::string what = std::string("ground switched on, one lane without, ") +
                             to_string(solver);
    const test::LaneFigures f = test::batch_against_alone(lanes, 300, 3, what);
    EXPECT_LE(f.ratio, test::kSensitivityFactor) << what;
    EXPECT_TRUE(lanes.contacts(2).empty()) << what;
    for (int e = 0; e < lanes.size(); ++e)  // held by the ground, or through where it is
      if (e == 2) EXPECT_LT(lanes.q()(e, 2), -1.0) << what;
      else EXPECT_GT(lanes.q()(e, 2), -0.5) << what;
  }
}

// A contact force that overflows where the state stays finite (dt 1e-200: the push-out impulse
// over dt) stops the lane with its state and reports as Simulation's check words it, the other
// environments (airborne) going on; the stopped one reports no contacts.
TEST(LaneContact, ContactForceOverflowStopsTheLaneAsSimulation) {
  // Guarded too: the lane is stepped again by its Simulation's guarded advance, which decides.
  for (const bool guard : {false, true}) {
  SimulationOptions o = test::lane_test_options(SolverType::pgs);
  o.dt = 1e-200;
  o.guard.enabled = guard;
  Simulation box(test::make_ground_box(0.5), o);
  Ground ground;
  ground.enabled = true;
  box.set_ground(ground);
  std::string messages[2];
  long triggers[2] = {0, 0};
  for (const bool lanes_on : {true, false}) {
    Batch b(box, 3);
    b.set_lanes(lanes_on);
    for (int e = 0; e < 3; ++e) {
      VecX q = box.q();
      q[2] = e == 1 ? 0.09 : 5.0;  // environment 1 a centimetre into the ground
      b.sim(e).set_q(q);
    }
    const VecX q1 = b.sim(1).q();
    try {
      b.step(2);
      ADD_FAILURE() << "no DivergenceError";
    } catch (const DivergenceError& e) {
      messages[lanes_on ? 0 : 1] = e.what();
    }
    triggers[lanes_on ? 0 : 1] = b.sim(1).guard_triggers();
    EXPECT_EQ(b.step_path().find("scalar") == std::string::npos, lanes_on) << b.step_path();
    ASSERT_TRUE(b.divergences()[1].has_value());
    EXPECT_TRUE(test::same_bits(VecX(b.sim(1).q()), q1));
    EXPECT_TRUE(b.contacts(1).empty());
    EXPECT_EQ(b.sim(0).step_count(), 2);
  }
  EXPECT_NE(messages[0].find("link 'box' contact force f"), std::string::npos) << messages[0];
  EXPECT_EQ(messages[0], messages[1]);
  EXPECT_EQ(triggers[0], triggers[1]) << guard;
  }
}

// The step guard on the ground (docs/simd_batch.md, "The step guard"): guarded trees dropped
// from their own heights, whose landings the guard redoes, the reports and anchors of a redone
// step then their Simulation's (none reported or kept); within kSensitivityFactor of each
// environment's own sensitivity, the same steps redone.
TEST(LaneContact, GuardedOnTheGroundAsSimulation) {
  for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    Simulation proto = test::grounded_tree(4, solver, false);
    SimulationOptions o = proto.options();
    o.guard.enabled = true;
    o.guard.max_joint_step = 0.05;
    // At most 2 sub-steps: with 4 or more PGS's redone landings reach NaN in the scalar step
    // too (the contacts' work is not in the guard's, eq. G-3, so landings fail test (ii)).
    o.guard.max_substeps = 2;
    proto.set_options(o);
    Batch lanes(proto, 7);
    std::mt19937 rng(4);
    test::drop_from_own_heights(lanes, rng);
    std::vector<Simulation> alone;
    for (int e = 0; e < lanes.size(); ++e) alone.push_back(lanes.simulation(e));
    const std::string what = std::string("guarded on the ground, ") + to_string(solver);
    const test::LaneFigures f = test::batch_against_alone(lanes, 300, 3, what);
    EXPECT_LE(f.ratio, test::kSensitivityFactor) << what;
    long triggers = 0;
    for (int e = 0; e < lanes.size(); ++e) {
      Simulation& a = alone[static_cast<size_t>(e)];
      for (int c = 0; c < 3; ++c) a.step(100);
      EXPECT_EQ(lanes.sim(e).guard_triggers(), a.guard_triggers()) << what << " env " << e;
      EXPECT_EQ(lanes.sim(e).contacts().size(), a.contacts().size()) << what << " env " << e;
      triggers += a.guard_triggers();
    }
    std::printf("%s: %ld steps redone\n", what.c_str(), triggers);
    EXPECT_GT(triggers, 0) << what;
  }
}

// The path: a grounded robot runs in the lanes, under compat none and physx; shapes on other
// links than environment 0's make a lane group of their own; self-collision stays refused.
TEST(LaneContact, StepPath) {
  Simulation s = test::grounded_tree(5, SolverType::pgs, false);
  Batch grounded(s, 3);
  EXPECT_EQ(grounded.step_path().find("scalar"), std::string::npos) << grounded.step_path();
  // An environment whose shapes sit on other links than environment 0's (the plan's).
  Model moved = s.model();
  moved.shapes.erase(moved.shapes.begin() + 1);
  grounded.sim(2).set_model(std::make_shared<const Model>(moved));
  EXPECT_NE(grounded.step_path().find(" lanes: 2 groups (2, 1 environments)"), std::string::npos)
      << grounded.step_path();
  Simulation self = s;
  ContactOptions contact;
  contact.self_collision = true;
  self.set_contact_options(contact);
  Batch selfish(self, 2);
  EXPECT_NE(selfish.step_path().find("self-collision between the model's shapes"),
            std::string::npos)
      << selfish.step_path();
  SimulationOptions o = s.options();
  o.compat = Compat::physx;
  Simulation physx(s.model_ptr(), o);
  physx.set_ground(s.ground());
  Batch px(physx, 2);
  EXPECT_EQ(px.step_path().find("scalar"), std::string::npos) << px.step_path();
}

}  // namespace
}  // namespace featherdrive
