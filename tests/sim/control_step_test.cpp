// Control steps: hold is "set the targets, then k steps" bit for bit; linear's sub-step targets
// are the closed form prev + j/k (new - prev), read back from the physics of a 1-dof slider; a
// batch gives what each copy gives alone; divergence and bad input as the brief says.
#include <gtest/gtest.h>

#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "featherdrive/sim/control_step.hpp"
#include "support/drives.hpp"
#include "support/models.hpp"
#include "support/compare.hpp"

namespace featherdrive {
namespace {

using test::kInf;

using test::same_bits;

bool same_state(const Simulation& a, const Simulation& b) {
  return same_bits(a.q(), b.q()) && same_bits(a.qd(), b.qd()) &&
         same_bits(a.drive_force(), b.drive_force()) && a.step_count() == b.step_count();
}

Simulation driven_tree(SolverType solver, unsigned seed) {
  const auto model = test::make_random_tree(seed, 6, /*floating=*/true);
  SimulationOptions options;
  options.solver = solver;
  options.dt = 0.005;
  Simulation sim(model, options);
  std::mt19937 rng(seed);
  sim.set_q(test::random_configuration(*model, rng));
  sim.set_qd(test::random_vector(model->nv, rng, 0.5));
  test::drive_every_joint(sim, rng, 300.0, 10.0);
  return sim;
}

/// Targets for the drivable dofs (0 elsewhere: those take no drive).
std::pair<VecX, VecX> random_targets(const Model& model, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  VecX p = VecX::Zero(model.nv), v = VecX::Zero(model.nv);
  for (const Link& l : model.links)
    if (l.joint_type == JointType::revolute || l.joint_type == JointType::prismatic)
      p[l.v_index] = u(rng), v[l.v_index] = u(rng);
  return {p, v};
}

TEST(ControlStep, HoldIsSetTargetsThenKStepsBitForBit) {
  for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    Simulation control = driven_tree(solver, 11), manual = control;
    std::mt19937 rng(5);
    for (int call = 0; call < 3; ++call) {
      const auto [p, v] = random_targets(control.model(), rng);
      const int k = 2 + call;
      step_control(control, p, v, ControlStep{k, TargetInterpolation::hold});
      set_drive_targets(manual, p, v);
      for (int j = 0; j < k; ++j) manual.step();
      ASSERT_TRUE(same_state(control, manual)) << to_string(solver) << " call " << call;
    }
    EXPECT_EQ(control.step_count(), 2 + 3 + 4);
  }
}

TEST(ControlStep, OneSubstepIsOneStepInBothModes) {
  for (TargetInterpolation mode : {TargetInterpolation::hold, TargetInterpolation::linear}) {
    Simulation control = driven_tree(SolverType::tgs, 3), manual = control;
    std::mt19937 rng(8);
    for (int call = 0; call < 4; ++call) {
      const auto [p, v] = random_targets(control.model(), rng);
      step_control(control, p, v, ControlStep{1, mode});
      set_drive_targets(manual, p, v);
      manual.step();
      ASSERT_TRUE(same_state(control, manual)) << to_string(mode) << " call " << call;
    }
  }
}

// The target a sub-step used, read back from its physics: a 1-dof slider of mass m without
// gravity, a force drive, PGS with one position and no velocity iteration. With x = 1/(a/m + 1),
// a = h (h kp + kd), the one impulse is x (h kp (x_T - x0) + h kd v_T) - x a v0
// (docs/math/implicit_drives.md, eq. 13-21), so stiffness alone reveals x_T and damping alone v_T.
TEST(ControlStep, LinearSubstepTargetsAreTheClosedForm) {
  const double m = 2.0, h = 0.01;
  const auto model = test::make_slider(m, Vec3::UnitX(), Vec3::Zero());
  SimulationOptions options;
  options.dt = h;
  options.position_iterations = 1;
  options.velocity_iterations = 0;
  for (const bool stiffness : {true, false}) {
    const double kp = stiffness ? 400.0 : 0.0, kd = stiffness ? 0.0 : 30.0;
    Simulation sim(model, options);
    sim.set_drive(0, Drive{DriveType::force, kp, kd, kInf, 0.2, -0.3});  // prev = (0.2, -0.3)
    const double a = h * (h * kp + kd), x = 1.0 / (a / m + 1.0);
    const int k = 5;
    const double next_p = 1.7, next_v = 0.9;
    double x0 = sim.q()[0], v0 = sim.qd()[0];
    double worst = 0.0;
    int calls = 0;
    step_control(sim, VecX::Constant(1, next_p), VecX::Constant(1, next_v),
                 ControlStep{k, TargetInterpolation::linear}, [&](const Simulation& s, int j) {
                   ++calls;
                   const double f = s.drive_force()[0];
                   // x_T = x0 + h v0 + f / (x kp); v_T = v0 + f / (x kd).
                   const double got = stiffness ? x0 + h * v0 + f / (x * kp) : v0 + f / (x * kd);
                   const double expected =
                       stiffness ? 0.2 + j / 5.0 * (next_p - 0.2) : -0.3 + j / 5.0 * (next_v + 0.3);
                   worst = std::max(worst, std::abs(got - expected));
                   EXPECT_NEAR(got, expected, 1e-12) << "sub-step " << j;
                   x0 = s.q()[0], v0 = s.qd()[0];
                 });
    EXPECT_EQ(calls, k);
    EXPECT_LT(worst, 1e-12);
    // The control step ends on the targets it was given, exactly.
    EXPECT_EQ(sim.drive(0).target_position, next_p);
    EXPECT_EQ(sim.drive(0).target_velocity, next_v);
    EXPECT_EQ(sim.step_count(), k);
  }
}

TEST(ControlStep, BatchEqualsEachCopyAloneForAnyThreadCount) {
  const auto model = test::make_random_tree(4, 5, /*floating=*/false, /*spherical=*/false);
  SimulationOptions options;
  options.dt = 0.004;
  const int n = 5, nv = model->nv;
  for (TargetInterpolation mode : {TargetInterpolation::hold, TargetInterpolation::linear}) {
    std::vector<Simulation> alone;
    RowMatrix p(n, nv), v(n, nv);
    std::mt19937 rng(21);
    for (int i = 0; i < n; ++i) {
      alone.emplace_back(model, options);
      test::drive_every_joint(alone.back(), rng, 150.0 + i, 4.0);
      const auto [pi, vi] = random_targets(*model, rng);
      p.row(i) = pi.transpose(), v.row(i) = vi.transpose();
    }
    const ControlStep control{3, mode};
    // Without lanes each copy is its Simulation bit for bit; in lanes within 1e-12 (another
    // operation order).
    for (bool lanes : {false, true})
      for (int threads : {1, 0}) {
        Batch batch(model, n, options);
        batch.set_num_threads(threads);
        batch.set_lanes(lanes);
        for (int i = 0; i < n; ++i) batch.sim(i) = alone[static_cast<size_t>(i)];
        EXPECT_EQ(batch.step_path().find("scalar"), lanes ? std::string::npos : 0u);
        step_control(batch, p, v, control);
        step_control(batch, 0.5 * p, -v, control);
        for (int i = 0; i < n; ++i) {
          Simulation s = alone[static_cast<size_t>(i)];
          step_control(s, p.row(i).transpose(), v.row(i).transpose(), control);
          step_control(s, 0.5 * p.row(i).transpose(), -v.row(i).transpose(), control);
          if (!lanes) EXPECT_TRUE(same_state(batch.sim(i), s)) << to_string(mode) << " copy " << i;
          EXPECT_LE(test::relative_difference(batch.sim(i).q(), s.q()), 1e-12) << i;
          EXPECT_LE(test::relative_difference(batch.sim(i).qd(), s.qd()), 1e-12) << i;
          EXPECT_LE(test::relative_difference(batch.sim(i).drive_force(), s.drive_force()), 1e-12);
          EXPECT_EQ(batch.sim(i).step_count(), s.step_count());
          EXPECT_EQ(batch.sim(i).time(), s.time());
        }
      }
  }
}

// An applied force of 1e307 N on a 1 kg slider with dt = 1 s runs away; the step where it
// diverges is found by stepping a plain simulation (it is 2: q = 1e307 overflows the kinematics).
TEST(ControlStep, DivergenceStopsAtTheSubstepAndNamesIt) {
  const auto model = test::make_slider(1.0, Vec3::UnitX(), Vec3::Zero());
  SimulationOptions options;
  options.dt = 1.0;
  Simulation sim(model, options), reference(model, options);
  for (Simulation* s : {&sim, &reference}) s->set_applied_force(VecX::Constant(1, 1e307));
  int made = 0;
  try {
    for (; made < 10; ++made) reference.step();
  } catch (const DivergenceError&) {
  }
  ASSERT_GE(made, 1);  // a sub-step before the one that diverges
  ASSERT_LT(made, 10);
  const std::string expected =
      "step_control: sub-step " + std::to_string(made + 1) + " of 10: ";
  try {
    step_control(sim, VecX::Zero(1), VecX::Zero(1), ControlStep{10, TargetInterpolation::linear});
    FAIL() << "no DivergenceError";
  } catch (const DivergenceError& e) {
    EXPECT_EQ(std::string(e.what()).find(expected), 0u) << e.what();
  }
  EXPECT_TRUE(same_state(sim, reference));

  // A batch: copies 1 and 3 diverge at that sub-step, the others make all 10.
  for (TargetInterpolation mode : {TargetInterpolation::hold, TargetInterpolation::linear}) {
    Batch batch(model, 4, options);
    for (int i : {1, 3}) batch.sim(i).set_applied_force(VecX::Constant(1, 1e307));
    try {
      // Zero targets: the slider has no drive (a nonzero target would be refused).
      step_control(batch, RowMatrix::Zero(4, 1), RowMatrix::Zero(4, 1), ControlStep{10, mode});
      FAIL() << "no DivergenceError";
    } catch (const DivergenceError& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.find(expected + "batch copy 1 "), 0u) << what;
      EXPECT_NE(what.find("2 of 4 copies diverged in the control step"), std::string::npos)
          << what;
    }
    Simulation calm(model, options);
    step_control(calm, VecX::Zero(1), VecX::Zero(1), ControlStep{10, mode});
    for (int i = 0; i < 4; ++i) {
      if (i == 1 || i == 3)
        EXPECT_TRUE(same_bits(batch.sim(i).q(), reference.q())) << i;
      else
        EXPECT_TRUE(same_state(batch.sim(i), calm)) << i;
    }
  }
}

TEST(ControlStep, BadInputChangesNothing) {
  Simulation sim = driven_tree(SolverType::pgs, 2);
  const Simulation before = sim;
  const int nv = sim.model().nv;
  const VecX zero = VecX::Zero(nv);
  auto refused = [&](const VecX& p, const VecX& v, const ControlStep& c, const std::string& msg) {
    try {
      step_control(sim, p, v, c);
      ADD_FAILURE() << "accepted: " << msg;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(msg), std::string::npos) << e.what();
    }
    EXPECT_TRUE(same_state(sim, before));
    for (int d = 0; d < nv; ++d)
      EXPECT_EQ(sim.drive(d).target_position, before.drive(d).target_position);
  };
  refused(zero, zero, ControlStep{0, TargetInterpolation::hold},
          "control step: substeps = 0 must be in [1, 1000000]");
  refused(zero, zero, ControlStep{kMaxSubsteps + 1, TargetInterpolation::hold},
          "substeps = 1000001");
  refused(zero, zero, ControlStep{2, static_cast<TargetInterpolation>(7)},
          "control step: targets = 7 must be hold or linear");
  refused(VecX::Zero(nv - 1), zero, ControlStep{}, "target_position has " +
          std::to_string(nv - 1) + " values, expected nv = " + std::to_string(nv));
  refused(zero, VecX::Zero(nv + 1), ControlStep{}, "target_velocity has");
  VecX bad = zero;
  bad[nv - 1] = std::numeric_limits<double>::quiet_NaN();
  refused(zero, bad, ControlStep{}, "target_velocity of dof " + std::to_string(nv - 1) +
          " (joint '");
  // linear: new - prev must be finite; hold does not interpolate, so it takes the same targets.
  const int d = nv - 1;
  Drive drive = sim.drive(d);
  drive.stiffness = drive.damping = 0.0;  // so that the hold run below applies no force
  drive.target_position = -1e308;
  sim.set_drive(d, drive);
  const Simulation far = sim;
  VecX high = zero;
  high[d] = 1e308;
  try {
    step_control(sim, high, zero, ControlStep{2, TargetInterpolation::linear});
    ADD_FAILURE() << "accepted an overflowing difference";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("minus the previous target -1e+308 overflows"),
              std::string::npos)
        << e.what();
  }
  EXPECT_TRUE(same_state(sim, far));
  EXPECT_NO_THROW(step_control(sim, high, zero, ControlStep{2, TargetInterpolation::hold}));

  Batch batch(sim.model_ptr(), 2);
  EXPECT_THROW(step_control(batch, RowMatrix::Zero(2, nv - 1), RowMatrix::Zero(2, nv),
                            ControlStep{}),
               std::invalid_argument);
  RowMatrix inf = RowMatrix::Zero(2, nv);
  inf(1, 0) = kInf;
  try {
    step_control(batch, inf, RowMatrix::Zero(2, nv), ControlStep{});
    ADD_FAILURE() << "accepted inf";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("step_control: copy 1: target_position of dof 0"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(batch.sim(0).step_count(), 0);
  EXPECT_EQ(batch.sim(1).step_count(), 0);
}

}  // namespace
}  // namespace featherdrive
