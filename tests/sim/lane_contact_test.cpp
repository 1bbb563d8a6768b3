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
#include "support/scoped_env.hpp"

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

// The number of environment e's contacts between its own links.
int self_contacts(const Batch& b, int e) {
  const auto c = b.contacts(e);
  return static_cast<int>(
      std::count_if(c.begin(), c.end(), [](const ContactReport& r) { return r.other_link >= 0; }));
}

// Self-collision in the lanes (the self rows before each sweep, the scalar step's own, lane by
// lane): the same bits at any lane, width, batch size and number of threads, with the ground and
// without it.
TEST(LaneContact, SelfCollisionSameBitsForAnyLaneWidthAndThreads) {
  for (const bool grounded : {true, false}) {
    const Simulation proto = test::self_colliding_tree(8, SolverType::tgs, Compat::none, grounded);
    int touching = 0;
    auto run = [&](int size, SimdIsa isa, int threads, int shift) {
      Batch b(proto, size);
      b.set_isa(isa);
      b.set_num_threads(threads);
      std::mt19937 rng(3);
      for (int k = 0; k < size; ++k) {
        VecX q = proto.q();
        q[2] = 0.3 + 0.1 * (k % 5);
        b.sim((k + shift) % size).set_q(q);
        b.sim((k + shift) % size).set_qd(test::random_vector(proto.model().nv, rng, 1.0));
      }
      RowMatrix out(size, proto.model().nq + 3 * proto.model().num_links());
      for (int c = 0; c < 10; ++c) {
        b.step(15);
        for (int k = 0; k < 5; ++k) touching += self_contacts(b, (k + shift) % size);
      }
      EXPECT_EQ(b.step_path().find("scalar"), std::string::npos) << b.step_path();
      for (int k = 0; k < size; ++k)
        out.row(k) << b.q().row((k + shift) % size), b.link_contact_force().row((k + shift) % size);
      return out;
    };
    const RowMatrix reference = run(5, SimdIsa::sse2, 1, 0);
    EXPECT_GT(touching, 0) << grounded;
    for (SimdIsa isa : available_simd_isas())
      for (int threads : {1, 2})
        for (int shift : {0, 7}) {
          const RowMatrix x = run(13, isa, threads, shift);
          EXPECT_TRUE(test::same_bits(RowMatrix(x.topRows(5)), reference))
              << to_string(isa) << " threads " << threads << " shift " << shift << " ground "
              << grounded;
        }
  }
}

// Self-collision in the lanes against each environment alone, short (the 1000-step cases are in
// tests/peers/lane_contact_long_test.cpp): the random trees of the case above, PGS and TGS,
// compat none and physx, with and without the ground, one environment without self-collision.
TEST(LaneContact, SelfCollisionAsSimulation) {
  for (const Compat compat : {Compat::none, Compat::physx})
    for (const bool grounded : {true, false})
      for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
        const Simulation proto = test::self_colliding_tree(8, solver, compat, grounded);
        Batch lanes(proto, 5);
        std::mt19937 rng(3);
        for (int e = 0; e < lanes.size(); ++e) {
          VecX q = proto.q();
          q[2] = 0.3 + 0.1 * e;
          lanes.sim(e).set_q(q);
          lanes.sim(e).set_qd(test::random_vector(proto.model().nv, rng, 1.0));
        }
        lanes.sim(3).set_contact_options(ContactOptions{});
        const std::string what = std::string("self-collision, ") +
                                 (grounded ? "on the ground, " : "no ground, ") +
                                 to_string(solver) +
                                 (compat == Compat::physx ? ", compat physx" : "");
        int touching = 0;  // steps with self contacts, of the environments alone
        for (int e = 0; e < lanes.size(); ++e) {
          Simulation alone = lanes.sim(e);
          for (int k = 0; k < 150; ++k) {
            alone.step();
            for (const ContactReport& r : alone.contacts()) touching += r.other_link >= 0;
          }
        }
        EXPECT_GT(touching, 100) << what;
        const test::LaneFigures f = test::batch_against_alone(lanes, 150, 15, what);
        EXPECT_LE(f.ratio, test::kSensitivityFactor) << what;
        EXPECT_EQ(self_contacts(lanes, 3), 0) << what;
      }
}

// A robot whose box rests on its own plate, on the ground (lane_contact_models.hpp's starts),
// against each environment alone over 150 steps (1000 in lane_contact_long_test.cpp).
TEST(LaneContact, ARobotWhoseLinksRestOnEachOtherAsSimulation) {
  for (const Compat compat : {Compat::none, Compat::physx})
    for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
      Batch lanes(test::self_touching_robot(solver, compat), 6);
      test::self_touching_starts(lanes);
      const std::string what = std::string("a robot resting on itself, on the ground, ") +
                               to_string(solver) +
                               (compat == Compat::physx ? ", compat physx" : "");
      const test::LaneFigures f = test::batch_against_alone(lanes, 150, 3, what);
      EXPECT_LE(f.ratio, test::kSensitivityFactor) << what;
      for (int e = 0; e < lanes.size(); ++e)
        EXPECT_EQ(self_contacts(lanes, e), 4) << what << " environment " << e;
      EXPECT_EQ(lanes.contacts(0).size(), 8u) << what;
      EXPECT_EQ(lanes.contacts(4).size(), 4u) << what;  // falling: the box on the plate alone
    }
}

// A box whose floating root's joint frame is turned and moved, dropped and slid on the ground:
// frame 0's origin is the root's world position r_T + E_T^T q (contact_poses), compat physx's
// root turns in the world and its contacts track the root's move in the world (C25a).
TEST(LaneContact, BoxOnATurnedRootFrameAsSimulation) {
  for (const Compat compat : {Compat::none, Compat::physx})
    for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
      Model m = *test::make_ground_box(0.5);
      Transform& frame = m.links[0].tree_transform;
      frame.E = rotation_about(Vec3(0.3, -0.5, 0.8).normalized(), 0.6);
      frame.r = Vec3(0.1, -0.2, 0.05);
      const Simulation box = test::on_ground(std::make_shared<const Model>(m), solver, compat,
                                             Material{0.5, 0.5, 0.0});
      Batch lanes(box, 5);
      for (int e = 0; e < lanes.size(); ++e) {
        VecX q = box.q(), qd = box.qd();
        // The box's origin at height 0.2 + 0.1 e in the world, in the joint frame's axes.
        q.head<3>() = frame.E * (Vec3(0.0, 0.0, 0.2 + 0.1 * e) - frame.r);
        qd[3] = 0.5 * e;
        lanes.sim(e).set_q(q);
        lanes.sim(e).set_qd(qd);
      }
      const std::string what = std::string("a box on a turned root frame, ") + to_string(solver) +
                               (compat == Compat::physx ? ", compat physx" : "");
      const test::LaneFigures f = test::batch_against_alone(lanes, 300, 6, what);
      EXPECT_LE(f.ratio, test::kSensitivityFactor) << what;
      for (int e = 0; e < lanes.size(); ++e)
        EXPECT_FALSE(lanes.contacts(e).empty()) << what << " environment " << e;
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
  // Guarded, the step's contact work (eq. G-3a) is inf - inf: the guard redoes it, and a sub-step
  // diverges first (its velocity).
  EXPECT_NE(messages[0].find(guard ? "joint 'box_root' velocity qd = nan"
                                   : "link 'box' contact force f"),
            std::string::npos)
      << messages[0];
  EXPECT_EQ(messages[0], messages[1]);
  EXPECT_EQ(triggers[0], triggers[1]) << guard;
  }
}

// The step guard on the ground (docs/simd_batch.md, "The step guard"): guarded trees dropped
// from their own heights, whose landings the guard redoes, the reports and anchors of a redone
// step then their Simulation's (its sub-steps'); within kSensitivityFactor of each
// environment's own sensitivity, the same steps redone.
TEST(LaneContact, GuardedOnTheGroundAsSimulation) {
  for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    Simulation proto = test::grounded_tree(4, solver, false);
    SimulationOptions o = proto.options();
    o.guard.enabled = true;
    o.guard.max_joint_step = 0.05;
    o.guard.max_substeps = 64;
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

// The path: a grounded robot runs in the lanes, under compat none and physx, with self-collision
// too, and with self-collision alone; shapes on other links than environment 0's make a lane
// group of their own.
TEST(LaneContact, StepPath) {
  const test::AutomaticSimd automatic;  // the path checked is the automatic one
  Simulation s = test::grounded_tree(5, SolverType::pgs, false);
  Batch grounded(s, 3);
  EXPECT_EQ(grounded.step_path().find("scalar"), std::string::npos) << grounded.step_path();
  // An environment whose shapes sit on other links than environment 0's (the plan's).
  Model moved = s.model();
  moved.shapes.erase(moved.shapes.begin() + 1);
  grounded.sim(2).set_model(std::make_shared<const Model>(moved));
  EXPECT_NE(grounded.step_path().find(" lanes: 2 groups (2, 1 environments; 1 at one lane)"),
            std::string::npos)
      << grounded.step_path();
  Simulation self = s;
  ContactOptions contact;
  contact.self_collision = true;
  self.set_contact_options(contact);
  Batch selfish(self, 2);
  EXPECT_EQ(selfish.step_path().find("scalar"), std::string::npos) << selfish.step_path();
  Ground off = s.ground();  // self-collision alone
  off.enabled = false;
  selfish.sim(1).set_ground(off);
  selfish.sim(0).set_ground(off);
  EXPECT_EQ(selfish.step_path().find("scalar"), std::string::npos) << selfish.step_path();
  SimulationOptions o = s.options();
  o.compat = Compat::physx;
  Simulation physx(s.model_ptr(), o);
  physx.set_ground(s.ground());
  Batch px(physx, 2);
  EXPECT_EQ(px.step_path().find("scalar"), std::string::npos) << px.step_path();
}

}  // namespace
}  // namespace featherdrive
