// Batch: N copies stepped in parallel give, bit for bit, what each copy gives stepped alone, for
// any thread count; a divergence names the lowest diverged copy and the other copies still make
// all their steps; the whole-vector drive setters check everything before changing anything.
#include <gtest/gtest.h>

#include <cstring>
#include <limits>
#include <numeric>
#include <random>
#include <vector>

#include "featherdrive/algorithm/floating_base.hpp"
#include "featherdrive/model/model_variant.hpp"
#include "featherdrive/sim/batch.hpp"
#include "support/drives.hpp"
#include "support/models.hpp"
#include "support/compare.hpp"
#include "support/contact_models.hpp"
#include "support/lanes.hpp"
#include "support/scoped_env.hpp"

namespace featherdrive {
namespace {

using test::same_bits;

// Copy i: a random state and random drives from seed i.
void configure(Simulation& sim, int i) {
  std::mt19937 rng(static_cast<unsigned>(100 + i));
  sim.set_q(test::random_configuration(sim.model(), rng));
  sim.set_qd(test::random_vector(sim.model().nv, rng, 0.5));
  test::drive_every_joint(sim, rng, 200.0 + 10.0 * i, 5.0 + i);
}

TEST(Batch, EqualsSeparateSimulationsForAnyThreadCount) {
  const auto model = test::make_random_tree(7, 8, /*floating=*/true);
  for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    SimulationOptions options;
    options.solver = solver;
    options.dt = 0.005;
    const int n = 12, steps = 20;
    std::vector<Simulation> alone;
    for (int i = 0; i < n; ++i) {
      alone.emplace_back(model, options);
      configure(alone.back(), i);
      alone.back().step(steps);
    }
    for (int threads : {1, 3, 0}) {
      Batch batch(model, n, options);
      batch.set_lanes(false);  // the scalar path: bit for bit (the lanes: batch_lanes_test.cpp)
      batch.set_num_threads(threads);
      for (int i = 0; i < n; ++i) configure(batch.sim(i), i);
      batch.step(steps);
      const RowMatrix q = batch.q(), qd = batch.qd(), f = batch.drive_force();
      ASSERT_EQ(q.rows(), n);
      ASSERT_EQ(q.cols(), model->nq);
      for (int i = 0; i < n; ++i) {
        EXPECT_TRUE(same_bits(q.row(i).transpose(), alone[static_cast<size_t>(i)].q())) << i;
        EXPECT_TRUE(same_bits(qd.row(i).transpose(), alone[static_cast<size_t>(i)].qd())) << i;
        EXPECT_TRUE(same_bits(f.row(i).transpose(), alone[static_cast<size_t>(i)].drive_force())) << i;
      }
    }
  }
}

TEST(Batch, DivergenceNamesTheLowestCopyAndTheOthersStep) {
  const auto model = test::make_planar_chain(3, 1.0, 0.5);
  Batch batch(model, 6);
  // An applied force of 1e308 overflows the velocity at the first step (a target of 1e300 is
  // refused: docs/math/implicit_drives.md eq. T3).
  VecX force = VecX::Zero(model->nv);
  force[1] = 1e308;
  batch.sim(4).set_applied_force(force);
  force.setZero();
  force[0] = 1e308;
  batch.sim(2).set_applied_force(force);
  try {
    batch.step(3);
    FAIL() << "no DivergenceError";
  } catch (const DivergenceError& e) {
    EXPECT_NE(std::string(e.what()).find("batch copy 2 (2 of 6 copies diverged)"), std::string::npos)
        << e.what();
  }
  Simulation alone(model);
  alone.step(3);
  for (int i = 0; i < 6; ++i) {
    if (i == 2 || i == 4) {
      EXPECT_EQ(batch.sim(i).step_count(), 0);
      EXPECT_TRUE(same_bits(batch.sim(i).q(), model->neutral_configuration()));
    } else {
      EXPECT_EQ(batch.sim(i).step_count(), 3);
      EXPECT_TRUE(same_bits(batch.sim(i).q(), alone.q()));
    }
  }
}

TEST(Batch, DriveSettersCheckEverythingFirst) {
  const auto model = test::make_random_tree(3, 5, /*floating=*/true, /*spherical=*/false);
  Simulation sim(model);
  const int nv = model->nv;
  // The floating root's six dofs take no drive: non-zero gains there are refused.
  EXPECT_THROW(set_drive_gains(sim, VecX::Constant(nv, 10.0), VecX::Zero(nv)), std::invalid_argument);
  VecX kp = VecX::Zero(nv);
  kp.tail(nv - 6).setConstant(10.0);
  set_drive_gains(sim, kp, VecX::Ones(nv) * 0.0);
  EXPECT_EQ(sim.drive(6).type, DriveType::force);
  EXPECT_EQ(sim.drive(0).type, DriveType::none);
  kp[nv - 1] = -1.0;
  EXPECT_THROW(set_drive_gains(sim, kp, VecX::Zero(nv)), std::invalid_argument);
  EXPECT_EQ(sim.drive(nv - 1).stiffness, 10.0);
  EXPECT_THROW(set_drive_targets(sim, VecX::Zero(nv - 1), VecX::Zero(nv)), std::invalid_argument);
  EXPECT_THROW(Batch(model, 0), std::invalid_argument);
  Batch batch(model, 2);
  EXPECT_THROW(batch.set_q(RowMatrix::Zero(3, model->nq)), std::invalid_argument);
  EXPECT_THROW(batch.sim(2), std::invalid_argument);
  EXPECT_THROW(batch.set_num_threads(-1), std::invalid_argument);
  EXPECT_THROW(batch.set_num_threads(Batch::kMaxThreads + 1), std::invalid_argument);
  EXPECT_NO_THROW(batch.set_num_threads(Batch::kMaxThreads));
}

// A spherical joint's axes take gains and limits like any other dof (PhysX's per-axis drives):
// the Batch's rows equal the Simulation setters called axis by axis.
TEST(Batch, SphericalAxesTakeGainsAndLimitsAsSimulationDoes) {
  const auto model = test::make_random_tree(11, 5, /*floating=*/false, /*spherical=*/true);
  std::vector<int> axes;
  for (const Link& l : model->links)
    if (l.joint_type == JointType::spherical)
      for (int d = l.v_index; d < l.v_index + 3; ++d) axes.push_back(d);
  ASSERT_FALSE(axes.empty());
  const int nv = model->nv;
  RowMatrix kp = RowMatrix::Constant(1, nv, 40.0), kd = RowMatrix::Constant(1, nv, 3.0);
  RowMatrix lower = RowMatrix::Constant(1, nv, -0.2), upper = RowMatrix::Constant(1, nv, 0.3);
  Simulation by_axis(model);
  for (int d = 0; d < nv; ++d) {
    by_axis.set_drive(d, Drive{DriveType::force, 40.0, 3.0});
    by_axis.set_joint_limits(d, -0.2, 0.3);
  }
  Batch batch(model, 1);
  batch.set_lanes(false);  // the scalar path: bit for bit (the lanes: lane_spherical_test.cpp)
  const int all[] = {0};
  batch.set_drive_gains(kp, kd);
  batch.set_joint_limits(all, lower, upper);
  for (int d : axes) {
    EXPECT_EQ(batch.sim(0).drive(d).type, DriveType::force) << model->dof_names[d];
    EXPECT_EQ(batch.sim(0).drive(d).stiffness, 40.0);
    EXPECT_EQ(batch.sim(0).upper_limit(d), 0.3);
  }
  VecX qd = VecX::LinSpaced(nv, -1.0, 1.0);
  by_axis.set_qd(qd);
  batch.set_qd(RowMatrix(qd.transpose()));
  by_axis.step(5);
  batch.step(5);
  EXPECT_TRUE(same_bits(batch.sim(0).q(), by_axis.q()));
  EXPECT_TRUE(same_bits(batch.sim(0).qd(), by_axis.qd()));
}

// The (N, n) arrays are the environments' storage: row i of q() is sim(i).q(), written by every
// step and setter; a copy of a batch has rows of its own; an environment assigned a Simulation
// keeps its row, and refuses one of other sizes.
TEST(Batch, StateArraysAreTheEnvironmentsStorage) {
  const auto model = test::make_random_tree(4, 6, /*floating=*/true);
  Batch batch(model, 5);
  batch.set_lanes(false);  // the scalar path: bit for bit (the lanes: batch_lanes_test.cpp)
  for (int i = 0; i < batch.size(); ++i) configure(batch.sim(i), i);
  batch.step(3);
  for (int i = 0; i < batch.size(); ++i) {
    const Simulation& s = batch.sim(i);
    EXPECT_EQ(s.q().data(), batch.q().row(i).data());
    EXPECT_EQ(s.qd().data(), batch.qd().row(i).data());
    EXPECT_EQ(s.applied_force().data(), batch.applied_force().row(i).data());
    EXPECT_EQ(s.drive_force().data(), batch.drive_force().row(i).data());
    EXPECT_EQ(s.limit_force().data(), batch.limit_force().row(i).data());
    EXPECT_EQ(s.friction_force().data(), batch.friction_force().row(i).data());
    EXPECT_EQ(s.velocity_limit_force().data(), batch.velocity_limit_force().row(i).data());
  }
  // Stepped alone from the same start, environment 2 gives what its row holds.
  Simulation alone(model);
  configure(alone, 2);
  alone.step(3);
  EXPECT_TRUE(same_bits(batch.q().row(2).transpose(), alone.q()));
  EXPECT_TRUE(same_bits(batch.drive_force().row(2).transpose(), alone.drive_force()));
  const Batch copy(batch);
  EXPECT_NE(copy.q().data(), batch.q().data());
  EXPECT_EQ(copy.sim(1).q().data(), copy.q().row(1).data());
  EXPECT_TRUE(same_bits(copy.q(), batch.q()));
  const double* row = batch.q().row(3).data();
  batch.sim(3) = alone;
  EXPECT_EQ(batch.sim(3).q().data(), row);
  EXPECT_TRUE(same_bits(batch.q().row(3).transpose(), alone.q()));
  EXPECT_THROW(batch.sim(3) = Simulation(test::make_planar_chain(2, 1.0, 0.5)),
               std::invalid_argument);
  EXPECT_TRUE(same_bits(batch.q().row(3).transpose(), alone.q()));
}

// Values for some environments: one row broadcast or one row each; bad indices, shapes and values
// change nothing.
TEST(Batch, EnvIdsAndBroadcastRows) {
  const auto model = test::make_planar_chain(3, 1.0, 0.5);
  Batch batch(model, 4);
  const std::vector<int> ids{3, 1};
  batch.set_qd(ids, RowMatrix::Constant(1, 3, 0.25));
  RowMatrix per(2, 3);
  per << 1, 2, 3, 4, 5, 6;
  batch.set_q(ids, per);
  EXPECT_EQ(batch.q().row(3), per.row(0));
  EXPECT_EQ(batch.q().row(1), per.row(1));
  EXPECT_TRUE(batch.q().row(0).isZero(0.0) && batch.q().row(2).isZero(0.0));
  EXPECT_TRUE(batch.qd().row(1).isConstant(0.25, 0.0) && batch.qd().row(3).isConstant(0.25, 0.0));
  EXPECT_TRUE(batch.qd().row(0).isZero(0.0));
  const RowMatrix q = batch.q(), qd = batch.qd();
  auto message = [&](auto f) {
    try {
      f();
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no throw");
  };
  EXPECT_EQ(message([&] { batch.set_q(std::vector<int>{0, 4}, per); }),
            "Batch: env_ids[1] = 4 is out of range [0, 4)");
  EXPECT_EQ(message([&] { batch.set_q(std::vector<int>{2, 2}, per); }),
            "Batch: env_ids[1] = 2 appears twice (also env_ids[0])");
  EXPECT_EQ(message([&] { batch.set_qd(ids, RowMatrix::Zero(3, 3)); }),
            "Batch: qd has shape (3, 3), expected (2, 3) for 2 environments, or (1, 3) for all");
  per(1, 2) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(message([&] { batch.set_q(ids, per); }),
            "Batch: environment 1: q[2] = nan is not finite");
  RowMatrix kp = RowMatrix::Constant(2, 3, 100.0);
  kp(0, 1) = -1.0;
  EXPECT_NE(message([&] { batch.set_drive_gains(ids, kp, RowMatrix::Zero(1, 3)); })
                .find("Batch: environment 3: set_drive_gains: dof 1"),
            std::string::npos);
  EXPECT_TRUE(same_bits(batch.q(), q));
  EXPECT_TRUE(same_bits(batch.qd(), qd));
  for (int i = 0; i < 4; ++i) EXPECT_EQ(batch.sim(i).drive(1).type, DriveType::none);
}

// reset: the environments named start again (the batch's initial q, or the q given; qd, forces
// and clock 0; drives stay), equal to a fresh copy of the prototype with their targets; every
// other environment's bits stay.
TEST(Batch, ResetStartsAgainAndLeavesTheOthersBitForBit) {
  const auto model = test::make_random_tree(9, 6, /*floating=*/true);
  Simulation prototype(model);
  std::mt19937 rng(3);
  prototype.set_q(test::random_configuration(*model, rng));
  test::drive_every_joint(prototype, rng, 300.0, 8.0);
  Batch batch(prototype, 5);
  batch.set_lanes(false);  // the scalar path: bit for bit (the lanes: batch_lanes_test.cpp)
  for (int i = 0; i < 5; ++i) {
    std::mt19937 r(static_cast<unsigned>(40 + i));
    batch.sim(i).set_qd(test::random_vector(model->nv, r, 0.5));
    batch.sim(i).set_applied_force(test::random_vector(model->nv, r, 2.0));
  }
  batch.step(25);
  std::vector<Simulation> before;
  for (int i = 0; i < 5; ++i) before.push_back(batch.sim(i));
  const std::vector<int> ids{3, 0};
  batch.reset(ids);
  for (int i : {1, 2, 4}) {
    const Simulation& s = batch.sim(i);
    const Simulation& b = before[static_cast<size_t>(i)];
    EXPECT_TRUE(same_bits(s.q(), b.q()) && same_bits(s.qd(), b.qd()) &&
                same_bits(s.applied_force(), b.applied_force()) &&
                same_bits(s.drive_force(), b.drive_force()) &&
                same_bits(s.limit_force(), b.limit_force()) &&
                same_bits(s.friction_force(), b.friction_force()) &&
                same_bits(s.velocity_limit_force(), b.velocity_limit_force()))
        << i;
    EXPECT_EQ(s.step_count(), 25);
    const double t = s.time(), t0 = b.time();
    EXPECT_EQ(std::memcmp(&t, &t0, sizeof(double)), 0);
  }
  for (int i : ids) {
    const Simulation& s = batch.sim(i);
    EXPECT_TRUE(same_bits(s.q(), prototype.q()));
    EXPECT_TRUE(s.qd().isZero(0.0) && s.applied_force().isZero(0.0) && s.drive_force().isZero(0.0));
    EXPECT_EQ(s.step_count(), 0);
    EXPECT_EQ(s.time(), 0.0);
  }
  batch.step(20);
  Simulation fresh = prototype;
  fresh.step(20);
  EXPECT_TRUE(same_bits(batch.sim(3).q(), fresh.q()));
  EXPECT_TRUE(same_bits(batch.sim(0).drive_force(), fresh.drive_force()));
  // A q and qd given: one row for both environments; a bad row changes nothing.
  RowMatrix q0 = prototype.q().transpose();
  q0(0, 0) += 0.1;
  batch.reset(ids, q0, RowMatrix::Constant(1, model->nv, 0.5));
  EXPECT_EQ(batch.q()(3, 0), q0(0, 0));
  EXPECT_TRUE(batch.qd().row(0).isConstant(0.5, 0.0));
  const RowMatrix q = batch.q();
  RowMatrix bad = RowMatrix::Zero(2, model->nv);
  bad(1, 0) = std::numeric_limits<double>::infinity();
  EXPECT_THROW(batch.reset(ids, std::nullopt, bad), std::invalid_argument);
  EXPECT_TRUE(same_bits(batch.q(), q));
}

// A chain of a revolute, a prismatic and a revolute joint, with its inertial parameters, armature
// and joint settings given.
struct ChainParameters {
  double mass[3] = {1.2, 0.8, 0.5};
  Vec3 com[3] = {Vec3(0.02, 0, -0.2), Vec3(0.1, 0.01, 0), Vec3(0, 0, -0.15)};
  Mat3 inertia[3] = {test::box_inertia(1.2, Vec3(0.05, 0.06, 0.4)),
                     test::box_inertia(0.8, Vec3(0.3, 0.05, 0.05)),
                     test::box_inertia(0.5, Vec3(0.04, 0.04, 0.3))};
  double armature[3] = {0.01, 0.02, 0.005};
};

std::shared_ptr<const Model> chain(const ChainParameters& p) {
  ModelBuilder b;
  b.add_link(make_link("base", "", 1.0, Vec3::Zero(), test::box_inertia(1, Vec3(.1, .1, .1)),
                       fixed_joint("weld")));
  JointSpec j[3] = {revolute_joint("shoulder", Vec3::UnitY()),
                    prismatic_joint("slide", Vec3(1, 0, 0.2), Vec3(0, 0, -0.4)),
                    revolute_joint("wrist", Vec3::UnitX(), Vec3(0.3, 0, 0))};
  const char* names[3] = {"upper", "carriage", "hand"};
  const char* parent = "base";
  for (int k = 0; k < 3; ++k) {
    j[k].armature = {p.armature[k]};
    j[k].lower_limit = -2.0;
    j[k].upper_limit = 2.0;
    b.add_link(make_link(names[k], parent, p.mass[k], p.com[k], p.inertia[k], j[k]));
    parent = names[k];
  }
  return std::make_shared<const Model>(b.build());
}

// The settings every environment shares, and the per-environment joint settings of env 1 and 3.
void drive_chain(Simulation& s) {
  set_drive_gains(s, VecX::Constant(3, 400.0), VecX::Constant(3, 20.0));
  set_drive_targets(s, Vec3(1.5, 0.3, -1.0), Vec3::Zero());
}

TEST(Batch, RandomisedEnvironmentsEqualSimulationsBuiltWithTheirParameters) {
  const ChainParameters nominal;
  ChainParameters p1 = nominal, p3 = nominal;
  p1.mass[2] = 0.9;  // scale_inertia: the inertia scales by 0.9 / 0.5
  p1.inertia[2] = nominal.inertia[2] * (0.9 / nominal.mass[2]);
  p1.com[0] = Vec3(0.05, 0, -0.25);
  p3.com[0] = Vec3(-0.01, 0.02, -0.1);
  p3.armature[0] = 0.2;
  p3.armature[2] = 0.05;
  p3.mass[1] = 2.5;  // scale_inertia false: the inertia stays
  SimulationOptions options;
  options.dt = 0.005;
  options.solver = SolverType::tgs;
  // Without lanes, bit for bit; in lanes (every setting here is per lane) within 1e-12.
  for (const auto& [threads, lanes] : {std::pair{1, false}, {2, false}, {1, true}, {2, true}}) {
    Simulation prototype(chain(nominal), options);
    drive_chain(prototype);
    Batch batch(prototype, 4);
    batch.set_num_threads(threads);
    batch.set_lanes(lanes);
    const std::vector<int> one{1}, three{3}, both{1, 3};
    batch.set_link_mass(one, 3, VecX::Constant(1, 0.9));
    batch.set_link_mass(three, 2, VecX::Constant(1, 2.5), /*scale_inertia=*/false);
    RowMatrix com(2, 3);
    com.row(0) = p1.com[0].transpose();
    com.row(1) = p3.com[0].transpose();
    batch.set_link_com(both, 1, com);
    RowMatrix armature(1, 3);
    armature << 0.2, 0.02, 0.05;
    batch.set_armature(three, armature);
    RowMatrix lower(1, 3), upper(1, 3), max_velocity(1, 3), kp(1, 3);
    lower << -0.5, -0.1, -0.3;
    upper << 0.4, 0.1, 0.2;
    max_velocity << 1.0, 0.5, 2.0;
    kp << 900.0, 50.0, 10.0;
    batch.set_joint_limits(one, lower, upper);
    batch.set_max_joint_velocity(one, max_velocity);
    batch.set_joint_friction(three, RowMatrix::Constant(1, 3, 0.3), RowMatrix::Constant(1, 3, 0.2),
                             RowMatrix::Constant(1, 3, 0.05));
    batch.set_drive_gains(three, kp, RowMatrix::Constant(1, 3, 7.0));
    batch.step(300);

    Simulation plain(chain(nominal), options), env1(chain(p1), options), env3(chain(p3), options);
    for (Simulation* s : {&plain, &env1, &env3}) drive_chain(*s);
    for (int d = 0; d < 3; ++d) {
      env1.set_joint_limits(d, lower(0, d), upper(0, d));
      env1.set_max_joint_velocity(d, max_velocity(0, d));
      env3.set_joint_friction(d, JointFriction{0.3, 0.2, 0.05});
    }
    set_drive_gains(env3, kp.row(0).transpose(), VecX::Constant(3, 7.0));
    for (Simulation* s : {&plain, &env1, &env3}) s->step(300);
    const Simulation* expected[4] = {&plain, &env1, &plain, &env3};
    for (int i = 0; i < 4; ++i) {
      const Simulation& b = batch.sim(i);
      const Simulation& e = *expected[i];
      if (!lanes) {
        EXPECT_TRUE(same_bits(b.q(), e.q())) << i << ", threads " << threads;
        EXPECT_TRUE(same_bits(b.qd(), e.qd())) << i;
        EXPECT_TRUE(same_bits(b.drive_force(), e.drive_force())) << i;
        EXPECT_TRUE(same_bits(b.limit_force(), e.limit_force())) << i;
        EXPECT_TRUE(same_bits(b.friction_force(), e.friction_force())) << i;
      }
      for (const auto& [x, y] : {std::pair{b.q(), e.q()}, {b.qd(), e.qd()},
                                 {b.drive_force(), e.drive_force()},
                                 {b.limit_force(), e.limit_force()},
                                 {b.friction_force(), e.friction_force()},
                                 {b.velocity_limit_force(), e.velocity_limit_force()}})
        // Environment 1's last joint comes to rest on its lower limit with q exactly on it,
        // where the limit row's law changes with the sign of a 1e-16 velocity (the speculative
        // branch or the release: joint_constraints.md), and the lanes' other operation order
        // flips that sign at some steps: its velocities part by up to 2e-4 at those steps, its
        // positions stay within 1e-9.
        EXPECT_LE(test::relative_difference(x, y), i == 1 && lanes ? 1e-3 : 1e-12)
            << i << (lanes ? ", lanes" : "");
      if (lanes && i == 1) EXPECT_LE(test::relative_difference(b.q(), e.q()), 1e-9);
    }
    // The randomisations really change the motion.
    EXPECT_FALSE(same_bits(env1.q(), plain.q()));
    EXPECT_FALSE(same_bits(env3.q(), plain.q()));
    // Read back.
    EXPECT_EQ(batch.link_mass(3), Eigen::Vector4d(0.5, 0.9, 0.5, 0.5));
    EXPECT_EQ(batch.link_com(1).row(3), p3.com[0].transpose());
    EXPECT_EQ(batch.armature()(3, 0), 0.2);
    EXPECT_EQ(batch.lower_limit()(1, 1), -0.1);
    EXPECT_EQ(batch.upper_limit()(0, 1), 2.0);
    EXPECT_EQ(batch.static_friction()(3, 2), 0.3);
    EXPECT_EQ(batch.max_joint_velocity()(1, 0), 1.0);
  }
}

TEST(Batch, RandomisationRefusesBadValuesAndChangesNothing) {
  const auto model = test::make_random_tree(5, 5, /*floating=*/true, /*spherical=*/false);
  Batch batch(model, 3);
  const std::vector<int> ids{0, 2};
  const auto* before = &batch.sim(2).model();
  EXPECT_THROW(batch.set_link_mass(ids, 2, Eigen::Vector2d(1.0, -1.0)), std::invalid_argument);
  EXPECT_THROW(batch.set_link_mass(ids, 99, VecX::Ones(1)), std::invalid_argument);
  EXPECT_THROW(batch.set_armature(ids, RowMatrix::Constant(1, model->nv, -0.1)),
               std::invalid_argument);
  EXPECT_EQ(&batch.sim(2).model(), before);
  EXPECT_EQ(&batch.sim(0).model(), before);
  // The floating root's six dofs take no limits: they must be given the +-inf they have.
  try {
    batch.set_joint_limits(ids, RowMatrix::Constant(1, model->nv, -1.0),
                           RowMatrix::Constant(1, model->nv, 1.0));
    FAIL() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("Batch: environment 0: joint limits: dof 0 of joint"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(batch.sim(0).lower_limit(6), model->lower_limit[6]);
  // A model of another topology is refused by set_model, naming the difference.
  Simulation sim(test::make_planar_chain(3, 1.0, 0.5));
  try {
    sim.set_model(test::make_planar_chain(3, 1.0, 0.6));
    FAIL() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("set_model: the model has another topology: link 2 "
                                         "('link2'): joint origin"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(sim.set_model(test::make_planar_chain(4, 1.0, 0.5)), std::invalid_argument);
}

// set_drive_delay is all or nothing: delays whose histories exceed kMaxDelaySamples are refused
// before any environment changes, and a refused environment leaves the others as they were.
std::vector<int> every_env(const Batch& batch) {
  std::vector<int> ids(static_cast<size_t>(batch.size()));
  std::iota(ids.begin(), ids.end(), 0);
  return ids;
}

TEST(Batch, DriveDelayIsAllOrNothing) {
  const auto model = test::make_planar_chain(2, 1.0, 0.5);
  Simulation prototype(model);
  for (int d = 0; d < model->nv; ++d) prototype.set_drive(d, {DriveType::force, 10.0, 1.0});
  Batch batch(prototype, 1000);
  batch.set_drive_delay(std::vector<int>{5}, RowMatrix::Constant(1, model->nv, 3.0));
  // 1000 environments x 2 dofs x (kMaxDelay + 1) samples: over 2^26, refused whole.
  const long long needed = 1000LL * model->nv * (kMaxDelay + 1);
  ASSERT_GT(needed, Batch::kMaxDelaySamples);
  try {
    batch.set_drive_delay(every_env(batch), RowMatrix::Constant(1, model->nv, kMaxDelay));
    FAIL() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("need " + std::to_string(needed) + " samples"),
              std::string::npos)
        << e.what();
  }
  for (int i = 0; i < batch.size(); ++i)
    for (int d = 0; d < model->nv; ++d) ASSERT_EQ(batch.sim(i).drive_delay(d), i == 5 ? 3 : 0);
  // Within the bound every environment takes it (and the old histories go).
  batch.set_drive_delay(every_env(batch), RowMatrix::Constant(1, model->nv, 7.0));
  for (int i = 0; i < batch.size(); ++i) EXPECT_EQ(batch.sim(i).drive_delay(1), 7);
  EXPECT_THROW(Batch(prototype, Batch::kMaxSize + 1), std::invalid_argument);
}

// observe() puts the fields side by side; frame_positions() is each environment's tip of a planar
// chain, sum of l (-sin phi_k, 0, -cos phi_k) over the links with phi_k the sum of the angles.
TEST(Batch, ObserveAndFramePositions) {
  const double l = 0.5;
  const auto model = test::make_planar_chain(3, 1.0, l);
  for (int threads : {1, 2}) {
    Batch batch(model, 7);
    batch.set_num_threads(threads);
    std::mt19937 rng(11);
    for (int i = 0; i < 7; ++i) {
      batch.sim(i).set_q(test::random_vector(3, rng, 2.0));
      test::drive_every_joint(batch.sim(i), rng, 100.0, 3.0);
    }
    batch.step(4);
    const std::vector<Observation> fields{Observation::qd, Observation::target_position,
                                          Observation::drive_force, Observation::q};
    const RowMatrix obs = batch.observe(fields);
    ASSERT_EQ(obs.cols(), 12);
    const RowMatrix tip = batch.frame_positions(3, Vec3(0, 0, -l));
    for (int i = 0; i < 7; ++i) {
      const Simulation& s = batch.sim(i);
      EXPECT_EQ(obs.row(i).segment(0, 3).transpose(), s.qd());
      EXPECT_EQ(obs(i, 4), s.drive(1).target_position);
      EXPECT_EQ(obs.row(i).segment(6, 3).transpose(), s.drive_force());
      EXPECT_EQ(obs.row(i).segment(9, 3).transpose(), s.q());
      Vec3 expected = Vec3::Zero();
      double phi = 0.0;
      for (int k = 0; k < 3; ++k) {
        phi += s.q()[k];
        expected += l * Vec3(-std::sin(phi), 0.0, -std::cos(phi));
      }
      EXPECT_LT((tip.row(i).transpose() - expected).norm(), 1e-14) << i;
    }
  }
}

// Boxes of masses m_i resting on the ground (set_link_mass): each environment's ground carries its
// own weight, m_i g along z (a steady state's linear momentum balance), and its contact outputs
// are, bit for bit, those of the same box stepped alone, for 1 and 2 threads, on the scalar
// path; through the lanes (another operation order: docs/simd_batch.md, "Contacts") within
// 1e-11 of them.
TEST(Batch, ContactForcesPerEnvironmentCarryEachBoxsWeight) {
  const std::vector<double> masses{0.5, 1.0, 2.0, 3.7};
  const int n = static_cast<int>(masses.size());
  Simulation prototype = test::ground_box_simulation(SolverType::pgs, 0.0);
  SimulationOptions options = prototype.options();
  options.position_iterations = 50;  // converges the four corners' rows within each step
  prototype.set_options(options);
  const Link& box = prototype.model().links[0];
  std::vector<Simulation> alone;
  for (double m : masses) {
    alone.push_back(prototype);
    alone.back().set_model(std::make_shared<const Model>(with_link_inertial(
        prototype.model(), 0, m, box.com, Mat3(box.inertia_com * (m / box.mass)))));
    alone.back().step(200);
  }
  for (const bool lanes : {false, true})
  for (int threads : {1, 2}) {
    Batch batch(prototype, n);
    batch.set_num_threads(threads);
    batch.set_lanes(lanes);
    batch.set_link_mass(std::vector<int>{0, 1, 2, 3}, 0, Eigen::Map<const VecX>(masses.data(), n));
    EXPECT_EQ(batch.link_contact_force(), RowMatrix::Zero(n, 3));
    batch.step(200);
    const RowMatrix f = batch.link_contact_force();
    ASSERT_EQ(f.rows(), n);
    ASSERT_EQ(f.cols(), 3);
    for (int i = 0; i < n; ++i) {
      const double weight = masses[static_cast<size_t>(i)] * test::kContactGravity;
      EXPECT_LT(std::abs(f(i, 2) / weight - 1.0), 1e-9) << i << ", threads " << threads;
      EXPECT_LT(std::hypot(f(i, 0), f(i, 1)), 1e-9 * weight) << i;
      const Simulation& lone = alone[static_cast<size_t>(i)];
      if (lanes) {
        EXPECT_LE(test::lane_difference(batch, i, lone), 1e-11) << i;
        continue;
      }
      EXPECT_TRUE(same_bits(batch.sim(i).q(), lone.q())) << i;
      EXPECT_EQ(f.row(i).transpose(), lone.link_contact_force()[0]) << i;
      const auto c = batch.contacts(i), expected = lone.contacts();
      ASSERT_EQ(c.size(), expected.size()) << i;
      ASSERT_EQ(c.size(), 4u) << i;  // the box's four bottom corners
      for (size_t k = 0; k < c.size(); ++k) {
        EXPECT_EQ(c[k].normal_impulse, expected[k].normal_impulse) << i << ", point " << k;
        EXPECT_EQ(c[k].friction_impulse, expected[k].friction_impulse) << i << ", point " << k;
        EXPECT_EQ(c[k].position, expected[k].position) << i << ", point " << k;
      }
    }
  }
  EXPECT_THROW(Batch(prototype, 2).contacts(2), std::invalid_argument);
}

// A reset environment starts its contacts over: right after the reset it reports none, and from
// then on it steps as a fresh copy of the prototype, bit for bit (the friction anchors its box
// kept while resting are gone).
TEST(Batch, ResetStartsTheContactsOver) {
  Simulation prototype = test::ground_box_simulation(SolverType::pgs, 0.0);
  Batch batch(prototype, 2), fresh(prototype, 1);
  RowMatrix qd = RowMatrix::Zero(1, prototype.model().nv);
  qd(0, 0) = 0.3;  // env 1 slides off: other anchors, another place
  batch.set_qd(std::vector<int>{1}, qd);
  batch.step(60);
  ASSERT_FALSE(batch.contacts(1).empty());
  batch.reset(std::vector<int>{1});
  EXPECT_TRUE(batch.contacts(1).empty());
  EXPECT_EQ(batch.link_contact_force().row(1), RowMatrix::Zero(1, 3));
  batch.step(40);
  fresh.step(40);
  EXPECT_TRUE(same_bits(batch.sim(1).q(), fresh.sim(0).q()));
  EXPECT_TRUE(same_bits(batch.sim(1).qd(), fresh.sim(0).qd()));
  EXPECT_EQ(batch.link_contact_force().row(1), fresh.link_contact_force().row(0));
}

}  // namespace
}  // namespace featherdrive

namespace featherdrive {
namespace {

// Batch through the SIMD lanes (docs/simd_batch.md, "Batch through the lanes"): every setter and
// every change made through a handed-out sim(i) reaches the lanes before the next step, each
// environment stays within 1e-12 of a Simulation given the same changes, and a setting the lanes
// do not simulate sends that environment to the scalar step, named in step_path() and env_path().
TEST(Batch, LanesFollowEverySetterAndHandedOutSimulations) {
  const test::AutomaticSimd automatic;  // the path checked is the automatic one
  const auto model = test::make_random_tree(13, 7, /*floating=*/false, /*spherical=*/false);
  SimulationOptions options;
  options.dt = 0.005;
  options.solver = SolverType::tgs;
  Simulation proto(model, options);
  std::mt19937 rng(13);
  test::drive_every_joint(proto, rng, 300.0, 20.0);
  const int n = 9, nv = model->nv;
  std::vector<Simulation> alone(static_cast<size_t>(n), proto);
  Batch batch(proto, n);
  ASSERT_EQ(batch.step_path().find("lanes"), batch.step_path().size() - 5) << batch.step_path();
  auto step_all = [&](int steps) {
    batch.step(steps);
    for (Simulation& s : alone) s.step(steps);
  };
  auto expect_within = [&](const char* when) {
    for (int i = 0; i < n; ++i) {
      const Simulation& b = batch.sim(i);
      const Simulation& a = alone[static_cast<size_t>(i)];
      EXPECT_LE(test::relative_difference(b.q(), a.q()), 1e-12) << when << ", env " << i;
      EXPECT_LE(test::relative_difference(b.qd(), a.qd()), 1e-12) << when << ", env " << i;
      EXPECT_LE(test::relative_difference(b.drive_force(), a.drive_force()), 1e-12) << when;
      EXPECT_LE(test::relative_difference(b.velocity_limit_force(), a.velocity_limit_force()),
                1e-12) << when;
      EXPECT_EQ(b.step_count(), a.step_count());
      EXPECT_EQ(b.time(), a.time());
    }
  };
  step_all(10);
  expect_within("as made");
  // Batch setters on some environments.
  const std::vector<int> some{1, 5};
  RowMatrix targets = RowMatrix::Constant(1, nv, 0.4);
  batch.set_drive_targets(some, targets, RowMatrix::Zero(1, nv));
  RowMatrix vmax = RowMatrix::Constant(1, nv, 0.35);
  const std::vector<int> limited{5, 7};
  batch.set_max_joint_velocity(limited, vmax);
  batch.set_link_mass(std::vector<int>{2}, 3, VecX::Constant(1, 2.0));
  for (int i : some)
    for (int d = 0; d < nv; ++d)
      alone[static_cast<size_t>(i)].set_drive_target(d, 0.4, 0.0);
  for (int i : limited)
    for (int d = 0; d < nv; ++d) alone[static_cast<size_t>(i)].set_max_joint_velocity(d, 0.35);
  alone[2].set_model(std::make_shared<const Model>(batch.sim(2).model()));
  // A change made through a handed-out environment.
  Simulation& handed = batch.sim(4);
  step_all(5);
  Drive stiff = handed.drive(1);
  stiff.stiffness = 900.0;
  handed.set_drive(1, stiff);
  alone[4].set_drive(1, stiff);
  step_all(30);
  expect_within("after the setters");
  EXPECT_GT(alone[5].velocity_limit_force().cwiseAbs().maxCoeff() +
                alone[7].velocity_limit_force().cwiseAbs().maxCoeff(),
            0.0);
  // Options of its own: that environment steps in a lane group of its own, the others in
  // theirs, then it joins them again.
  SimulationOptions other = handed.options();
  other.dt = 0.004;
  handed.set_options(other);
  EXPECT_NE(batch.step_path().find("lanes: 2 groups ("), std::string::npos)
      << batch.step_path();
  EXPECT_NE(batch.env_path(4).find(" lanes, group 1"), std::string::npos) << batch.env_path(4);
  handed.set_options(options);
  EXPECT_EQ(batch.step_path().find("scalar"), std::string::npos);
  // A floating base steps in lanes.
  Batch floating(test::make_random_tree(13, 4, /*floating=*/true, /*spherical=*/false), 3);
  EXPECT_NE(floating.step_path().find("lanes"), std::string::npos) << floating.step_path();
  floating.set_lanes(false);
  EXPECT_EQ(floating.step_path(), "scalar: lanes off (set_lanes)");
}

}  // namespace
}  // namespace featherdrive
