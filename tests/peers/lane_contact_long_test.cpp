// Ground contacts in Batch's SIMD lanes on floating robots over 1000 steps: random trees (with and
// without spherical joints) dropped on the ground and the quadruped standing and dropped, under
// compat none and physx, each environment bounded by the scalar step's own last-bit sensitivity
// (docs/simd_batch.md, "Contacts"). Each case steps five Simulations per environment beside the
// lanes: seconds here, minutes under the sanitizers, so they run in the main build only; the
// shorter contact cases stay in featherdrive_tests (tests/sim/lane_contact_test.cpp).
#include <gtest/gtest.h>

#include <random>
#include <string>
#include <utility>

#include "featherdrive/sim/batch.hpp"
#include "support/compare.hpp"
#include "support/contact_models.hpp"
#include "support/lane_contact_models.hpp"
#include "support/lanes.hpp"
#include "support/models.hpp"

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

}  // namespace
}  // namespace featherdrive
