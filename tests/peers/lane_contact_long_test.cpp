// Ground contacts in Batch's SIMD lanes over 1000 steps: random floating trees (with and without
// spherical joints, with self-collision) dropped on the ground, a robot resting on itself on the
// ground, the quadruped standing and dropped, boxes resting,
// sliding and falling, a fixed tree under compat physx, and the examples' Ant loaded through io
// (standing, walking, with implicit DC motors), each environment bounded by the scalar step's own
// last-bit sensitivity (docs/simd_batch.md, "Contacts"). Each case steps five Simulations per
// environment beside the lanes: seconds here, minutes under the sanitizers (up to 178 s a case),
// so they run in the main build only; the short contact cases stay in featherdrive_tests
// (tests/sim/lane_contact_test.cpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <random>
#include <string>
#include <utility>

#include "featherdrive/algorithm/kinematics.hpp"
#include "featherdrive/io/scene.hpp"
#include "featherdrive/sim/batch.hpp"
#include "support/compare.hpp"
#include "support/contact_models.hpp"
#include "support/lane_contact_models.hpp"
#include "support/lanes.hpp"
#include "support/models.hpp"
#include "support/scoped_env.hpp"
#include "support/source_tree.hpp"

namespace featherdrive {
namespace {

// Each case's figures against the bound LaneFigures gives: the lanes stay as close to the scalar
// step as a last-bit change of its start moves it (contact rows amplify both alike).
TEST(LaneContact, RandomTreesDroppedOnTheGroundAsSimulation) {
  for (const Compat compat : {Compat::none, Compat::physx})
  for (const bool spherical : {false, true})
    for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
      Batch lanes(test::grounded_tree(5, solver, spherical, compat), 7);
      std::mt19937 rng(17);
      test::drop_from_own_heights(lanes, rng);
      const std::string what = std::string("random trees on the ground") +
                               (spherical ? " (spherical joints), " : ", ") + to_string(solver) +
                               (compat == Compat::physx ? ", compat physx" : "");
      const test::LaneFigures f = test::batch_against_alone(lanes, 1000, 10, what);
      EXPECT_LE(f.ratio, test::kSensitivityFactor) << what;
      int touching = 0;
      for (int e = 0; e < lanes.size(); ++e) touching += !lanes.contacts(e).empty();
      EXPECT_GE(touching, 4) << what;
      EXPECT_TRUE(lanes.contacts(4).empty()) << what;  // the one still falling
    }
}

// Shapes on three sets of links in one batch: three lane groups (docs/simd_batch.md, "Lane
// groups"), each environment's contacts as its Simulation's, 1000 steps, compat none and physx.
TEST(LaneContact, ShapesOnOtherLinksInLaneGroupsAsSimulation) {
  const test::AutomaticSimd automatic;  // the path checked is the automatic one
  for (const Compat compat : {Compat::none, Compat::physx})
    for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
      Batch lanes = test::shapes_on_three_link_sets(solver, compat);
      EXPECT_NE(lanes.step_path().find("3 groups (3, 2, 1 environments; 1 at one lane)"),
                std::string::npos)
          << lanes.step_path();
      const std::string what = std::string("shapes on three link sets, ") + to_string(solver) +
                               (compat == Compat::physx ? ", compat physx" : "");
      EXPECT_LE(test::batch_against_alone(lanes, 1000, 10, what).ratio, test::kSensitivityFactor)
          << what;
      EXPECT_FALSE(lanes.contacts(5).empty()) << what;  // the group of one on the ground
    }
}

// The same trees with self-collision on (the self rows per lane, before each sweep): links that
// touch each other as they land and tumble, besides the ground.
TEST(LaneContact, SelfCollidingRandomTreesOnTheGroundAsSimulation) {
  for (const Compat compat : {Compat::none, Compat::physx})
    for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
      Batch lanes(test::self_colliding_tree(8, solver, compat, true), 7);
      std::mt19937 rng(17);
      test::drop_from_own_heights(lanes, rng);
      int touching = 0;  // self contacts over the steps, of the environments alone
      for (int e = 0; e < lanes.size(); ++e) {
        Simulation alone = lanes.sim(e);
        for (int k = 0; k < 1000; ++k) {
          alone.step();
          for (const ContactReport& r : alone.contacts()) touching += r.other_link >= 0;
        }
      }
      const std::string what = std::string("self-colliding random trees on the ground, ") +
                               to_string(solver) +
                               (compat == Compat::physx ? ", compat physx" : "");
      EXPECT_GT(touching, 100) << what;
      const test::LaneFigures f = test::batch_against_alone(lanes, 1000, 10, what);
      EXPECT_LE(f.ratio, test::kSensitivityFactor) << what;
      EXPECT_TRUE(lanes.contacts(4).empty()) << what;  // the one still falling
    }
}

// lane_contact_models.hpp's robot whose box rests on its own plate, on the ground, from its
// starts (one robot high above the ground for the whole run).
TEST(LaneContact, ARobotRestingOnItselfOnTheGroundAsSimulation) {
  for (const Compat compat : {Compat::none, Compat::physx})
    for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
      Batch lanes(test::self_touching_robot(solver, compat), 6);
      test::self_touching_starts(lanes);
      const std::string what = std::string("a robot resting on itself on the ground, ") +
                               to_string(solver) +
                               (compat == Compat::physx ? ", compat physx" : "");
      const test::LaneFigures f = test::batch_against_alone(lanes, 1000, 10, what);
      EXPECT_LE(f.ratio, test::kSensitivityFactor) << what;
      EXPECT_EQ(lanes.contacts(0).size(), 8u) << what;  // four corners on the ground, four above
      EXPECT_EQ(lanes.contacts(4).size(), 4u) << what;  // the box on the falling plate
    }
}

// contact_models.hpp's quadruped under compat none, its PD drives holding the standing pose:
// standing, dropped from heights of its own, turned, one high above the ground.
TEST(LaneContact, QuadrupedStandingAndDroppedAsSimulation) {
  for (const Compat compat : {Compat::none, Compat::physx})
  for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    Simulation sim =
        test::on_ground(test::make_quadruped(1.0), solver, compat, Material{1.0, 1.0, 0.0});
    const Model& model = sim.model();
    VecX q = sim.q();
    for (const char* leg : {"fl", "fr", "hl", "hr"})
      for (const auto& [joint, target] : {std::pair{"_hip", test::kQuadrupedHip},
                                          std::pair{"_knee", test::kQuadrupedKnee}}) {
        const std::string name = std::string(leg) + joint;
        q[model.links[model.joint_link_index(name)].q_index] = target;
        sim.set_drive(name, Drive{DriveType::force, 300.0, 10.0, test::kInf, target, 0.0});
      }
    Batch lanes(sim, 7);
    std::mt19937 rng(17);
    const double lift[] = {0.0, 0.05, 0.1, 0.2, 200.0, 0.02, 0.3};
    for (int e = 0; e < lanes.size(); ++e) {
      VecX qe = q;
      qe[2] = test::quadruped_standing_height() + lift[e];
      qe[3] = 1.0, qe[4] = 0.03 * e, qe[5] = -0.02 * e, qe[6] = 0.01 * e;  // set_q normalises
      lanes.sim(e).set_q(qe);
      lanes.sim(e).set_qd(test::random_vector(model.nv, rng, 0.1));
    }
    const std::string what = std::string("quadruped on the ground, ") + to_string(solver) +
                             (compat == Compat::physx ? ", compat physx" : "");
    const test::LaneFigures f = test::batch_against_alone(lanes, 1000, 10, what);
    EXPECT_LE(f.ratio, test::kSensitivityFactor) << what;
    EXPECT_GE(lanes.contacts(0).size(), 4u) << what;
    EXPECT_TRUE(lanes.contacts(4).empty()) << what;
  }
}

// contact_models.hpp's box (cases a, b) under compat none: resting, sliding at speeds of its
// own, dropped, one high above the ground.
TEST(LaneContact, BoxesRestingSlidingAndFallingAsSimulation) {
  for (const Compat compat : {Compat::none, Compat::physx})
  for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    const Simulation box =
        test::on_ground(test::make_ground_box(0.5), solver, compat, Material{0.5, 0.5, 0.0});
    Batch lanes(box, 6);
    const double heights[] = {0.1, 0.1, 0.1, 0.25, 200.0, 0.1};
    const double speeds[] = {0.0, 0.5, 1.5, 0.0, 0.0, 3.0};
    for (int e = 0; e < lanes.size(); ++e) {
      VecX q = box.q(), qd = box.qd();
      q[2] = heights[e];
      qd[3] = speeds[e];  // along the box's x, its start axes the world's
      qd[2] = 0.4 * (e % 2);
      lanes.sim(e).set_q(q);
      lanes.sim(e).set_qd(qd);
    }
    const std::string what = std::string("boxes on the ground, ") + to_string(solver) +
                             (compat == Compat::physx ? ", compat physx" : "");
    const test::LaneFigures f = test::batch_against_alone(lanes, 1000, 10, what);
    EXPECT_LE(f.ratio, test::kSensitivityFactor) << what;
    EXPECT_EQ(lanes.contacts(0).size(), 4u) << what;
    EXPECT_TRUE(lanes.contacts(4).empty()) << what;
  }
}

// A fixed random tree of revolute joints (no prismatic, spherical or floating joint asks for the
// link bias) with a ball on each link, its lowest 5 mm into the ground, under compat physx: the
// bias is formed for the contacts alone. (One of its balls sits where its link cannot move along
// the normal: J Lambda J is rounding, counted as 0 (C22a; contact_test.cpp's
// FixedRandomTreeOnTheGroundStaysBounded).)
TEST(LaneContact, FixedTreeOnTheGroundUnderCompatPhysxAsSimulation) {
  Model m = *test::make_random_tree(1, 7, /*floating=*/false, /*spherical=*/false, 0.01);
  for (const Link& link : m.links) ASSERT_NE(link.joint_type, JointType::prismatic);
  for (int i = 1; i < m.num_links(); ++i) {
    CollisionShape ball;
    ball.link = i;
    ball.size = Vec3(0.05, 0.0, 0.0);
    m.shapes.push_back(ball);
  }
  for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    SimulationOptions o = test::lane_test_options(solver);
    o.compat = Compat::physx;
    Simulation sim(std::make_shared<const Model>(m), o);
    Data posed(sim.model());
    forward_kinematics(sim.model(), posed, sim.q());
    Ground ground;
    ground.enabled = true;
    ground.height = std::numeric_limits<double>::infinity();
    for (const CollisionShape& ball : sim.model().shapes)
      ground.height = std::min(ground.height, posed.world_position[ball.link].z() - 0.045);
    sim.set_ground(ground);
    std::mt19937 rng(1);
    test::drive_every_joint(sim, rng, 100.0, 10.0);
    for (int d = 0; d < sim.model().nv; ++d)
      sim.set_joint_friction(d, JointFriction{0.0, 0.0, 0.2});
    Batch lanes(sim, 5);
    for (int e = 0; e < lanes.size(); ++e)
      lanes.sim(e).set_qd(test::random_vector(sim.model().nv, rng, 0.3));
    const std::string what = std::string("fixed tree on the ground, compat physx, ") +
                             to_string(solver);
    const test::LaneFigures f = test::batch_against_alone(lanes, 1000, 10, what);
    EXPECT_LE(f.ratio, test::kSensitivityFactor) << what;
    EXPECT_FALSE(lanes.contacts(0).empty()) << what;
  }
}

// Environments of their own: on the ground as the scene starts, dropped from 1 to 10 cm, turned
// about z, one high above the ground for the whole run. (Dropped from 30 cm under TGS, the Ant
// lands where a friction decision rests on the last bits: the lanes parted from the scalar run by
// 2.9e-2 where four last-bit changes of its start parted it by 1.6e-3, a sample of the same
// chaos; docs/simd_batch.md, "Contacts".)
void ant_starts(Batch& batch) {
  const double lift[] = {0.0, 0.05, 0.1, 0.01, 1000.0, 0.02};
  for (int e = 0; e < batch.size(); ++e) {
    VecX q = batch.sim(e).q();
    q[2] += lift[e];
    q[3] = 1.0, q[4] = 0.0, q[5] = 0.0, q[6] = 0.05 * e;  // set_q normalises
    batch.sim(e).set_q(q);
  }
}

TEST(LaneContactIo, AntOnTheGroundAsSimulation) {
  for (const char* file : {"ant_standing.yaml", "ant_walk.yaml"}) {
    const Simulation ant = make_simulation(load_scene(test::kExamples + file));
    ASSERT_TRUE(ant.ground().enabled) << file;
    Batch lanes(ant, 6);
    ant_starts(lanes);
    const std::string what = std::string("Ant on the ground (") + file + ", " +
                             to_string(ant.options().solver) + ")";
    const test::LaneFigures f = test::batch_against_alone(lanes, 1000, 10, what);
    EXPECT_LE(f.ratio, test::kSensitivityFactor) << what;
    EXPECT_FALSE(lanes.contacts(0).empty()) << what;
    EXPECT_TRUE(lanes.contacts(4).empty()) << what;
  }
}

// The features compose in the lanes: the standing Ant's hinges driven by implicit DC motors (their
// rows in the drives' place, the speed-dependent clip solved in the sweep) while its feet are on
// the ground, against each environment alone, bounded as above.
TEST(LaneContactIo, AntOnTheGroundWithImplicitActuators) {
  Simulation ant = make_simulation(load_scene(test::kExamples + std::string("ant_standing.yaml")));
  for (int d = 6; d < ant.model().nv; ++d) {
    const Drive drive = ant.drive(d);
    ExplicitActuator motor;
    motor.kind = ActuatorKind::dc_motor;
    motor.stiffness = drive.stiffness;
    motor.damping = drive.damping;
    motor.effort_limit = 0.1;
    motor.saturation_effort = 0.12;
    motor.velocity_limit = 1.0;
    motor.integration = ActuatorIntegration::implicit_law;
    ant.set_drive(d, Drive{});
    ant.set_actuator(d, motor);
    ant.set_drive_target(d, drive.target_position, 0.0);
  }
  Batch lanes(ant, 6);
  ant_starts(lanes);
  const test::LaneFigures f =
      test::batch_against_alone(lanes, 1000, 10, "Ant on the ground, implicit DC motors");
  EXPECT_LE(f.ratio, test::kSensitivityFactor);
  EXPECT_FALSE(lanes.contacts(0).empty());
  // The motors' rows replaced the drives' and their clip binds (the drives alone push up to
  // 0.13 Nm here).
  for (int e = 0; e < lanes.size(); ++e) {
    EXPECT_EQ(lanes.sim(e).drive_force().cwiseAbs().maxCoeff(), 0.0) << e;
    EXPECT_LE(lanes.sim(e).actuator_force().cwiseAbs().maxCoeff(), 0.1 * (1 + 1e-12)) << e;
  }
  EXPECT_GE(lanes.sim(0).actuator_force().cwiseAbs().maxCoeff(), 0.1 * (1 - 1e-12));
}

}  // namespace
}  // namespace featherdrive
