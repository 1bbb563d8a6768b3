// Gain translation (docs/mujoco_bridge.md, eq. B1-B12): featherdrive's per-step map of a lone
// drive against Simulation itself on 1-dof models, and the translation's algebra. MuJoCo itself
// runs the translated drives in tests/peers/mujoco_bridge_test.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "featherdrive/sim/gain_translation.hpp"
#include "support/compare.hpp"
#include "support/models.hpp"

namespace featherdrive {
namespace {

using test::kInf;

SimulationOptions gain_options(SolverType type, int position, int velocity, double dt) {
  SimulationOptions o;
  o.solver = type;
  o.position_iterations = position;
  o.velocity_iterations = velocity;
  o.dt = dt;
  return o;
}

// One step of Simulation from random states and targets against A [q; qd] + B [x_T; v_T; f],
// f the gravity torque or force at the step's start, m = 1 / (M^-1)_00 (effective_inertia).
TEST(GainTranslation, StepMapIsSimulationsStepOnOneDof) {
  const auto slider = test::make_slider(1.7, Vec3(0.6, 0, 0.8), Vec3(0, 0, -9.81));
  const auto pendulum = test::make_pendulum(1.3, 0.7, 0.02);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  double worst = 0.0;
  int cases = 0;
  for (const auto& model : {slider, pendulum}) {
    for (DriveType type : {DriveType::force, DriveType::acceleration}) {
      for (const SimulationOptions& o : {gain_options(SolverType::pgs, 4, 1, 1.0 / 60),
                                         gain_options(SolverType::pgs, 1, 0, 1.0 / 240),
                                         gain_options(SolverType::tgs, 4, 1, 1.0 / 60),
                                         gain_options(SolverType::tgs, 3, 2, 1.0 / 120)}) {
        for (double stiffness : {10.0, 1e3, 1e6}) {
          Simulation sim(model, o);
          const double damping = std::abs(u(rng)) * 2.0 * std::sqrt(stiffness);
          const Drive drive{type, stiffness, damping, kInf, u(rng), 3.0 * u(rng)};
          sim.set_drive(0, drive);
          VecX q(1), qd(1);
          q << u(rng);
          qd << 2.0 * u(rng);
          sim.set_q(q);
          sim.set_qd(qd);
          const double m = effective_inertia(*model, q)[0];
          // The generalised gravity force at q: the pendulum's -m g l sin q, the slider's m g.a.
          const double f = model == slider ? 1.7 * Vec3(0.6, 0, 0.8).dot(Vec3(0, 0, -9.81))
                                           : -1.3 * 9.81 * 0.7 * std::sin(q[0]);
          const DriveStepMap map = physx_step_map(m, drive, o);
          const Eigen::Vector2d predicted =
              map.A * Eigen::Vector2d(q[0], qd[0]) +
              map.B * Eigen::Vector3d(drive.target_position, drive.target_velocity, f);
          sim.step();
          const double err = std::max(std::abs(sim.q()[0] - predicted[0]),
                                      std::abs(sim.qd()[0] - predicted[1]) * o.dt);
          worst = std::max(worst, err);
          EXPECT_LE(err, 1e-13 * (1.0 + std::abs(predicted[0]) + std::abs(predicted[1])))
              << to_string(type) << " " << to_string(o.solver) << o.position_iterations << " kp "
              << stiffness;
          ++cases;
        }
      }
    }
  }
  std::printf("[ map      ] %d one-step cases: largest |Simulation - map| %.3g\n", cases, worst);
}

TEST(GainTranslation, SubsteppedMujocoWithDampingIsThePhysxStep) {
  // Eq. B7-B8: joint damping kd + h kp at MuJoCo timestep h = dt / n is PhysX's implicit step.
  const double m = 0.8, dt = 1.0 / 60;
  for (int n : {1, 4}) {
    const SimulationOptions o = gain_options(n == 1 ? SolverType::pgs : SolverType::tgs, n, 1, dt);
    for (double s : {1e-3, 1.0, 100.0}) {
      const double kp = s * m / (dt * dt), kd = 0.7 * 2.0 * std::sqrt(kp * m);
      const Drive drive{DriveType::force, kp, kd, kInf, 0.0, 0.0};
      const MujocoTranslation t = translate_to_mujoco(m, drive, o);
      EXPECT_TRUE(t.exact) << t.note;
      EXPECT_EQ(t.mujoco.substeps, n);
      EXPECT_NEAR(t.mujoco.damping, kd + dt / n * kp, 1e-12 * kp);
      const DriveStepMap a = physx_step_map(m, drive, o), b = mujoco_step_map(m, t.mujoco, dt);
      EXPECT_LE((a.A - b.A).cwiseAbs().maxCoeff(), 1e-12);
      // The force input: once per step in PhysX, per sub-step in MuJoCo (equal for n = 1).
      EXPECT_LE((a.B.leftCols<2>() - b.B.leftCols<2>()).cwiseAbs().maxCoeff(), 1e-12);
    }
  }
}

TEST(GainTranslation, LiteralCopyIsUnstablePastEulersLimit) {
  // Semi-implicit Euler with explicit kp and kv: stable for dt^2 kp / m < 4 - 2 dt kv / m.
  const double m = 2.0, dt = 0.01, kd = 10.0;
  const double limit = 4.0 - 2.0 * dt * kd / m;
  for (double s : {0.9 * limit, 1.1 * limit}) {
    const Drive drive{DriveType::force, s * m / (dt * dt), kd, kInf, 0.0, 0.0};
    EXPECT_EQ(
        stable(mujoco_step_map(m, literal_mujoco_drive(m, drive, MujocoIntegrator::euler), dt)),
        s < limit);
  }
}

TEST(GainTranslation, KeepingTheTimestepForTgsIsNotReproducible) {
  // TGS 4 sub-steps is less damped than MuJoCo Euler can be at timestep dt without negative
  // armature: the translation says so and reports the closest setting's distance.
  const double m = 1.0, dt = 1.0 / 60, kp = 0.5 / (dt * dt), kd = 2.0 * 0.5 * std::sqrt(kp);
  TranslationOptions keep;
  keep.keep_timestep = true;
  const MujocoTranslation t = translate_to_mujoco(m, Drive{DriveType::force, kp, kd, kInf, 0, 0},
                                                  gain_options(SolverType::tgs, 4, 1, dt), keep);
  EXPECT_FALSE(t.reproducible);
  EXPECT_NE(t.note.find("not reproducible"), std::string::npos) << t.note;
  EXPECT_GE(t.mujoco.armature, 0.0);
  EXPECT_GT(t.distance.step_response, 0.01);
}

TEST(GainTranslation, MujocoToPhysxRoundTripsAndRefusesUnderdampedSteps) {
  const double m = 1.3, dt = 1.0 / 60;
  for (int n : {1, 4}) {
    const SimulationOptions o = gain_options(n == 1 ? SolverType::pgs : SolverType::tgs, n, 1, dt);
    const Drive drive{DriveType::force, 2e3, 30.0, kInf, 0.0, 0.0};
    const MujocoTranslation there =
        translate_to_mujoco(m, drive, gain_options(SolverType::pgs, 1, 0, dt));
    const PhysxTranslation back = translate_to_physx(m, there.mujoco, o);
    ASSERT_TRUE(back.reproducible) << back.note;
    EXPECT_LE(back.distance.poles, 1e-9);
    // TGS's step has other zeros than one implicit step (its position moves within the step):
    // the poles match, the step response not exactly, and the note says by how much.
    if (n == 1)
      EXPECT_LE(back.distance.step_response, 1e-9);
    else
      EXPECT_NE(back.note.find("step response differs"), std::string::npos) << back.note;
    if (n == 1) {
      EXPECT_NEAR(back.drive.stiffness, drive.stiffness, 1e-9 * drive.stiffness);
      EXPECT_NEAR(back.drive.damping, drive.damping, 1e-9 * drive.stiffness);
    }
  }
  // MuJoCo's explicit stiffness with damping below dt kp rings longer than any implicit drive.
  MujocoDrive ringing;
  ringing.kp = 2.0 * m / (dt * dt);
  ringing.damping = 0.1 * dt * ringing.kp;
  const PhysxTranslation refused =
      translate_to_physx(m, ringing, gain_options(SolverType::pgs, 4, 1, dt));
  EXPECT_FALSE(refused.reproducible);
  EXPECT_NE(refused.note.find("not reproducible"), std::string::npos);
  EXPECT_GT(refused.distance.step_response, 0.0);
}

TEST(GainTranslation, BadInputIsRefused) {
  const SimulationOptions o;
  EXPECT_THROW(physx_step_map(0.0, Drive{}, o), std::invalid_argument);
  EXPECT_THROW(translate_to_mujoco(1.0, Drive{}, o), std::invalid_argument);
  MujocoDrive sub;
  sub.substeps = 2;
  EXPECT_THROW(translate_to_physx(1.0, sub, o), std::invalid_argument);
}

// Every number that enters the translation is checked where it enters: one line naming the
// argument (or field) and the value, never a NaN, an identity map or inf in the result.
TEST(GainTranslation, NonFiniteNegativeAndOverflowingNumbersAreRefused) {
  auto message = [](auto f) {
    try {
      f();
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const SimulationOptions o;
  const double nan = std::nan("");
  MujocoDrive mj;
  mj.kp = nan;
  EXPECT_EQ(message([&] { translate_to_physx(1.0, mj, o); }),
            "MuJoCo setting: kp = nan: must be finite and >= 0");
  mj.kp = 100.0;
  mj.substeps = -5;
  EXPECT_EQ(message([&] { mujoco_step_map(1.0, mj, 0.01); }),
            "MuJoCo setting: substeps = -5: must be in [1, 1000000]");
  mj.substeps = 1;
  EXPECT_EQ(message([&] { mujoco_step_map(1.0, mj, 0.0); }).substr(0, 34),
            "dt = 0: must be a normal number in");
  mj.armature = -1.0;
  EXPECT_EQ(message([&] { mujoco_step_map(1.0, mj, 0.01); }),
            "MuJoCo setting: armature = -1: must be finite and >= 0");
  mj.armature = 0.0;
  // Gains that fit a double but whose translation (damping kd + dt kp = 2e308) overflows are
  // refused, not written as inf.
  SimulationOptions one_second;
  one_second.dt = 1.0;
  const std::string big = message(
      [&] { translate_to_mujoco(1.0, Drive{DriveType::force, 1e308, 1e308}, one_second); });
  EXPECT_EQ(big.find("the translated damping = inf"), 0u) << big;
  const auto pendulum = test::make_pendulum(1.3, 0.7, 0.02);
  EXPECT_EQ(message([&] { effective_inertia(*pendulum, VecX::Constant(1, nan)); }),
            "effective_inertia: q[0] = nan: must be finite");
  Drive d{DriveType::force, nan, 1.0};
  EXPECT_EQ(message([&] { translate_to_mujoco(1.0, d, o); }),
            "drive on joint '(translated)': stiffness = nan must be finite and >= 0");
}

}  // namespace
}  // namespace featherdrive
