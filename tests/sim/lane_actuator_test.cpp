// Implicit actuators and convergence tracking in Batch's SIMD lanes (docs/simd_batch.md,
// docs/math/implicit_actuators.md) against each environment stepped alone as a Simulation: 1000
// steps within 1e-12 (the lanes' operation order differs), PGS and TGS, compat none and physx,
// with mimic rows; and the same bits whatever an environment's lane, the batch's size, the width
// and the threads.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include "featherdrive/sim/batch.hpp"
#include "featherdrive/sim/simd_isa.hpp"
#include "support/compare.hpp"
#include "support/drives.hpp"
#include "support/lanes.hpp"
#include "support/models.hpp"

namespace featherdrive {
namespace lane_actuator {
namespace {

using test::kInf;

constexpr int kEnvironments = 5;  // not a whole number of blocks: padding lanes too

// A random fixed-base tree of 9 links (revolute and prismatic joints) with force drives on every
// dof, joint limits (with `limits`) and velocity limits on some, viscous friction everywhere (no
// chaos: the last bits of two operation orders stay within 1e-12 over 1000 steps) and three mimic
// rows, two rigid and one soft. The limits lie beyond where the drives and actuators take the
// joints: a joint held against its limit goes one way or the other by a last bit, drives alone
// too (TGS, 1e-5 after 300 steps), as no two operation orders share.
Simulation actuator_prototype(unsigned seed, SolverType solver, Compat compat, bool limits = true) {
  SimulationOptions options = test::lane_test_options(solver);
  options.compat = compat;
  Simulation sim(test::make_random_tree(seed, 9, false, false, 0.01), options);
  std::mt19937 rng(seed);
  test::drive_every_joint(sim, rng, 300.0, 20.0);
  const int nv = sim.model().nv;
  for (int d = 0; d < nv; ++d) {
    sim.set_joint_friction(d, JointFriction{0.0, 0.0, 0.5});
    if (limits && d % 3 == 0) sim.set_joint_limits(d, -1.4, 1.5);
    if (d % 5 == 3) sim.set_max_joint_velocity(d, 0.6);
  }
  test::set_three_mimic_rows(sim);
  sim.set_qd(test::random_vector(nv, rng, 0.5));
  return sim;
}

// An implicit actuator of kind k % 3 (ideal PD, DC motor, remotized PD) whose gains, clips and
// table are environment e's own; the clips bind for the targets `command` gives.
ExplicitActuator implicit_actuator(int k, int e, int delay) {
  ExplicitActuator a;
  a.integration = ActuatorIntegration::implicit_law;
  a.stiffness = 60.0 + 10.0 * k + 7.0 * e;
  a.damping = 4.0 + 0.5 * e;
  a.delay = delay;
  switch (k % 3) {
    case 0:
      a.kind = ActuatorKind::ideal_pd;
      a.effort_limit = 8.0 + 0.3 * e;
      break;
    case 1:
      a.kind = ActuatorKind::dc_motor;
      a.saturation_effort = 12.0 + e;
      a.velocity_limit = 0.8;
      a.effort_limit = 9.0;
      break;
    default:
      a.kind = ActuatorKind::remotized_pd;
      a.lookup = {{-0.5, 3.0 + 0.2 * e}, {0.0, 9.0}, {0.4, 5.0}};
      a.effort_limit = 7.0;
      break;
  }
  return a;
}

// Environment e: implicit actuators of every kind on three dofs in four (some delayed, with a
// feed-forward effort), delayed drives on the others; convergence tracking on in every other
// environment.
void give_implicit_control(Simulation& s, int e) {
  const int nv = s.model().nv;
  for (int d = 0; d < nv; ++d) {
    if ((d + e) % 4 == 3) {
      s.set_drive_delay(d, (d + e) % 3);
      continue;
    }
    const Drive old = s.drive(d);
    s.set_drive(d, Drive{});
    s.set_actuator(d, implicit_actuator(d + 2 * e, e, (d + e) % 2));
    s.set_drive_target(d, old.target_position, old.target_velocity);
    s.set_actuator_feedforward(d, 0.4 * (d % 2 ? 1.0 : -1.0));
  }
  s.set_track_convergence(e % 2 == 0);
}

// Targets of call k of environment e (the same for the batch and the lone Simulation).
void implicit_command(Simulation& s, int e, int k) {
  for (int d = 0; d < s.model().nv; ++d) {
    const double x = 0.35 * std::sin(0.07 * k + 0.9 * d + 0.3 * e);
    s.set_drive_target(d, x, 0.4 * std::cos(0.05 * k + d));
  }
}

class LaneImplicitActuators : public testing::TestWithParam<std::tuple<SolverType, Compat>> {};

// Every kind of implicit actuator, per-environment gains, clips and commands, delays, mimic rows
// and convergence tracking in some environments, targets changed between calls of 1 to 9 steps:
// 1000 steps in the lanes within 1e-12 of each environment stepped alone.
TEST_P(LaneImplicitActuators, EveryKindWithMimicRowsWithinTolOfSimulation) {
  const auto [solver, compat] = GetParam();
  const std::string what = std::string(to_string(solver)) + ", compat " + to_string(compat);
  const Simulation prototype = actuator_prototype(21, solver, compat);
  // Three under compat physx: its scalar steps are most of this test's time under the sanitizers.
  Batch batch(prototype, compat == Compat::physx ? 3 : kEnvironments);
  batch.set_num_threads(2);
  std::vector<Simulation> alone = test::give_each(batch, prototype, give_implicit_control);
  EXPECT_NE(batch.step_path().find(" lanes"), std::string::npos) << batch.step_path();
  test::step_with_commands(batch, alone, 1000, implicit_command);
  test::LaneWorst worst;
  for (int e = 0; e < batch.size(); ++e)
    test::compare_with_alone(batch, e, alone[static_cast<size_t>(e)], worst, what);
  EXPECT_LE(worst.state, 1e-12) << what;
  EXPECT_LE(worst.force, 1e-12) << what;
  EXPECT_LE(worst.change, 1e-12) << what;
  // The rows acted, their forces are the actuators' (the drive's 0 on their dofs), and the
  // tracked changes are there in PGS only, in the tracking environments only.
  for (int e = 0; e < batch.size(); ++e) {
    const Simulation& s = batch.sim(e);
    for (int d = 0; d < s.model().nv; ++d)
      if (s.has_actuator(d)) EXPECT_EQ(s.drive_force()[d], 0.0) << what;
    const double change = s.last_drive_impulse_change().cwiseAbs().maxCoeff();
    if (e % 2 == 0 && solver == SolverType::pgs)
      EXPECT_GT(change, 0.0) << what << " env " << e;
    else
      EXPECT_EQ(change, 0.0) << what << " env " << e;
  }
  EXPECT_GT(alone[0].actuator_force().cwiseAbs().maxCoeff(), 1.0);
  std::printf(
      "lanes with implicit actuators, %s: q, qd %.1e, forces %.1e, drive changes %.1e "
      "(docs/simd_batch.md)\n",
      what.c_str(), worst.state, worst.force, worst.change);
}

INSTANTIATE_TEST_SUITE_P(SolversAndCompat, LaneImplicitActuators,
                         testing::Combine(testing::Values(SolverType::pgs, SolverType::tgs),
                                          testing::Values(Compat::none, Compat::physx)),
                         [](const testing::TestParamInfo<std::tuple<SolverType, Compat>>& info) {
                           return std::string(to_string(std::get<0>(info.param))) + "_" +
                                  to_string(std::get<1>(info.param));
                         });

// Each clip binds somewhere in a run: an ideal PD's at +-E, a DC motor's below E at speed, a
// remotized PD's at its table's value; one environment per kind on every actuated dof.
TEST(LaneImplicitActuatorClips, EachKindBindsAndMatchesSimulation) {
  for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    const Simulation prototype = actuator_prototype(22, solver, Compat::none, /*limits=*/false);
    const int nv = prototype.model().nv;
    Batch batch(prototype, 3);
    std::vector<Simulation> alone(3, prototype);
    auto give = [&](Simulation& s, int kind) {
      for (int d = 0; d < nv; ++d) {
        s.set_drive(d, Drive{});
        ExplicitActuator a = implicit_actuator(kind, 0, 0);
        a.stiffness = 400.0;  // far targets: every clip binds
        s.set_actuator(d, a);
        s.set_drive_target(d, d % 2 ? 2.0 : -2.0, 0.0);
      }
    };
    for (int kind = 0; kind < 3; ++kind) {
      give(batch.sim(kind), kind);
      give(alone[static_cast<size_t>(kind)], kind);
    }
    ASSERT_NE(batch.step_path().find(" lanes"), std::string::npos) << batch.step_path();
    test::LaneWorst worst;
    double bound[3] = {0.0, 0.0, 0.0};  // the largest |force| / E of each kind
    for (int k = 0; k < 100; ++k) {
      batch.step(3);
      for (Simulation& s : alone) s.step(3);
      for (int kind = 0; kind < 3; ++kind)
        for (int d = 0; d < nv; ++d)
          bound[kind] = std::max(bound[kind], std::abs(batch.sim(kind).actuator_force()[d]) /
                                                  batch.sim(kind).actuator(d).effort_limit);
    }
    for (int e = 0; e < 3; ++e)
      test::compare_with_alone(batch, e, alone[static_cast<size_t>(e)], worst, "clips");
    EXPECT_LE(worst.state, 1e-12) << to_string(solver);
    EXPECT_LE(worst.force, 1e-12) << to_string(solver);
    // ideal PD: at E; DC motor and remotized PD: within E, held below it by their own bounds
    // (the line at speed, the table's 3-9 against E = 7 on remotized dofs away from 0).
    EXPECT_DOUBLE_EQ(bound[0], 1.0) << to_string(solver);
    EXPECT_GT(bound[1], 0.5) << to_string(solver);
    EXPECT_LE(bound[1], 1.0 + 1e-12) << to_string(solver);
    EXPECT_GT(bound[2], 0.4) << to_string(solver);
    EXPECT_LE(bound[2], 1.0 + 1e-12) << to_string(solver);
    std::printf("implicit clips binding, %s: q, qd %.1e, forces %.1e\n", to_string(solver),
                worst.state, worst.force);
  }
}

// Convergence tracking without control stages (the lanes step many steps a run) in some
// environments, and an environment that diverges: it keeps the changes of the step it diverged
// in, as its Simulation does; the others every step's.
TEST(LaneConvergenceTracking, SeveralEnvironmentsAndADivergenceAsSimulation) {
  for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    const Simulation prototype = actuator_prototype(23, solver, Compat::none);
    Batch batch(prototype, kEnvironments);
    std::vector<Simulation> alone(kEnvironments, prototype);
    for (int e = 0; e < kEnvironments; ++e) {
      batch.sim(e).set_track_convergence(e != 1);
      alone[static_cast<size_t>(e)].set_track_convergence(e != 1);
    }
    ASSERT_NE(batch.step_path().find(" lanes"), std::string::npos) << batch.step_path();
    batch.step(300);
    for (Simulation& s : alone) s.step(300);
    test::LaneWorst worst;
    for (int e = 0; e < kEnvironments; ++e)
      test::compare_with_alone(batch, e, alone[static_cast<size_t>(e)], worst, "tracking");
    // Environment 3 set spinning far too fast (no velocity limit to scale it back): it diverges
    // in the call's first step.
    const int bad = 3, nv = prototype.model().nv;
    for (Simulation* s : {&batch.sim(bad), &alone[bad]}) {
      for (int d = 0; d < nv; ++d) s->set_max_joint_velocity(d, kInf);
      s->set_qd(VecX::Constant(nv, 1e200));
    }
    EXPECT_THROW(batch.step(40), DivergenceError);
    for (int e = 0; e < kEnvironments; ++e) {
      if (e == bad) {
        EXPECT_THROW(alone[bad].step(40), DivergenceError);
        continue;
      }
      alone[static_cast<size_t>(e)].step(40);
      test::compare_with_alone(batch, e, alone[static_cast<size_t>(e)], worst, "tracking");
    }
    EXPECT_EQ(batch.sim(bad).step_count(), 300);
    EXPECT_EQ(alone[bad].step_count(), 300);
    const VecX& lanes = batch.sim(bad).last_drive_impulse_change();
    const VecX& scalar = alone[bad].last_drive_impulse_change();
    for (int d = 0; d < lanes.size(); ++d) {
      // The diverged step's: non-finite where the Simulation's is (a NaN's sign aside).
      EXPECT_EQ(std::isfinite(lanes[d]), std::isfinite(scalar[d])) << d;
      if (std::isfinite(scalar[d]))
        EXPECT_LE(std::abs(lanes[d] - scalar[d]) / std::max(1.0, std::abs(scalar[d])), 1e-12) << d;
    }
    EXPECT_LE(worst.state, 1e-12) << to_string(solver);
    EXPECT_LE(worst.force, 1e-12) << to_string(solver);
    EXPECT_LE(worst.change, 1e-12) << to_string(solver);
    if (solver == SolverType::pgs)
      EXPECT_GT(batch.sim(0).last_drive_impulse_change().cwiseAbs().maxCoeff(), 0.0);
    EXPECT_EQ(batch.sim(1).last_drive_impulse_change().cwiseAbs().maxCoeff(), 0.0);
    std::printf("lanes tracking convergence, %s: q, qd %.1e, forces %.1e, drive changes %.1e\n",
                to_string(solver), worst.state, worst.force, worst.change);
  }
}

// The same environments, given the same implicit actuators, give the same bits (q, qd, the
// actuators' forces, the tracked changes) at any lane, in a batch of any size, at every width this
// CPU has and on any number of threads.
TEST(LaneImplicitActuatorBits, IndependentOfLaneBatchSizeWidthAndThreads) {
  const Simulation prototype = actuator_prototype(24, SolverType::pgs, Compat::none);
  const int nv = prototype.model().nv, nq = prototype.model().nq;
  auto run = [&](int size, SimdIsa isa, int threads, int shift) {
    Batch batch(prototype, size);
    batch.set_isa(isa);
    batch.set_num_threads(threads);
    // Environment e of the reference sits at (e + shift) % size.
    for (int e = 0; e < size; ++e) give_implicit_control(batch.sim((e + shift) % size), e % 7);
    EXPECT_EQ(batch.step_path(), std::string(to_string(isa)) + " lanes");
    for (int k = 0; k < 10; ++k) {
      for (int e = 0; e < size; ++e) implicit_command(batch.sim((e + shift) % size), e, k);
      batch.step(4);
    }
    RowMatrix out(size, nq + 3 * nv);
    for (int e = 0; e < size; ++e) {
      const Simulation& s = batch.sim((e + shift) % size);
      out.row(e) << s.q().transpose(), s.qd().transpose(), s.actuator_force().transpose(),
          s.last_drive_impulse_change().transpose();
    }
    return out;
  };
  const int n = 13;
  const RowMatrix reference = run(n, SimdIsa::sse2, 1, 0);
  for (SimdIsa isa : available_simd_isas())
    for (int threads : {1, 2, 3})
      for (int shift : {0, 5})
        EXPECT_TRUE(test::same_bits(run(n, isa, threads, shift), reference))
            << to_string(isa) << ", " << threads << " threads, shift " << shift;
  // 40 environments fill blocks of four vectors: the first 13 are the same ones.
  for (SimdIsa isa : available_simd_isas())
    EXPECT_TRUE(test::same_bits(RowMatrix(run(40, isa, 2, 0).topRows(n)), reference))
        << to_string(isa) << ", 40 environments";
}

}  // namespace
}  // namespace lane_actuator
}  // namespace featherdrive
