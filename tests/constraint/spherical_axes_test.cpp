// PhysX's spherical joint positions and drive error (docs/math/spherical_joints.md, eq. S-2, S-5)
// against closed forms: rotations about one axis, the rotation vector of compositions rebuilt as
// a rotation matrix, and the error of a single driven axis, 2 sin((target - angle) / 2).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "featherdrive/constraint/spherical_axes.hpp"

namespace featherdrive {
namespace {

constexpr double kSphericalPi = std::numbers::pi;

Quat turned_about(const Vec3& axis, double angle) { return Quat(Eigen::AngleAxisd(angle, axis)); }

TEST(SphericalAxes, RotationAboutOneAxisIsThatAxisPosition) {
  for (int k = 0; k < 3; ++k)
    for (const double angle : {-3.0, -1.2, -1e-9, 0.0, 1e-7, 0.4, 2.9, kSphericalPi - 1e-6}) {
      const Vec3 e = Vec3::Unit(k);
      const Vec3 theta = spherical_joint_positions(turned_about(e, angle));
      EXPECT_NEAR(theta[k], angle, 1e-14) << "axis " << k;
      EXPECT_NEAR(theta[(k + 1) % 3], 0.0, 1e-15);
      EXPECT_NEAR(theta[(k + 2) % 3], 0.0, 1e-15);
    }
}

TEST(SphericalAxes, BeyondPiTheShorterWayAndEitherSignOfTheQuaternion) {
  // A turn by 1.1 pi about x is one by -0.9 pi; -Q is the same rotation as Q.
  const Quat Q = turned_about(Vec3::UnitX(), 1.1 * kSphericalPi);
  EXPECT_NEAR(spherical_joint_positions(Q)[0], -0.9 * kSphericalPi, 1e-14);
  const Quat R = turned_about(Vec3(1, -2, 0.5).normalized(), 2.2);
  Quat minus = R;
  minus.coeffs() = -R.coeffs();
  EXPECT_LT((spherical_joint_positions(minus) - spherical_joint_positions(R)).norm(), 1e-15);
  EXPECT_LT((spherical_joint_positions(R) - 2.2 * Vec3(1, -2, 0.5).normalized()).norm(), 1e-14);
}

TEST(SphericalAxes, PositionsOfCompositionsRebuildTheRotation) {
  // The positions are a rotation vector: turning by |theta| about theta / |theta| must give the
  // composed rotation matrix (Rodrigues' formula, not the quaternion the positions came from).
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.4, 1.4);
  for (int n = 0; n < 200; ++n) {
    const Mat3 R = (Eigen::AngleAxisd(u(rng), Vec3::UnitZ()) * Eigen::AngleAxisd(u(rng), Vec3::UnitY()) *
                    Eigen::AngleAxisd(u(rng), Vec3::UnitX()))
                       .toRotationMatrix();
    const Vec3 theta = spherical_joint_positions(Quat(R));
    ASSERT_LE(theta.norm(), kSphericalPi);
    const double a = theta.norm();
    const Vec3 n3 = theta / a;
    Mat3 K;
    K << 0, -n3.z(), n3.y(), n3.z(), 0, -n3.x(), -n3.y(), n3.x(), 0;
    const Mat3 rodrigues = Mat3::Identity() + std::sin(a) * K + (1 - std::cos(a)) * K * K;
    EXPECT_LT((rodrigues - R).cwiseAbs().maxCoeff(), 1e-13);
  }
  // Small turns a then b compose to a + b + (a x b) / 2 to second order (Baker-Campbell-Hausdorff).
  const Vec3 a(1e-4, 0, 0), b(0, 2e-4, 0);
  const Quat small = turned_about(a.normalized(), a.norm()) * turned_about(b.normalized(), b.norm());
  EXPECT_LT((spherical_joint_positions(small) - (a + b + 0.5 * a.cross(b))).norm(), 1e-12);
}

TEST(SphericalAxes, DriveErrorOfOneAxisIsTwiceTheSineOfHalfTheMiss) {
  for (int k = 0; k < 3; ++k)
    for (const auto& [angle, target] : {std::pair{0.3, 0.9}, {-1.0, 0.5}, {2.0, -2.5}, {0.2, 0.2}}) {
      std::array<bool, 3> driven{};
      driven[static_cast<size_t>(k)] = true;
      Vec3 targets = Vec3::Constant(7.0);  // undriven axes' targets count for nothing
      targets[k] = target;
      const Vec3 e = spherical_drive_error(turned_about(Vec3::Unit(k), angle), targets, driven);
      // T* Q is a turn by angle - target about e_k, taken the short way round.
      const double miss = std::remainder(target - angle, 2 * kSphericalPi);
      EXPECT_NEAR(e[k], 2.0 * std::sin(miss / 2.0), 1e-14) << "axis " << k;
      EXPECT_NEAR(e.norm(), std::abs(e[k]), 1e-14);
    }
}

TEST(SphericalAxes, DriveErrorIsTheTurnFromTheTargetInItsFrame) {
  // Every axis driven: at Q = T exp(d e_k), a turn by d about the target frame's axis k, the
  // error is -2 sin(d / 2) e_k exactly (T* Q = exp(d e_k)), whatever the target rotation.
  const Vec3 t(0.3, -0.2, 0.5);
  const Quat T(Eigen::AngleAxisd(t.norm(), t.normalized()));
  for (int k = 0; k < 3; ++k)
    for (const double d : {-0.7, 1e-5, 0.4}) {
      const Vec3 e = spherical_drive_error(T * turned_about(Vec3::Unit(k), d), t, {true, true, true});
      EXPECT_LT((e + 2.0 * std::sin(d / 2.0) * Vec3::Unit(k)).norm(), 1e-15) << k << " " << d;
    }
  EXPECT_LT(spherical_drive_error(T, t, {true, true, true}).norm(), 1e-16);
  EXPECT_EQ(spherical_drive_error(T, t, {false, false, false}), Vec3::Zero());
}

}  // namespace
}  // namespace featherdrive
