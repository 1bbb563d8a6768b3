// Batch: N copies stepped in parallel give, bit for bit, what each copy gives stepped alone, for
// any thread count; a divergence names the lowest diverged copy and the other copies still make
// all their steps; the whole-vector drive setters check everything before changing anything.
#include <gtest/gtest.h>

#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "featherdrive/sim/batch.hpp"
#include "support/drives.hpp"
#include "support/models.hpp"

namespace featherdrive {
namespace {

bool same_bits(const VecX& a, const VecX& b) {
  return a.size() == b.size() &&
         std::memcmp(a.data(), b.data(), sizeof(double) * static_cast<size_t>(a.size())) == 0;
}

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
  // Stiffness times position error overflows to inf at the first step.
  const Drive overflow{DriveType::force, 1e300, 0.0, std::numeric_limits<double>::infinity(), 1e300, 0.0};
  batch.sim(4).set_drive(1, overflow);
  batch.sim(2).set_drive(0, overflow);
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

}  // namespace
}  // namespace featherdrive
