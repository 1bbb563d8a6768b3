// The implicit drives' delay (sim/drive_delay.hpp): a system whose every drive is delayed by K
// steps and that starts at rest at its targets answers any target sequence exactly as the
// undelayed system does, K steps later (time invariance of the step): the closed form the tests
// compare with, bit for bit. Also eq. (9)'s start-up rule, Batch, divergence and bad delays.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "featherdrive/sim/batch.hpp"
#include "featherdrive/sim/simulation.hpp"
#include "support/compare.hpp"
#include "support/models.hpp"

namespace featherdrive {
namespace {

using test::kInf;

bool same_double_bits(double a, double b) {
  return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b);
}

// Zero until step `onset`, then a step of 0.4 plus a sine, on every dof (phase per dof).
double target(int step, int dof, int onset) {
  return step < onset ? 0.0 : 0.4 + 0.3 * std::sin(0.21 * step + dof);
}

Simulation driven_chain(SolverType solver, DriveType type, int delay) {
  SimulationOptions o;
  o.dt = 0.01;
  o.solver = solver;
  o.position_iterations = 4;
  o.velocity_iterations = 1;
  // No gravity: at rest at q = 0 with targets 0 nothing moves, so the first K steps of the
  // delayed run are the undelayed run's rest.
  Simulation sim(test::make_planar_chain(3, 1.0, 0.5, Vec3::Zero()), o);
  const double kp = type == DriveType::force ? 400.0 : 900.0;
  const double kd = type == DriveType::force ? 20.0 : 45.0;
  for (int d = 0; d < 3; ++d) {
    sim.set_drive(d, Drive{type, kp, kd, d == 2 ? 30.0 : kInf, 0.0, 0.0});
    sim.set_drive_delay(d, delay);
  }
  return sim;
}

void run(Simulation& sim, int steps, int onset, std::vector<VecX>& q, std::vector<VecX>& f) {
  for (int k = 0; k < steps; ++k) {
    for (int d = 0; d < 3; ++d) sim.set_drive_target(d, target(k, d, onset), 0.0);
    sim.step();
    q.push_back(sim.q());
    f.push_back(sim.drive_force());
  }
}

struct ShiftCase {
  SolverType solver;
  DriveType type;
};

class DriveDelayShift : public ::testing::TestWithParam<ShiftCase> {};

TEST_P(DriveDelayShift, DelayedResponseIsTheUndelayedOneKStepsLater) {
  const auto [solver, type] = GetParam();
  constexpr int kSteps = 60, kOnset = 5;
  Simulation plain = driven_chain(solver, type, 0);
  std::vector<VecX> q0, f0;
  run(plain, kSteps, kOnset, q0, f0);
  ASSERT_GT(std::abs(q0.back()[0]), 0.1);  // it moved
  for (int K : {1, 3, 7}) {
    Simulation delayed = driven_chain(solver, type, K);
    std::vector<VecX> q, f;
    run(delayed, kSteps + K, kOnset, q, f);
    for (int n = 0; n < K; ++n) EXPECT_EQ(q[n], VecX::Zero(3)) << "K " << K << " step " << n;
    for (int n = 0; n < kSteps; ++n)
      for (int d = 0; d < 3; ++d) {
        ASSERT_TRUE(same_double_bits(q[n + K][d], q0[n][d])) << "K " << K << " step " << n << " dof " << d;
        ASSERT_TRUE(same_double_bits(f[n + K][d], f0[n][d])) << "K " << K << " step " << n << " dof " << d;
      }
    // drive() reports the targets as commanded, not as the row used them.
    EXPECT_EQ(delayed.drive(1).target_position, target(kSteps + K - 1, 1, kOnset));
  }
}

INSTANTIATE_TEST_SUITE_P(Solvers, DriveDelayShift,
                         ::testing::Values(ShiftCase{SolverType::pgs, DriveType::force},
                                           ShiftCase{SolverType::tgs, DriveType::force},
                                           ShiftCase{SolverType::pgs, DriveType::acceleration},
                                           ShiftCase{SolverType::tgs, DriveType::acceleration}));

// eq. (9): until K steps are made the drive sees the oldest target it has, so a target held from
// the first step gives the undelayed run exactly; and a new delay starts its history over.
TEST(DriveDelay, ConstantTargetFromTheStartIsNotDelayed) {
  Simulation plain = driven_chain(SolverType::tgs, DriveType::force, 0);
  Simulation delayed = driven_chain(SolverType::tgs, DriveType::force, 4);
  for (Simulation* s : {&plain, &delayed})
    for (int d = 0; d < 3; ++d) s->set_drive_target(d, 0.5 - 0.2 * d, 0.1);
  for (int k = 0; k < 20; ++k) {
    plain.step();
    delayed.step();
    for (int d = 0; d < 3; ++d) ASSERT_TRUE(same_double_bits(plain.q()[d], delayed.q()[d])) << k;
  }
  EXPECT_EQ(delayed.drive_delay(2), 4);
  EXPECT_EQ(delayed.drive_delays().pushes(2), 20);
  delayed.set_drive_delay(2, 4);
  EXPECT_EQ(delayed.drive_delays().pushes(2), 0);
  delayed.set_drive(2, Drive{DriveType::force, 10.0, 1.0});  // gains change, the delay stays
  EXPECT_EQ(delayed.drive_delay(2), 4);
  delayed.set_drive(2, Drive{});  // no drive, no delay
  EXPECT_EQ(delayed.drive_delay(2), 0);
}

// A step that diverges takes its push back: the retried step sees what an undisturbed run sees.
TEST(DriveDelay, ADivergedStepLeavesTheHistoryAsItWas) {
  Simulation sim = driven_chain(SolverType::pgs, DriveType::force, 2);
  Simulation reference = sim;
  std::vector<VecX> q, f;
  for (Simulation* s : {&sim, &reference}) {
    q.clear();
    run(*s, 6, 0, q, f);
  }
  sim.set_applied_force(VecX::Constant(3, 1e308));
  EXPECT_THROW(sim.step(), DivergenceError);
  EXPECT_EQ(sim.drive_delays().pushes(0), 6);
  sim.set_applied_force(VecX::Zero(3));
  for (int k = 6; k < 12; ++k)
    for (Simulation* s : {&sim, &reference}) {
      for (int d = 0; d < 3; ++d) s->set_drive_target(d, target(k, d, 0), 0.0);
      s->step();
    }
  for (int d = 0; d < 3; ++d) EXPECT_TRUE(same_double_bits(sim.q()[d], reference.q()[d])) << d;
}

// Each environment with its own delays steps as a lone Simulation with them, on 2 threads, bit
// for bit without SIMD lanes and within 1e-12 in them (another operation order); a reset empties
// the reset environments' histories only.
TEST(DriveDelay, BatchEnvironmentsEqualSimulationsAndResetClearsTheHistory) {
  for (const bool lanes : {false, true}) {
    const Simulation prototype = driven_chain(SolverType::tgs, DriveType::force, 0);
    Batch batch(prototype, 4);
    batch.set_num_threads(2);
    batch.set_lanes(lanes);
    EXPECT_EQ(batch.step_path().find("scalar"), lanes ? std::string::npos : 0u);
    RowMatrix delays(4, 3);
    delays << 0, 0, 0, 1, 2, 3, 5, 5, 5, 2, 0, 4;
    const std::vector<int> all = {0, 1, 2, 3};
    batch.set_drive_delay(all, delays);
    EXPECT_EQ(batch.drive_delay(), delays);
    std::vector<Simulation> alone(4, prototype);
    for (int i = 0; i < 4; ++i)
      for (int d = 0; d < 3; ++d)
        alone[static_cast<size_t>(i)].set_drive_delay(d, static_cast<int>(delays(i, d)));
    auto command = [&](int k) {
      for (int i = 0; i < 4; ++i)
        for (int d = 0; d < 3; ++d) {
          const double x = target(k + 3 * i, d, 2);
          batch.sim(i).set_drive_target(d, x, 0.0);
          alone[static_cast<size_t>(i)].set_drive_target(d, x, 0.0);
        }
    };
    auto expect_equal = [&](const char* when) {
      for (int i = 0; i < 4; ++i)
        for (int d = 0; d < 3; ++d)
          if (lanes)
            ASSERT_LE(std::abs(batch.q()(i, d) - alone[static_cast<size_t>(i)].q()[d]), 1e-12)
                << when << ": env " << i << " dof " << d;
          else
            ASSERT_TRUE(same_double_bits(batch.q()(i, d), alone[static_cast<size_t>(i)].q()[d]))
                << when << ": env " << i << " dof " << d;
    };
    for (int k = 0; k < 15; ++k) {
      command(k);
      batch.step();
      for (Simulation& s : alone) s.step();
    }
    expect_equal("before the reset");
    const std::vector<int> reset = {1, 3};
    batch.reset(reset);
    for (int i : reset) {  // a fresh start: the prototype's state, the same delays, no history
      Simulation fresh = prototype;
      for (int d = 0; d < 3; ++d) fresh.set_drive_delay(d, static_cast<int>(delays(i, d)));
      alone[static_cast<size_t>(i)] = fresh;
    }
    for (int k = 15; k < 30; ++k) {
      command(k);
      batch.step();
      for (Simulation& s : alone) s.step();
    }
    expect_equal("after the reset");
    EXPECT_EQ(batch.sim(1).drive_delays().pushes(2), 15);
    EXPECT_EQ(batch.sim(2).drive_delays().pushes(2), 30);
  }
}

constexpr auto delay_error = test::invalid_argument_message;

TEST(DriveDelay, BadDelaysGetOneLineAndChangeNothing) {
  Simulation sim = driven_chain(SolverType::pgs, DriveType::force, 0);
  EXPECT_EQ(delay_error([&] { sim.set_drive_delay(0, -1); }),
            "drive of joint 'joint1': delay = -1 must be in [0, 100000] steps");
  EXPECT_EQ(delay_error([&] { sim.set_drive_delay("joint2", 100001); }),
            "drive of joint 'joint2': delay = 100001 must be in [0, 100000] steps");
  sim.set_drive(2, Drive{});
  EXPECT_NE(delay_error([&] { sim.set_drive_delay(2, 3); })
                .find("joint 'joint3' (dof 2) has no drive (type none)"),
            std::string::npos);
  sim.set_drive_delay(2, 0);  // no delay is always fine
  ExplicitActuator pd;
  pd.kind = ActuatorKind::ideal_pd;
  sim.set_actuator(2, pd);
  EXPECT_EQ(delay_error([&] { sim.set_drive_delay(2, 1); }),
            "joint 'joint3' has an explicit actuator: a drive delay of 1 steps would do nothing "
            "(give the actuator its own delay)");
  EXPECT_EQ(sim.drive_delay(0), 0);

  Batch batch(sim, 2);
  RowMatrix delays(2, 3);
  delays << 1, 1, 0, 2.5, 0, 0;
  const std::vector<int> all = {0, 1};
  EXPECT_EQ(delay_error([&] { batch.set_drive_delay(all, delays); }),
            "Batch: environment 1: drive delay of joint 'joint1' = 2.5 must be a whole number of "
            "steps in [0, 100000]");
  delays << 1, 1, 0, 1, 0, 3;
  EXPECT_NE(delay_error([&] { batch.set_drive_delay(all, delays); }).find("Batch: environment 1: "),
            std::string::npos);
  EXPECT_EQ(batch.drive_delay(), RowMatrix::Zero(2, 3));  // nothing changed
}

}  // namespace
}  // namespace featherdrive
