// Long runs, in the main build's optimised binary (about 1 s there; minutes under the sanitizer
// build's ASan, UBSan and fuzzing coverage): passive motion over 100 000 steps (a pendulum's
// period, a chain's energy drift), the stability check's verdict (docs/stability_check.md,
// "Accuracy") against actual runs of random robots, gains, steps and solvers, its robot fix
// against a long run, the step guard on issue 35's diverging chain, and a box resting on the
// ground for 10 000 converged steps.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "featherdrive/algorithm/energy.hpp"
#include "featherdrive/algorithm/kinematics.hpp"
#include "featherdrive/model/model_builder.hpp"
#include "featherdrive/sim/stability_check.hpp"
#include "featherdrive/algorithm/floating_base.hpp"
#include "support/contact_models.hpp"
#include "support/drives.hpp"
#include "support/models.hpp"

namespace featherdrive {
namespace {

// The benchmark chain's shape (bench/bench_models.cpp, make_chain): n links of 1 kg, 0.5 m,
// revolute axes cycling y, z, x.
std::shared_ptr<const Model> make_axis_chain(int n, double gravity) {
  const Vec3 axes[3] = {Vec3::UnitY(), Vec3::UnitZ(), Vec3::UnitX()};
  ModelBuilder b;
  b.set_gravity(Vec3(0, 0, -gravity));
  b.add_link(make_link("base", "", 1.0, Vec3::Zero(), test::box_inertia(1.0, Vec3(0.1, 0.1, 0.1)),
                       fixed_joint("world_joint")));
  std::string parent = "base";
  for (int i = 0; i < n; ++i) {
    const std::string name = "link" + std::to_string(i + 1);
    b.add_link(make_link(name, parent, 1.0, Vec3(0, 0, -0.25),
                         test::box_inertia(1.0, Vec3(0.1, 0.1, 0.5)),
                         revolute_joint("joint" + std::to_string(i + 1), axes[i % 3],
                                        i == 0 ? Vec3::Zero() : Vec3(0, 0, -0.5))));
    parent = name;
  }
  return std::make_shared<const Model>(b.build());
}

struct Trial {
  std::string what;
  Simulation sim;
};

// Configuration i: a random tree (3-6 links, every joint type) or the chain (2-16 links), dt
// log-uniform in [1e-3, 1/30], PGS or TGS with 1-8 position iterations, implicit drives or
// explicit ideal PD on every revolute and prismatic dof with kp dt^2/m log-uniform over [0.03, 3e4]
// (explicit: [0.03, 30]) and damping ratios in [0, 2] (explicit: h kd / m in [0, 1.5]).
Trial make_trial(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  auto log_uniform = [&](double lo, double hi) {
    return std::exp(std::log(lo) + u(rng) * (std::log(hi) - std::log(lo)));
  };
  const bool chain = u(rng) < 0.5;
  const int links = chain ? 2 + static_cast<int>(u(rng) * 15) : 3 + static_cast<int>(u(rng) * 4);
  std::shared_ptr<const Model> model =
      chain ? make_axis_chain(links, u(rng) < 0.5 ? 0.0 : 9.81)
            : test::make_random_tree(seed, links, false, true, 0.01);
  SimulationOptions o;
  o.dt = log_uniform(1e-3, 1.0 / 30.0);
  o.solver = u(rng) < 0.5 ? SolverType::pgs : SolverType::tgs;
  o.position_iterations = 1 + static_cast<int>(u(rng) * 8);
  o.velocity_iterations = 1;
  Simulation sim(model, o);
  VecX q = model->neutral_configuration();
  for (const Link& l : model->links)
    if (l.joint_type == JointType::revolute || l.joint_type == JointType::prismatic)
      q[l.q_index] = 0.5 * (2.0 * u(rng) - 1.0);
  sim.set_q(q);
  const VecX m = effective_inertia(*model, sim.q());
  const bool explicit_law = u(rng) < 0.5;
  const double ratio = explicit_law ? log_uniform(0.03, 30.0) : log_uniform(0.03, 3e4);
  const double damping = explicit_law ? 1.5 * u(rng) : 2.0 * u(rng);
  for (const Link& l : model->links) {
    if (l.joint_type != JointType::revolute && l.joint_type != JointType::prismatic) continue;
    const int d = l.v_index;
    const double kp = ratio * (0.7 + 0.6 * u(rng)) * m[d] / (o.dt * o.dt);
    const double target = 0.5 * (2.0 * u(rng) - 1.0);
    if (explicit_law) {
      ExplicitActuator a;
      a.kind = ActuatorKind::ideal_pd;
      a.stiffness = kp;
      a.damping = damping * m[d] / o.dt;
      sim.set_actuator(d, a);
      sim.set_drive_target(d, target, 0.0);
    } else {
      sim.set_drive(d, Drive{DriveType::force, kp, 2.0 * damping * std::sqrt(kp * m[d]),
                             std::numeric_limits<double>::infinity(), target, 0.0});
    }
  }
  char what[160];
  std::snprintf(what, sizeof what, "seed %u: %s %d, dt %.4g, %s %d/1, %s kp dt^2/m %.3g, %s %.2f",
                seed, chain ? "chain" : "tree", links, o.dt, to_string(o.solver),
                o.position_iterations, explicit_law ? "explicit" : "implicit", ratio,
                explicit_law ? "h kd/m" : "zeta", damping);
  return {what, sim};
}

// The truth: `steps` steps of the run itself; diverged on DivergenceError or the energy test of
// eq. S5-S6 (the same bound as the trial's, over a horizon five times longer and more).
bool run_diverges(Simulation sim, int steps) {
  const double e0 = check_energy(sim), scale = check_energy_scale(sim);
  for (int k = 0; k < steps; ++k) {
    try {
      sim.step();
    } catch (const DivergenceError&) {
      return true;
    }
    // Every 10 steps: a diverging run grows by orders of magnitude within them.
    if (k % 10 == 9 && !((check_energy(sim) - e0) / scale <= 1000.0)) return true;
  }
  return false;
}

struct Tally {
  int right = 0, missed = 0, false_alarm = 0;
  void add(bool says_stable, bool diverged) {
    if (says_stable == !diverged)
      ++right;
    else if (says_stable)
      ++missed;
    else
      ++false_alarm;
  }
};

// The parts of the estimate: the one-joint maps (eq. S1-S3), the linearised step (S4), the trial
// run (S5-S6); the verdict is maps + trial.
struct Tallies {
  Tally joints, joints_linear, joints_trial, all, verdict;
  int configurations = 0, diverged = 0;
};

Tallies tally(int count, int horizon) {
  StabilityCheckOptions options;
  options.find_fixes = false;
  Tallies t;
  for (int i = 0; i < count; ++i) {
    const Trial trial = make_trial(1000u + static_cast<unsigned>(i));
    const StabilityReport report = check_stability(trial.sim, options);
    const bool truth = run_diverges(trial.sim, horizon);
    const bool joints = std::all_of(report.joints.begin(), report.joints.end(),
                                    [](const JointStability& j) { return j.stable; });
    ++t.configurations;
    t.diverged += truth;
    t.joints.add(joints, truth);
    t.joints_linear.add(joints && report.robot.linear_stable, truth);
    t.joints_trial.add(joints && report.robot.trial_bounded, truth);
    t.all.add(joints && report.robot.linear_stable && report.robot.trial_bounded, truth);
    t.verdict.add(report.stable, truth);
    EXPECT_EQ(report.stable, joints && report.robot.trial_bounded);
    if (report.stable == truth)
      std::printf("  wrong: %s: check %s, run %s\n", trial.what.c_str(), report.verdict.c_str(),
                  truth ? "diverged" : "bounded");
  }
  return t;
}

TEST(StabilityCheck, RobotFixKeepsALongRunBounded) {
  // A 6-link chain with explicit PD laws whose dofs are each stable (kp dt^2/m 0.39) but whose
  // coupled run diverges: the sub-steps check proposes must keep 5000 steps' worth of time bounded.
  const Trial trial = make_trial(1026u);
  const StabilityReport r = check_stability(trial.sim);
  for (const JointStability& j : r.joints) EXPECT_TRUE(j.stable) << j.joint;
  EXPECT_FALSE(r.robot.trial_bounded);
  ASSERT_GT(r.robot.substeps, 1) << trial.what;
  EXPECT_TRUE(run_diverges(trial.sim, 5000));
  Simulation fixed = trial.sim;
  SimulationOptions o = fixed.options();
  o.dt /= r.robot.substeps;
  fixed.set_options(o);
  EXPECT_FALSE(run_diverges(fixed, 5000 * r.robot.substeps)) << trial.what;
}

// The table of docs/stability_check.md, "Accuracy" (measured: 95 right, 5 "stable" runs that
// diverged, none "unstable" that stayed bounded).
TEST(StabilityCheck, VerdictAgainstActualRuns) {
  const Tallies t = tally(100, 5000);
  std::printf("  %d configurations, %d diverged within 5000 steps\n", t.configurations,
              t.diverged);
  std::printf("  | estimate | right | says stable, diverged | says unstable, bounded |\n");
  const std::pair<const char*, const Tally*> rows[] = {{"one-joint maps", &t.joints},
                                                       {"maps + linearised step", &t.joints_linear},
                                                       {"maps + trial run", &t.joints_trial},
                                                       {"all three", &t.all},
                                                       {"verdict (maps + trial run)", &t.verdict}};
  for (const auto& [name, r] : rows)
    std::printf("  | %s | %d | %d | %d |\n", name, r->right, r->missed, r->false_alarm);
  EXPECT_GE(t.diverged, 30);  // the sample spans both outcomes
  EXPECT_GE(t.configurations - t.diverged, 30);
  EXPECT_GE(t.verdict.right, 91);
  EXPECT_LE(t.verdict.missed, 5);
}

// The step guard (docs/math/step_guard.md), a long run: the chain diverges unguarded within the horizon and stays bounded guarded (the guard's
// defaults): PGS 4/1 at 48 links, TGS 4/1 at 64 (benchmarks.md: unguarded they diverge at steps
// 466 and 333, guarded they stay bounded for 10 000).
TEST(StepGuard, KeepsTheDivergingChainBounded) {
  const int steps = 1000;
  for (const auto& [solver, links] :
       {std::pair{SolverType::pgs, 48}, std::pair{SolverType::tgs, 64}}) {
    const auto model = test::make_benchmark_chain(links, Vec3::Zero());
    SimulationOptions off;
    off.solver = solver;
    SimulationOptions on = off;
    on.guard.enabled = true;
    Simulation unguarded(model, off);
    Simulation guarded(model, on);
    test::drive_benchmark_chain(unguarded);
    test::drive_benchmark_chain(guarded);
    bool diverged = false;
    for (int k = 0; k < steps && !diverged; ++k) {
      try {
        unguarded.step();
      } catch (const DivergenceError&) {
        diverged = true;
      }
      diverged = diverged || !(unguarded.qd().norm() < 1e3);
    }
    EXPECT_TRUE(diverged) << to_string(solver);
    for (int k = 0; k < steps; ++k)
      ASSERT_NO_THROW(guarded.step()) << to_string(solver) << " " << k;
    EXPECT_GT(guarded.guard_triggers(), 0) << to_string(solver);
    EXPECT_LT(guarded.qd().norm(), 10.0) << to_string(solver);
    EXPECT_TRUE(guarded.q().allFinite());
  }
}

// Test (iii), the guard's account (eq. G-7..G-11): with it the chain settles on its targets (the
// drives' equilibrium, q = target, since gravity is off); with tests (i) and (ii) alone
// (dissipation_share 100 leaves (iii) no say) the steps they pass still feed energy in, and the
// chain keeps thrashing around them or diverges. 48 links, 3000 steps, PGS and TGS 4/1.
TEST(StepGuard, TheAccountMakesTheChainSettleOnItsTargets) {
  const int links = 48, steps = 3000;
  const auto model = test::make_benchmark_chain(links, Vec3::Zero());
  for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    // The largest RMS of q - target over the last 1000 steps (infinite once diverged).
    auto worst_late_error = [&](double share) {
      SimulationOptions o;
      o.solver = solver;
      o.guard.enabled = true;
      o.guard.dissipation_share = share;
      Simulation sim(model, o);
      const VecX target = test::drive_benchmark_chain(sim);
      double worst = 0.0;
      for (int k = 0; k < steps; ++k) {
        try {
          sim.step();
        } catch (const DivergenceError&) {
          return std::numeric_limits<double>::infinity();
        }
        const double rms = std::sqrt((sim.q() - target).squaredNorm() / links);
        if (!(rms < 10.0)) return std::numeric_limits<double>::infinity();
        if (k >= steps - 1000) worst = std::max(worst, rms);
      }
      return worst;
    };
    const double with_account = worst_late_error(StepGuard{}.dissipation_share);
    const double without = worst_late_error(100.0);
    EXPECT_LT(with_account, 0.08) << to_string(solver);
    EXPECT_GT(without, 0.2) << to_string(solver);
    std::printf("  %s: worst RMS of the last 1000 steps %.4f with the account, %.4f without\n",
                to_string(solver), with_account, without);
  }
}

// Period from the times of successive upward zero crossings, linearly interpolated.
double measured_period(Simulation& sim, int steps) {
  std::vector<double> crossings;
  double prev = sim.q()[0];
  for (int k = 0; k < steps; ++k) {
    sim.step();
    const double now = sim.q()[0];
    if (prev < 0.0 && now >= 0.0)
      crossings.push_back(sim.time() - sim.options().dt * now / (now - prev));
    prev = now;
  }
  return (crossings.back() - crossings.front()) / static_cast<double>(crossings.size() - 1);
}

// A 1 kg box resting on the ground, 50 (PGS) or 100 (TGS) position iterations that converge its
// four corners' rows: its velocity does not change, so over each step the normal impulses carry
// exactly its weight (linear momentum), and over 10 000 steps it neither sinks nor rises
// (docs/math/contact.md, section 13).
TEST(Contact, RestingBoxCarriesItsWeightWithoutDrift) {
  const double m = 1.0, half = 0.1, dt = 0.01, g = 9.81;
  for (const SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    SimulationOptions o;
    o.dt = dt;
    o.solver = solver;
    o.position_iterations = solver == SolverType::pgs ? 50 : 100;
    Simulation sim(test::make_ground_box(0.5), o);
    VecX q = sim.q(), qd = sim.qd();
    BaseState base;
    base.position = Vec3(0, 0, half);
    set_base_state(sim.model(), base, q, qd);
    sim.set_q(q);
    sim.set_qd(qd);
    Ground ground;
    ground.enabled = true;
    sim.set_ground(ground);
    sim.step(10);
    ASSERT_EQ(sim.contacts().size(), 4u);
    const double z0 = base_state(sim.model(), sim.q(), sim.qd()).position.z();
    double worst = 0.0;
    for (int k = 0; k < 10000; ++k) {
      sim.step();
      double sum = 0.0;
      for (const ContactReport& c : sim.contacts()) sum += c.normal_impulse;
      worst = std::max(worst, std::abs(sum / (dt * m * g) - 1.0));
    }
    const double z1 = base_state(sim.model(), sim.q(), sim.qd()).position.z();
    EXPECT_LT(worst, 1e-9) << to_string(solver);
    EXPECT_LT(std::abs(z1 - z0), 1e-9) << to_string(solver);
    EXPECT_LT(std::abs(z1 - half), 1e-9) << to_string(solver);
  }
}

TEST(Passive, SmallAnglePendulumPeriod) {
  const double m = 1.2, l = 0.8, Ic = 2e-3, g = 9.81;
  auto model = test::make_pendulum(m, l, Ic);
  SimulationOptions o;
  o.dt = 1e-4;
  Simulation sim(model, o);
  VecX q(1);
  q << 1e-3;  // small angle
  sim.set_q(q);
  const double I = Ic + m * l * l;  // about the pivot
  const double expected = 2 * M_PI * std::sqrt(I / (m * g * l));
  const double period = measured_period(sim, static_cast<int>(10 * expected / o.dt));
  EXPECT_NEAR(period / expected, 1.0, 1e-3);
}

TEST(Passive, ThreeLinkChainEnergyDriftIsBounded) {
  auto model = test::make_planar_chain(3, 1.0, 0.5);
  SimulationOptions o;
  o.dt = 1e-4;
  Simulation sim(model, o);
  VecX q(3);
  q << 0.8, -0.5, 0.3;
  sim.set_q(q);
  Data data(*model);
  auto energy = [&]() {
    forward_kinematics(*model, data, sim.q(), sim.qd());
    return kinetic_energy(*model, data, sim.qd()) + potential_energy(*model, data);
  };
  const double e0 = energy();
  double worst = 0.0;
  for (int k = 0; k < 100000; ++k) {  // 10 s
    sim.step();
    if (k % 100 == 0) worst = std::max(worst, std::abs(energy() - e0));
  }
  // Semi-implicit Euler is symplectic: the energy error oscillates with amplitude O(dt) and
  // does not grow. The scale is m g l ~ 5 J.
  EXPECT_LT(worst, 5e-3);
}

}  // namespace
}  // namespace featherdrive
