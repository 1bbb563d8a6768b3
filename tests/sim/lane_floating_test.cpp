// Floating bases in Batch's SIMD lanes against each environment stepped alone as a Simulation (the
// scalar path, another operation order): docs/simd_batch.md, "Floating bases".
#include <gtest/gtest.h>

#include <cmath>
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

// A random tree of revolute and prismatic joints on a floating root, no gravity's ground to stop
// it: drives on every joint, limits and viscous friction on some, the root tumbling (its start
// velocity random) so that its rotation, the w x v term and the rotated axes all act.
Simulation floating_prototype(unsigned seed, SolverType solver) {
  auto model = test::make_random_tree(seed, 9, /*floating=*/true, /*spherical=*/false, 0.01);
  Simulation sim(model, test::lane_test_options(solver));
  std::mt19937 rng(seed);
  test::drive_every_joint(sim, rng, 300.0, 20.0);
  for (int d = 6; d < model->nv; ++d) {
    // Limits the drives' targets (within +-1) stay clear of: where a joint comes to rest exactly
    // on its limit, TGS's limit row decides between holding it and not on the last bit, so a
    // Simulation whose start velocity is 1e-15 off leaves it 1.6 rad/s apart within 26 steps
    // (a floating tree with a soft mimic row at the limit); the lanes' other operation order
    // would too.
    if (d % 3 == 0) sim.set_joint_limits(d, -1.3, 1.4);
    // Viscous friction keeps the free tree from chaos, which would grow the two step orders'
    // last bits past 1e-12 in 1000 steps.
    sim.set_joint_friction(d, JointFriction{0.0, 0.0, 0.2});
  }
  std::vector<double> q(sim.q().data(), sim.q().data() + model->nq);
  const double half = 0.3;  // the root turned by 0.6 rad about a skew axis, lifted
  q[0] = 0.2, q[1] = -0.1, q[2] = 1.5;
  q[3] = std::cos(half), q[4] = std::sin(half) * 0.6, q[5] = std::sin(half) * 0.0,
  q[6] = std::sin(half) * 0.8;
  sim.set_q(Eigen::Map<const VecX>(q.data(), model->nq));
  VecX qd = test::random_vector(model->nv, rng, 0.5);
  sim.set_qd(qd);
  return sim;
}

TEST(LaneFloating, RandomTreeAsSimulation) {
  for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    const Simulation proto = floating_prototype(7, solver);
    ASSERT_TRUE(proto.model().floating_base());
    expect_lanes_as_alone(proto, 1000, std::string("random floating tree, ") + to_string(solver),
                          7);
  }
}

// Each environment its own start (root pose and velocity) and gains: lanes that differ in every
// quantity of the root's path.
TEST(LaneFloating, EnvironmentsOfTheirOwnAsSimulation) {
  for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    const Simulation proto = floating_prototype(11, solver);
    const int n = 6;
    Batch lanes(proto, n), alone(proto, n);
    alone.set_lanes(false);
    std::mt19937 rng(3);
    for (int e = 0; e < n; ++e) {
      VecX q = proto.q();
      q[2] += 0.1 * e;
      q[4] += 0.05 * e;  // set_q normalises the quaternion
      VecX qd = test::random_vector(proto.model().nv, rng, 0.5);
      for (Batch* b : {&lanes, &alone}) {
        b->sim(e).set_q(q);
        b->sim(e).set_qd(qd);
        Drive drive = b->sim(e).drive(7);
        drive.stiffness *= 1.0 + 0.2 * e;
        b->sim(e).set_drive(7, drive);
      }
    }
    ASSERT_NE(lanes.step_path().find("lanes"), std::string::npos) << lanes.step_path();
    lanes.step(1000);
    alone.step(1000);
    double worst = 0.0;
    for (const auto& [a, b] : {std::pair{&lanes.q(), &alone.q()}, {&lanes.qd(), &alone.qd()},
                               {&lanes.drive_force(), &alone.drive_force()},
                               {&lanes.limit_force(), &alone.limit_force()},
                               {&lanes.friction_force(), &alone.friction_force()}})
      worst = std::max(worst, test::relative_difference(*a, *b));
    EXPECT_LE(worst, 1e-12) << to_string(solver);
    std::printf("random floating tree, own starts and gains, %s: largest relative difference "
                "%.1e\n", to_string(solver), worst);
  }
}

// Mimic rows on a floating tree: the sweeps of given impulses (setup_mimic) move the root too.
TEST(LaneFloating, RandomTreeWithMimicRowsAsSimulation) {
  for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    Simulation proto = floating_prototype(13, solver);
    const int nv = proto.model().nv;
    proto.set_mimic_joints({{7, 6, -1.5, 0.05}, {nv - 1, 8, -1.0, 0.0, 30.0, 0.7}});
    expect_lanes_as_alone(proto, 1000,
                          std::string("random floating tree, mimic rows, ") + to_string(solver));
  }
}

// floating_prototype(7, solver) under compat physx without gravity, its root's joint frame
// `frame` (the tree's own: none).
Simulation physx_prototype(SolverType solver, const Transform* frame = nullptr) {
  const Simulation none = floating_prototype(7, solver);
  SimulationOptions o = none.options();
  o.compat = Compat::physx;
  auto model = std::make_shared<Model>(none.model());
  model->gravity.setZero();
  if (frame) model->links[0].tree_transform = *frame;
  Simulation proto(model, o);
  for (int d = 6; d < none.model().nv; ++d) {
    proto.set_drive(d, none.drive(d));
    proto.set_joint_limits(d, none.lower_limit(d), none.upper_limit(d));
    proto.set_joint_friction(d, none.joint_friction(d));
  }
  proto.set_q(none.q());
  proto.set_qd(none.qd());
  return proto;
}

// compat physx: the root's momentum corrections and its pose integrated about its centre of mass
// (docs/math/physx_departures.md, section 2), PhysX's defaults (wrapped revolute joints, link
// damping and cfm, friction coefficients), prismatic rows with their link bias. Without gravity:
// falling for 5 s the links move at 40 m/s, and the momentum about the centre of mass (PD-4)
// subtracts that common velocity from each link's, which leaves 2e-14 of it relative to the
// root's velocity per step of either order's rounding (4e-15 without gravity), growing to 6e-11
// in 1000 steps (measured, docs/simd_batch.md).
TEST(LaneFloating, RandomTreeCompatPhysxAsSimulation) {
  for (SolverType solver : {SolverType::pgs, SolverType::tgs})
    expect_lanes_as_alone(physx_prototype(solver), 1000,
                          std::string("random floating tree, compat physx, ") + to_string(solver));
}

// The same with the root's joint frame turned (0.7 rad about a skew axis) and moved: compat
// physx turns the root about its centre of mass in the world's axes, its joint frame's turn taken
// off after (momentum_correction.cpp's integrate_root_about_com), and shifts its centre of mass
// in the world (correct_end_of_step_momentum).
TEST(LaneFloating, TurnedRootFrameCompatPhysxAsSimulation) {
  Transform frame;
  frame.E = rotation_about(Vec3(0.2, -0.6, 0.77).normalized(), 0.7);
  frame.r = Vec3(0.3, -0.2, 0.1);
  for (SolverType solver : {SolverType::pgs, SolverType::tgs})
    expect_lanes_as_alone(physx_prototype(solver, &frame), 1000,
                          std::string("random floating tree, turned root frame, compat "
                                      "physx, ") +
                              to_string(solver));
}

}  // namespace
}  // namespace featherdrive
