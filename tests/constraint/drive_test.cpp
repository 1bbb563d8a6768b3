// The drive row against the spec's own closed forms: eq. (12) for the PGS force drive, eq. (29)
// for the acceleration drive, eq. (44) for the TGS sub-step, written here in the spec's variables
// rather than the coefficients the code uses.
#include <gtest/gtest.h>

#include <random>

#include "featherdrive/constraint/drive.hpp"

namespace featherdrive {
namespace {

struct Sample {
  double kp, kd, xT, vT, x0, v, lambda, r, tau;
};

Sample random_sample(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_real_distribution<double> lg(-2.0, 6.0);
  return {std::pow(10.0, lg(rng)), std::pow(10.0, lg(rng) - 2), u(rng), u(rng), u(rng),
          3 * u(rng), 5 * u(rng), std::pow(10.0, u(rng)), 1.0 / (30 + 200 * (u(rng) + 1))};
}

TEST(DriveRow, PgsForceDriveIsEquation12) {
  std::mt19937 rng(1);
  for (int k = 0; k < 1000; ++k) {
    const Sample s = random_sample(rng);
    Drive d{DriveType::force, s.kp, s.kd, std::numeric_limits<double>::infinity(), s.xT, s.vT};
    const DriveRow row = setup_drive_row(d, s.r, s.x0, s.tau, s.tau, false);
    const double delta = (s.tau * s.kd * s.vT + s.tau * s.kp * (s.xT - s.x0) -
                          s.tau * (s.tau * s.kp + s.kd) * s.v - s.lambda) /
                         (s.tau * (s.tau * s.kp + s.kd) * s.r + 1.0);  // eq. (12)
    const double expected = s.lambda + delta;                            // eq. (6)
    EXPECT_NEAR(drive_impulse(row, s.v, s.lambda, 0.0, 0.0), expected, 1e-12 * (1 + std::abs(expected)));
  }
}

TEST(DriveRow, PgsAccelerationDriveIsEquation29) {
  std::mt19937 rng(2);
  for (int k = 0; k < 1000; ++k) {
    const Sample s = random_sample(rng);
    Drive d{DriveType::acceleration, s.kp, s.kd, std::numeric_limits<double>::infinity(), s.xT, s.vT};
    const DriveRow row = setup_drive_row(d, s.r, s.x0, s.tau, s.tau, false);
    // eq. (29) with ERRATA 1: every k and a, b the acceleration drive's.
    const double delta = (1.0 / s.r * (s.tau * s.kd * s.vT + s.tau * s.kp * (s.xT - s.x0) -
                                       s.tau * (s.tau * s.kp + s.kd) * s.v) -
                          s.lambda) /
                         (s.tau * (s.tau * s.kp + s.kd) + 1.0);
    const double expected = s.lambda + delta;
    EXPECT_NEAR(drive_impulse(row, s.v, s.lambda, 0.0, 0.0), expected, 1e-12 * (1 + std::abs(expected)));
  }
}

TEST(DriveRow, PgsUpdateIsAFixedPointForOneDof) {
  // With the exact unit response, the velocity after the update makes the next update zero.
  std::mt19937 rng(3);
  for (int k = 0; k < 200; ++k) {
    const Sample s = random_sample(rng);
    for (DriveType type : {DriveType::force, DriveType::acceleration}) {
      Drive d{type, s.kp, s.kd, std::numeric_limits<double>::infinity(), s.xT, s.vT};
      const DriveRow row = setup_drive_row(d, s.r, s.x0, s.tau, s.tau, false);
      const double l1 = drive_impulse(row, s.v, s.lambda, 0.0, 0.0);
      const double v1 = s.v + s.r * (l1 - s.lambda);
      const double l2 = drive_impulse(row, v1, l1, 0.0, 0.0);
      EXPECT_NEAR(l2, l1, 1e-12 * (1 + std::abs(l1)));
    }
  }
}

TEST(DriveRow, TgsSubstepIsEquation44) {
  std::mt19937 rng(4);
  for (int k = 0; k < 1000; ++k) {
    const Sample s = random_sample(rng);
    const int n = 1 + k % 8, i = 1 + k % n;
    const double rho = s.tau / n, dx = 0.01 * (k % 7 - 3);
    Drive d{DriveType::force, s.kp, s.kd, std::numeric_limits<double>::infinity(), s.xT, s.vT};
    const DriveRow row = setup_drive_row(d, s.r, s.x0, rho, s.tau, true);
    const double a = rho * (rho * s.kp + s.kd), b = rho * s.kd * s.vT, x = 1.0 / (a * s.r + 1.0);
    const double expected =
        x * (b + rho * s.kp * (s.xT - (s.tau - i * rho) * s.vT - s.x0) - rho * s.kp * dx - a * s.v) +
        s.lambda;  // eq. (44) with ERRATA 3-5
    EXPECT_NEAR(drive_impulse(row, s.v, s.lambda, dx, s.tau - i * rho), expected,
                1e-12 * (1 + std::abs(expected)));
  }
}

TEST(DriveRow, ImpulseIsClampedToMaxForceTimesDt) {
  Drive d{DriveType::force, 1e6, 10, 50.0, 1.0, 0.0};
  const DriveRow row = setup_drive_row(d, 1.0, 0.0, 0.01, 0.01, false);
  EXPECT_DOUBLE_EQ(drive_impulse(row, 0.0, 0.0, 0.0, 0.0), 0.5);
  d.target_position = -1.0;
  EXPECT_DOUBLE_EQ(drive_impulse(setup_drive_row(d, 1.0, 0.0, 0.01, 0.01, false), 0.0, 0.0, 0.0, 0.0), -0.5);
}

TEST(DriveRow, RejectsBadSettings) {
  auto message = [](Drive d) {
    try {
      validate_drive(d, "elbow");
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(message({DriveType::force, -1, 0, inf, 0, 0}),
            "drive on joint 'elbow': stiffness = -1 must be finite and >= 0");
  EXPECT_EQ(message({DriveType::force, 1, std::nan(""), inf, 0, 0}),
            "drive on joint 'elbow': damping = nan must be finite and >= 0");
  EXPECT_EQ(message({DriveType::force, 1, 1, 0, 0, 0}),
            "drive on joint 'elbow': max_force = 0 must be > 0");
  EXPECT_EQ(message({DriveType::force, 1, 1, -5, 0, 0}),
            "drive on joint 'elbow': max_force = -5 must be > 0");
  EXPECT_EQ(message({DriveType::force, inf, 1, 1, 0, 0}),
            "drive on joint 'elbow': stiffness = inf must be finite and >= 0");
  EXPECT_EQ(message({DriveType::force, 1, 1, 1, inf, 0}),
            "drive on joint 'elbow': target_position = inf must be finite");
  EXPECT_EQ(message({DriveType::force, 1, 1, inf, 0, 0}), "no error");
  EXPECT_EQ(message({DriveType::force, 1, 1, inf, 0, 0, 0.0}),
            "drive on joint 'elbow': max_impulse = 0 must be > 0");
  EXPECT_EQ(message({DriveType::force, 1, 1, 10, 0, 0, 0.5}),
            "drive on joint 'elbow': set max_force (a force) or max_impulse (an impulse per step), "
            "not both");
}

// docs/math/implicit_drives.md eq. T1-T3: the velocity a step's target term gives a dof is at
// most |x_T - x_0| / tau + |v_T|, whatever the gains; targets beyond +-1e6 are refused.
TEST(DriveRow, TargetsBeyondTheRepresentableRangeAreRefused) {
  std::mt19937 rng(3);
  for (int i = 0; i < 2000; ++i) {
    const Sample s = random_sample(rng);
    Drive d{DriveType::force, s.kp, s.kd, std::numeric_limits<double>::infinity(), 1e6 * s.xT,
            1e6 * s.vT};
    const DriveRow row = setup_drive_row(d, s.r, s.x0, s.tau, s.tau, false);
    const double bound = std::abs(d.target_position - s.x0) / s.tau + std::abs(d.target_velocity);
    EXPECT_LE(s.r * std::abs(row.target_vel_plus_initial_bias), bound * (1 + 1e-12));
  }
  auto message = [](double position, double velocity) {
    try {
      validate_drive({DriveType::force, 1, 1, std::numeric_limits<double>::infinity(), position,
                      velocity},
                     "slider");
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message(1e6, -1e6), "no error");
  EXPECT_EQ(message(-1e20, 0.0),
            "drive on joint 'slider': target_position = -1e+20 is beyond +-1e6 (m or rad): its "
            "drive impulse cannot be represented beside the step's other impulses");
  EXPECT_NE(message(std::nextafter(1e6, 2e6), 0.0), "no error");
  EXPECT_EQ(message(0.0, 2e10).substr(0, 55),
            "drive on joint 'slider': target_velocity = 2e+10 is bey");
}

TEST(DriveRow, MaxImpulseBoundsTheStepImpulseDirectly) {
  Drive d{DriveType::force, 1e6, 10, std::numeric_limits<double>::infinity(), 1.0, 0.0};
  d.max_impulse = 0.3;
  EXPECT_DOUBLE_EQ(drive_impulse(setup_drive_row(d, 1.0, 0.0, 0.01, 0.01, false), 0.0, 0.0, 0.0, 0.0), 0.3);
}

}  // namespace
}  // namespace featherdrive
