// The step guard (docs/math/step_guard.md): bit for bit the unguarded step where it does not
// trigger, the closed form of a redone step on a slider, bounded runs where the unguarded step
// diverges, the bad values refused.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "featherdrive/model/model_builder.hpp"
#include "featherdrive/sim/batch.hpp"
#include "support/compare.hpp"
#include "support/drives.hpp"
#include "support/lanes.hpp"
#include "support/models.hpp"

namespace featherdrive {
namespace {

using test::kInf;

SimulationOptions guard_options(SolverType solver, bool guard, double dt = 1.0 / 60.0) {
  SimulationOptions o;
  o.dt = dt;
  o.solver = solver;
  o.guard.enabled = guard;
  return o;
}

bool guard_same_outputs(const Simulation& a, const Simulation& b) {
  return test::same_bits(a.q(), b.q()) && test::same_bits(a.qd(), b.qd()) &&
         test::same_bits(a.drive_force(), b.drive_force()) &&
         test::same_bits(a.limit_force(), b.limit_force()) &&
         test::same_bits(a.friction_force(), b.friction_force()) &&
         test::same_bits(a.velocity_limit_force(), b.velocity_limit_force());
}

// Where no test fails, the guard changes nothing: the same bits as the unguarded step, every
// step, for PGS and TGS, compat none and physx, with gravity, limits, friction and a delay.
TEST(StepGuard, NotTriggeringIsTheUnguardedStepBitForBit) {
  const auto model = test::make_benchmark_chain(6, Vec3(0, 0, -9.81));
  for (const Compat compat : {Compat::none, Compat::physx})
    for (const SolverType solver : {SolverType::pgs, SolverType::tgs}) {
      SimulationOptions off = guard_options(solver, false, 1.0 / 240.0), on = off;
      off.compat = on.compat = compat;
      on.guard.enabled = true;
      Simulation a(model, off), b(model, on);
      for (Simulation* s : {&a, &b}) {
        std::mt19937 rng(5);
        test::drive_every_joint(*s, rng, 200.0, 20.0);
        s->set_joint_friction(3, JointFriction{0.2, 0.1, 0.05});
        s->set_drive_delay(4, 2);
      }
      for (int k = 0; k < 200; ++k) {
        a.step();
        b.step();
        ASSERT_TRUE(guard_same_outputs(a, b)) << to_string(compat) << " " << to_string(solver)
                                              << " step " << k << " n " << b.guard_substeps();
        ASSERT_EQ(b.guard_substeps(), 1);
      }
      EXPECT_EQ(b.guard_triggers(), 0);
    }
}

// A triggered step on a slider (no force along the axis): the first n = 2, 4, ... whose every
// sub-step moves at most max_joint_step, each sub-step n P implicit-Euler steps of dt / (n P)
// towards the target x_T - v_T (time to the step's end) (P = 1 for PGS, the position
// iterations for TGS: docs/math/implicit_drives.md, eq. 41), written here from the spec.
TEST(StepGuard, TriggeredSliderStepIsImplicitEulerSubsteps) {
  const double m = 2.0, kp = 900.0, kd = 10.0, xT = 0.5, vT = 0.4, dt = 1.0 / 30.0, bound = 0.06;
  const auto model = test::make_slider(m, Vec3(1, 0, 0), Vec3(0, 0, -9.81));
  // The same law as an implicit actuator (implicit_actuators.md, I4): the same sub-steps, its
  // force reported as the actuator's.
  for (const bool actuator : {false, true})
  for (const SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    SimulationOptions o = guard_options(solver, true, dt);
    o.guard.max_joint_step = bound;
    Simulation sim(model, o);
    if (actuator) {
      ExplicitActuator pd;
      pd.kind = ActuatorKind::ideal_pd;
      pd.stiffness = kp;
      pd.damping = kd;
      pd.integration = ActuatorIntegration::implicit_law;
      sim.set_actuator("slide", pd);
      sim.set_drive_target("slide", xT, vT);
    } else {
      sim.set_drive("slide", Drive{DriveType::force, kp, kd, kInf, xT, vT});
    }
    const int P = solver == SolverType::tgs ? o.position_iterations : 1;
    double x = 0.0, v = 0.0;
    int triggered = 0;
    for (int k = 0; k < 20; ++k) {
      double x1 = x, v1 = v, impulse = 0.0;
      int chosen = 0;
      for (int n = 1; n <= o.guard.max_substeps && !chosen; n *= 2) {
        x1 = x, v1 = v, impulse = 0.0;
        bool within = true;
        const int K = n * P;
        const double h = dt / K;
        for (int i = 0; i < n; ++i) {
          const double start = x1;
          for (int j = 1; j <= P; ++j) {
            const int step = i * P + j;  // of K
            const double target = xT - vT * (K - step) * h;
            const double vn =
                (m * v1 + h * (kp * (target - x1) + kd * vT)) / (m + h * h * kp + h * kd);
            impulse += m * (vn - v1);
            v1 = vn;
            x1 += h * vn;
          }
          within = within && std::abs(x1 - start) <= bound;
        }
        if (within) chosen = n;
      }
      ASSERT_GT(chosen, 0);
      sim.step();
      triggered += chosen > 1;
      ASSERT_EQ(sim.guard_substeps(), chosen) << to_string(solver) << " step " << k;
      ASSERT_NEAR(sim.q()[0], x1, 1e-12) << to_string(solver) << " step " << k;
      ASSERT_NEAR(sim.qd()[0], v1, 1e-12) << to_string(solver) << " step " << k;
      const double force = actuator ? sim.actuator_force()[0] : sim.drive_force()[0];
      ASSERT_NEAR(force, impulse / dt, 1e-9 * (1 + std::abs(impulse / dt)));
      if (actuator) ASSERT_EQ(sim.drive_force()[0], 0.0);
      x = x1;
      v = v1;
    }
    EXPECT_GE(triggered, 2) << to_string(solver);  // the case exercises the sub-steps
    EXPECT_EQ(sim.guard_triggers(), triggered);
    EXPECT_EQ(sim.guard_exhausted(), 0);
  }
}

// An explicit PD actuator on a 1 kg slider at kp dt^2 / m = 10: explicit Euler's oscillation
// grows without bound; the guard's sub-steps of dt / n (kp (dt / n)^2 / m <= 10 / 16) settle it
// on the target.
TEST(StepGuard, BoundsAStiffExplicitActuator) {
  const double m = 1.0, dt = 0.01, kp = 10.0 * m / (dt * dt), kd = 20.0;
  const auto model = test::make_slider(m, Vec3(1, 0, 0), Vec3(0, 0, -9.81));
  for (const bool guard : {false, true}) {
    Simulation sim(model, guard_options(SolverType::pgs, guard, dt));
    ExplicitActuator a;
    a.kind = ActuatorKind::ideal_pd;
    a.stiffness = kp;
    a.damping = kd;
    sim.set_actuator(0, a);
    sim.set_drive_target(0, 0.2, 0.0);
    bool diverged = false;
    for (int k = 0; k < 300 && !diverged; ++k) {
      try {
        sim.step();
      } catch (const DivergenceError&) {
        diverged = true;
      }
      diverged = diverged || !(std::abs(sim.q()[0]) < 10.0);
    }
    EXPECT_EQ(diverged, !guard);
    if (guard) {
      EXPECT_NEAR(sim.q()[0], 0.2, 1e-6);
      EXPECT_GT(sim.guard_triggers(), 0);
      EXPECT_EQ(sim.guard_exhausted(), 0);
    }
  }
}

// A Batch with its lanes off steps its Simulations: one guarded environment equals a guarded
// Simulation bit for bit (through triggered steps), as does one that recomputes every start's
// energies. Through the lanes, which take the guard (docs/simd_batch.md, "The step guard"), it
// equals it within 1e-12 (another operation order) with the same steps redone.
TEST(StepGuard, BatchEqualsASimulationWithLanesOffAndOn) {
  const auto model = test::make_benchmark_chain(32, Vec3::Zero());
  const SimulationOptions o = guard_options(SolverType::pgs, true);
  Simulation alone(model, o);
  test::drive_benchmark_chain(alone);
  Batch batch(model, 2, o), lanes(model, 3, o);
  batch.set_lanes(false);
  for (int i = 0; i < 2; ++i) test::drive_benchmark_chain(batch.sim(i));
  for (int i = 0; i < 3; ++i) test::drive_benchmark_chain(lanes.sim(i));
  // The start's energies reused from the last step's end (step_guard.cpp) are the ones a new
  // forward kinematics pass gives: set_model (same model) drops them every step here.
  Simulation recomputed(model, o);
  test::drive_benchmark_chain(recomputed);
  for (int k = 0; k < 60; ++k) {
    recomputed.set_model(recomputed.model_ptr());
    recomputed.step();
  }
  EXPECT_EQ(batch.step_path(), "scalar: lanes off (set_lanes)");
  EXPECT_NE(lanes.step_path().find(" lanes"), std::string::npos) << lanes.step_path();
  alone.step(60);
  batch.step(60);
  lanes.step(60);
  EXPECT_TRUE(guard_same_outputs(recomputed, alone));
  EXPECT_EQ(recomputed.guard_triggers(), alone.guard_triggers());
  EXPECT_GT(alone.guard_triggers(), 0);
  EXPECT_EQ(batch.sim(1).guard_triggers(), alone.guard_triggers());
  EXPECT_TRUE(guard_same_outputs(batch.sim(1), alone));
  test::LaneWorst worst;
  for (int i = 0; i < 3; ++i) {
    test::compare_with_alone(lanes, i, alone, worst, "chain");
    EXPECT_EQ(lanes.sim(i).guard_triggers(), alone.guard_triggers());
    EXPECT_EQ(lanes.sim(i).guard_exhausted(), alone.guard_exhausted());
  }
  EXPECT_LT(worst.state, 1e-12);
  EXPECT_LT(worst.force, 1e-12);
}

// A random fixed-base tree (spherical joints too) at dt 1/30 with limits, friction and velocity
// limits on some dofs; environment e's drives are stiff (kp 4000: steps the guard redoes as
// their targets jump) for e % 3 == 0, soft (kp 40: kept) otherwise, and e % 4 == 3 is not
// guarded (and soft: stiff and unguarded, a floating tree's steps diverge).
SimulationOptions guard_lane_options(SolverType solver, Compat compat, bool guard) {
  SimulationOptions o = test::lane_test_options(solver);
  o.dt = 1.0 / 30.0;
  o.compat = compat;
  o.guard.enabled = guard;
  return o;
}

Simulation guard_prototype(SolverType solver, Compat compat, bool floating = false) {
  auto model = test::make_random_tree(11, 7, floating, true, 0.01);
  SimulationOptions o = guard_lane_options(solver, compat, true);
  if (floating) o.dt = 0.01;  // its light links spin up at dt 1/30 even guarded
  Simulation sim(model, o);
  std::mt19937 rng(3);
  test::drive_every_joint(sim, rng, 40.0, 4.0);
  for (int d = 0; d < model->nv; ++d) {
    if (!dof_has_rows(*model, d)) continue;
    if (d % 4 == 1) sim.set_joint_friction(d, JointFriction{0.3, 0.2, 0.1});
    if (d % 5 == 3) sim.set_max_joint_velocity(d, 6.0);
  }
  return sim;
}

void give_guard_lane_gains(Simulation& sim, int e) {
  const Model& m = sim.model();
  const bool stiff = e % 3 == 0 && e % 4 != 3;
  // A floating tree, whose root the drives swing too, is stiff (redone) at 3 % of the gains.
  const double scale = m.floating_base() ? 0.03 : 1.0;
  const double kp = stiff ? 4000.0 * scale : 40.0, kd = stiff ? 20.0 * scale : 4.0;
  for (int d = 0; d < m.nv; ++d) {
    if (!dof_has_rows(m, d)) continue;
    Drive drive = sim.drive(d);
    drive.type = DriveType::force;
    drive.stiffness = kp;
    drive.damping = kd;
    sim.set_drive(d, drive);
  }
  if (e % 4 == 3) {
    SimulationOptions o = sim.options();
    o.guard.enabled = false;
    sim.set_options(o);
  }
}

// Targets jumping by up to 1.2 rad every call (calls of 1 to 9 steps).
void jump_guard_lane_targets(Simulation& sim, int e, int k) {
  const Model& m = sim.model();
  for (int d = 0; d < m.nv; ++d) {
    if (!dof_has_rows(m, d)) continue;
    const double x = 0.6 * std::sin(0.7 * k + 1.3 * d + 0.5 * e);
    sim.set_drive_target(d, x, 0.2 * std::cos(0.3 * k + d));
  }
}

// Environment s's guard counters equal those of a, stepped alone; returns the largest relative
// difference of their accounts.
double expect_same_guard(const Simulation& s, const Simulation& a, const std::string& what) {
  EXPECT_EQ(s.guard_triggers(), a.guard_triggers()) << what;
  EXPECT_EQ(s.guard_exhausted(), a.guard_exhausted()) << what;
  EXPECT_EQ(s.guard_substeps(), a.guard_substeps()) << what;
  const GuardAccount &x = s.guard_account(), &y = a.guard_account();
  double worst = 0.0;
  for (const auto& [u, v] : {std::pair{x.created, y.created}, std::pair{x.dissipated, y.dissipated},
                             std::pair{x.scale, y.scale}})
    worst = std::max(worst, std::abs(u - v) / std::max(1.0, std::abs(v)));
  return worst;
}

TEST(StepGuard, GuardedLanesEqualGuardedSimulations) {
  for (const Compat compat : {Compat::none, Compat::physx})
    for (const SolverType solver : {SolverType::pgs, SolverType::tgs}) {
      const std::string what = std::string(to_string(compat)) + " " + to_string(solver);
      const Simulation proto = guard_prototype(solver, compat);
      Batch batch(proto, 7);
      std::vector<Simulation> alone = test::give_each(batch, proto, give_guard_lane_gains);
      EXPECT_NE(batch.step_path().find(" lanes"), std::string::npos) << batch.step_path();
      test::step_with_commands(batch, alone, 1000, jump_guard_lane_targets);
      test::LaneWorst worst;
      long redone = 0, kept_guarded = 0;
      double account = 0.0;
      for (int e = 0; e < batch.size(); ++e) {
        const Simulation& a = alone[static_cast<size_t>(e)];
        test::compare_with_alone(batch, e, a, worst, what);
        account = std::max(account, expect_same_guard(batch.sim(e), a, what));
        if (e % 4 != 3 && e % 3 == 0) redone += a.guard_triggers() > 0;
        if (e % 4 != 3 && e % 3 != 0) kept_guarded += a.guard_triggers() == 0;
      }
      std::printf("%s: guarded lanes against guarded Simulations: state %.1e, forces %.1e, "
                  "accounts %.1e (docs/simd_batch.md)\n",
                  what.c_str(), worst.state, worst.force, account);
      EXPECT_LT(worst.state, 1e-12) << what;
      EXPECT_LT(worst.force, 1e-12) << what;
      EXPECT_LT(account, 1e-12) << what;
      // The case exercises both: the stiff environments redone, soft ones kept every step.
      EXPECT_EQ(redone, 2) << what;
      EXPECT_GE(kept_guarded, 2) << what;
    }
}

// A floating tree at dt 0.01 (its root falling freely and swung by its drives: test (i) on the
// root's rotation, the work over its velocity coordinates) is sensitive: the scalar step's own
// difference from a start a last bit off reaches 1.5e-11 in 300 steps. Each environment in the
// lanes stays within kSensitivityFactor of that sensitivity, its own (tests/support/lanes.hpp),
// with the same steps redone.
TEST(StepGuard, GuardedFloatingLanesWithinTheirOwnSensitivity) {
  const Simulation proto = guard_prototype(SolverType::tgs, Compat::none, /*floating=*/true);
  Batch batch(proto, 7);
  std::vector<Simulation> alone = test::give_each(batch, proto, give_guard_lane_gains);
  std::vector<Simulation> nudged = alone;
  for (Simulation& s : nudged) {
    VecX qd = s.qd();
    for (double& v : qd) v += std::numeric_limits<double>::epsilon() * std::max(1.0, std::abs(v));
    s.set_qd(qd);
  }
  EXPECT_NE(batch.step_path().find(" lanes"), std::string::npos) << batch.step_path();
  for (int k = 0, done = 0; done < 300; ++k) {
    const int n = std::min(1 + k % 9, 300 - done);
    for (int e = 0; e < batch.size(); ++e) {
      jump_guard_lane_targets(batch.sim(e), e, k);
      jump_guard_lane_targets(alone[static_cast<size_t>(e)], e, k);
      jump_guard_lane_targets(nudged[static_cast<size_t>(e)], e, k);
    }
    batch.step(n);
    for (Simulation& s : alone) s.step(n);
    for (Simulation& s : nudged) s.step(n);
    done += n;
  }
  double ratio = 0.0;
  for (int e = 0; e < batch.size(); ++e) {
    const Simulation& a = alone[static_cast<size_t>(e)];
    test::LaneWorst worst;
    test::compare_with_alone(batch, e, a, worst, "floating");
    const double own =
        std::max(1e-12, test::simulation_difference(nudged[static_cast<size_t>(e)], a));
    ratio = std::max(ratio, std::max(worst.state, worst.force) / own);
    expect_same_guard(batch.sim(e), a, "floating env " + std::to_string(e));
  }
  std::printf("floating: guarded lanes against guarded Simulations: largest ratio to an "
              "environment's own sensitivity %.2g (docs/simd_batch.md)\n", ratio);
  EXPECT_LE(ratio, test::kSensitivityFactor);
  EXPECT_GT(alone[0].guard_triggers(), 0);
  EXPECT_EQ(alone[1].guard_triggers(), 0);
}

// A guarded batch's bits do not depend on where an environment sits, the width, the batch size
// or the threads: each environment's guard runs on its own lane's values (docs/simd_batch.md,
// "Determinism").
TEST(StepGuard, GuardedLanesBitsIndependentOfLaneWidthSizeAndThreads) {
  const Simulation proto = guard_prototype(SolverType::pgs, Compat::none);
  const int nq = proto.model().nq, nv = proto.model().nv;
  // Environment e of the reference (settings e % 7) sits at (e + shift) % size.
  auto run = [&](int size, SimdIsa isa, int threads, int shift) {
    Batch batch(proto, size);
    batch.set_isa(isa);
    batch.set_num_threads(threads);
    auto at = [&](int e) -> Simulation& { return batch.sim((e + shift) % size); };
    for (int e = 0; e < size; ++e) give_guard_lane_gains(at(e), e % 7);
    for (int k = 0; k < 40; ++k) {
      for (int e = 0; e < size; ++e) jump_guard_lane_targets(at(e), e % 7, k);
      batch.step(1 + k % 3);
    }
    RowMatrix out(size, nq + nv + 2);
    for (int e = 0; e < size; ++e)
      out.row(e) << at(e).q().transpose(), at(e).qd().transpose(),
          static_cast<double>(at(e).guard_triggers()), at(e).guard_account().created;
    return out;
  };
  const RowMatrix reference = run(7, SimdIsa::sse2, 1, 0);
  EXPECT_GT(reference(0, nq + nv), 0.0);  // environment 0 was redone
  for (SimdIsa isa : available_simd_isas())
    for (int threads : {1, 2})
      for (int shift : {0, 3})
        EXPECT_TRUE(test::same_bits(run(7, isa, threads, shift), reference))
            << to_string(isa) << ", " << threads << " threads, shift " << shift;
  for (SimdIsa isa : available_simd_isas())
    EXPECT_TRUE(test::same_bits(RowMatrix(run(19, isa, 2, 0).topRows(7)), reference))
        << to_string(isa) << ", 19 environments";
}

// A guarded environment whose redone step still diverges (its sub-steps too) stops with the
// state before that step and its Simulation's message; the others step on.
TEST(StepGuard, GuardedLaneThatDivergesStopsAsItsSimulation) {
  Simulation proto = guard_prototype(SolverType::tgs, Compat::none);
  SimulationOptions o = proto.options();
  o.guard.max_substeps = 4;
  proto.set_options(o);
  // Without velocity limits, which would scale the huge velocity below back to theirs.
  for (int d = 0; d < proto.model().nv; ++d)
    if (dof_has_rows(proto.model(), d)) proto.set_max_joint_velocity(d, kInf);
  Batch batch(proto, 5);
  EXPECT_NE(batch.step_path().find(" lanes"), std::string::npos) << batch.step_path();
  const int bad[] = {3};
  batch.step(2);
  batch.set_qd(bad, RowMatrix::Constant(1, proto.model().nv, 1e200));
  const VecX q_before = batch.q().row(3).transpose();
  Simulation alone = batch.simulation(3);
  std::string message;
  try {
    alone.step();
  } catch (const DivergenceError& e) {
    message = e.what();
  }
  ASSERT_FALSE(message.empty());
  EXPECT_EQ(alone.guard_triggers(), 1);
  try {
    batch.step(4);
    ADD_FAILURE() << "no DivergenceError";
  } catch (const DivergenceError& e) {
    EXPECT_NE(std::string(e.what()).find("batch copy 3 (1 of 5"), std::string::npos) << e.what();
  }
  ASSERT_TRUE(batch.divergences()[3].has_value());
  EXPECT_EQ(batch.divergences()[3]->message, message);
  EXPECT_EQ(batch.step_count()[3], 2);
  EXPECT_EQ(batch.sim(3).guard_triggers(), 1);
  EXPECT_TRUE(test::same_bits(VecX(batch.q().row(3).transpose()), q_before));
  for (int e : {0, 1, 2, 4}) EXPECT_EQ(batch.step_count()[e], 6) << e;
}

// Test (iii)'s account on a slider without gravity, PGS, steps the guard keeps: each step is the
// implicit Euler of the drive law, v1 = (m v0 + h (kp (xT - x0) + kd vT)) / (m + h kd + h^2 kp),
// so the energy created beyond the work is -m (v1 - v0)^2 / 2 (G-4), the drive's work beyond its
// spring and damper -kp (h v1)^2 / 2 (G-10), the dampers' share h kd v1^2 (G-7) and the scale
// K0 + K1 + |W| (G-5). The account is their sums, leaking by 0.999 a step (G-8).
TEST(StepGuard, TheAccountOfASliderIsItsClosedForm) {
  const double m = 2.0, kp = 50.0, kd = 3.0, xT = 0.1, vT = 0.05, h = 1.0 / 60.0;
  const auto model = test::make_slider(m, Vec3(1, 0, 0), Vec3::Zero());
  Simulation sim(model, guard_options(SolverType::pgs, true, h));
  sim.set_drive("slide", Drive{DriveType::force, kp, kd, kInf, xT, vT});
  sim.set_qd(VecX::Constant(1, 0.3));
  double x = 0.0, v = 0.3, created = 0.0, dissipated = 0.0, scale = 0.0;
  for (int k = 0; k < 5; ++k) {
    const double v1 = (m * v + h * (kp * (xT - x) + kd * vT)) / (m + h * kd + h * h * kp);
    const double work = m * (v1 - v) * v1;  // the drive's force (impulse / h) times h v1
    created = 0.999 * created - 0.5 * m * (v1 - v) * (v1 - v) - 0.5 * kp * h * v1 * h * v1;
    dissipated = 0.999 * dissipated + h * kd * v1 * v1;
    scale = 0.999 * scale + 0.5 * m * (v * v + v1 * v1) + std::abs(work);
    x += h * v1;
    v = v1;
    sim.step();
    ASSERT_EQ(sim.guard_triggers(), 0);
    EXPECT_NEAR(sim.q()[0], x, 1e-14);
    const GuardAccount& a = sim.guard_account();
    EXPECT_NEAR(a.created, created, 1e-12 * std::abs(created)) << k;
    EXPECT_NEAR(a.dissipated, dissipated, 1e-12 * dissipated) << k;
    EXPECT_NEAR(a.scale, scale, 1e-12 * scale) << k;
  }
}

// The account is state: a second simulation given the first's state() continues with the
// same account, so its next step keeps the same bits; a bad account is refused and leaves the
// state as it was.
TEST(StepGuard, TheAccountTravelsWithTheState) {
  const auto model = test::make_slider(2.0, Vec3(1, 0, 0), Vec3::Zero());
  Simulation a(model, guard_options(SolverType::pgs, true));
  a.set_drive("slide", Drive{DriveType::force, 50.0, 3.0, kInf, 0.1, 0.05});
  a.set_qd(VecX::Constant(1, 0.3));
  for (int k = 0; k < 3; ++k) a.step();
  Simulation b = a;
  State fresh = b.state();
  fresh.guard_account = {};
  b.set_state(fresh);
  ASSERT_EQ(b.guard_account().scale, 0.0);
  b.set_state(a.state());
  ASSERT_GT(b.guard_account().scale, 0.0);
  a.step();
  b.step();
  EXPECT_EQ(a.guard_account().created, b.guard_account().created);
  EXPECT_EQ(a.guard_account().scale, b.guard_account().scale);
  State bad = a.state();
  bad.guard_account.dissipated = -1.0;
  bad.q[0] = 7.0;
  try {
    b.set_state(bad);
    ADD_FAILURE() << "a negative dissipation was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "guard account: dissipated = -1 must be finite and >= 0");
  }
  EXPECT_EQ(b.q()[0], a.q()[0]);
  EXPECT_EQ(b.guard_account().scale, a.guard_account().scale);
}

TEST(StepGuard, BadBoundsAreRefusedNamingKeyAndValue) {
  auto message = [](const StepGuard& g) {
    SimulationOptions o;
    o.guard = g;
    try {
      validate_options(o);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_EQ(message({true, -0.1, 64}),
            "simulation options: guard.max_joint_step = -0.1 must be finite and > 0");
  EXPECT_EQ(message({true, 0.0, 64}),
            "simulation options: guard.max_joint_step = 0 must be finite and > 0");
  EXPECT_EQ(message({true, kInf, 64}),
            "simulation options: guard.max_joint_step = inf must be finite and > 0");
  EXPECT_EQ(message({true, 0.25, 0}),
            "simulation options: guard.max_substeps = 0 must be in [2, 4096]");
  EXPECT_EQ(message({true, 0.25, 1000000}),
            "simulation options: guard.max_substeps = 1000000 must be in [2, 4096]");
  EXPECT_EQ(message({true, 0.25, 4096}), "");
  EXPECT_EQ(message({true, 0.25, 64, 0.0}),
            "simulation options: guard.energy_tolerance = 0 must be in (0, 1]");
  EXPECT_EQ(message({true, 0.25, 64, 1.5}),
            "simulation options: guard.energy_tolerance = 1.5 must be in (0, 1]");
  EXPECT_EQ(message({true, 0.25, 64, 0.02, 0.0}),
            "simulation options: guard.dissipation_share = 0 must be in (0, 100]");
  EXPECT_EQ(message({true, 0.25, 64, 0.02, 101.0}),
            "simulation options: guard.dissipation_share = 101 must be in (0, 100]");
  EXPECT_EQ(message({true, 0.25, 64, 0.02, 100.0}), "");
  const auto model = test::make_slider(1.0, Vec3(1, 0, 0), Vec3::Zero());
  Simulation sim(model);
  SimulationOptions o;
  o.guard = {true, std::nan(""), 8};
  EXPECT_THROW(sim.set_options(o), std::invalid_argument);
  EXPECT_FALSE(sim.options().guard.enabled);  // unchanged
}

}  // namespace
}  // namespace featherdrive
