// quaternion_law for double against Eigen's quaternions and angle-axis rotations (a second
// implementation) and against closed forms (docs/math/quaternion_update.md).
#include "featherdrive/spatial/quaternion_law.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "featherdrive/spatial/types.hpp"

namespace featherdrive {
namespace {

Vec3 random_vector(std::mt19937_64& rng, double scale) {
  std::uniform_real_distribution<double> u(-scale, scale);
  return Vec3(u(rng), u(rng), u(rng));
}

Quat random_quat(std::mt19937_64& rng) {
  std::normal_distribution<double> n;
  return Quat(n(rng), n(rng), n(rng), n(rng)).normalized();
}

void store(const Quat& q, double* out) {
  out[0] = q.w(), out[1] = q.x(), out[2] = q.y(), out[3] = q.z();
}

TEST(QuaternionLaw, TurnIsEigensAngleAxis) {
  std::mt19937_64 rng(5);
  for (int k = 0; k < 200; ++k) {
    const Vec3 t = random_vector(rng, k < 100 ? 1e-3 : 10.0);
    double d[4];
    quaternion_law::turn(t.data(), d);
    const Quat ref(Eigen::AngleAxisd(t.norm(), t.normalized()));
    EXPECT_NEAR(d[0], ref.w(), 1e-15);
    EXPECT_NEAR(d[1], ref.x(), 1e-15);
    EXPECT_NEAR(d[2], ref.y(), 1e-15);
    EXPECT_NEAR(d[3], ref.z(), 1e-15);
  }
  const double zero[3] = {0.0, 0.0, 0.0};
  double d[4];
  quaternion_law::turn(zero, d);
  EXPECT_EQ(d[0], 1.0);
  EXPECT_EQ(d[1], 0.0);
  EXPECT_EQ(d[2], 0.0);
  EXPECT_EQ(d[3], 0.0);
}

TEST(QuaternionLaw, ProductRotateAndRotationAreEigens) {
  std::mt19937_64 rng(6);
  for (int k = 0; k < 100; ++k) {
    const Quat a = random_quat(rng), b = random_quat(rng);
    double qa[4], qb[4], ab[4];
    store(a, qa);
    store(b, qb);
    quaternion_law::product(qa, qb, ab);
    const Quat ref = a * b;
    EXPECT_NEAR(ab[0], ref.w(), 1e-15);
    EXPECT_NEAR(ab[1], ref.x(), 1e-15);
    EXPECT_NEAR(ab[2], ref.y(), 1e-15);
    EXPECT_NEAR(ab[3], ref.z(), 1e-15);
    const Vec3 v = random_vector(rng, 2.0);
    double rv[3];
    quaternion_law::rotate(qa, v.data(), rv);
    const Vec3 vref = a * v;
    for (int r = 0; r < 3; ++r) EXPECT_NEAR(rv[r], vref[r], 1e-14);
    // A quaternion of length 3: the rotation of its normalisation.
    double q3[4], R[9];
    for (int e = 0; e < 4; ++e) q3[e] = 3.0 * qa[e];
    quaternion_law::rotation(q3, R);
    const Mat3 Rref = a.toRotationMatrix();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(R[3 * r + c], Rref(r, c), 1e-15);
  }
}

// A constant body rate w over n steps of h turns q by exp(n h w / 2) exactly (rotations about one
// axis commute), and keeps |q| = 1.
TEST(QuaternionLaw, BodyUpdateComposesToTheClosedForm) {
  std::mt19937_64 rng(7);
  const Quat q0 = random_quat(rng);
  const Vec3 w(0.3, -1.2, 2.0);
  const double h = 1e-3;
  const int n = 1000;
  double q[4];
  store(q0, q);
  for (int k = 0; k < n; ++k) quaternion_law::integrate_body(q, w.data(), h, q);
  const Quat ref = q0 * Quat(Eigen::AngleAxisd(n * h * w.norm(), w.normalized()));
  EXPECT_NEAR(q[0], ref.w(), 1e-12);
  EXPECT_NEAR(q[1], ref.x(), 1e-12);
  EXPECT_NEAR(q[2], ref.y(), 1e-12);
  EXPECT_NEAR(q[3], ref.z(), 1e-12);
  EXPECT_NEAR(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3], 1.0, 1e-15);
}

TEST(QuaternionLaw, TurnRotationIsAngleAxisTimesR) {
  std::mt19937_64 rng(8);
  for (int k = 0; k < 100; ++k) {
    const Mat3 R = random_quat(rng).toRotationMatrix();
    const Vec3 t = random_vector(rng, 5.0);
    const double h = 0.01;
    double Rr[9], out[9];
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) Rr[3 * r + c] = R(r, c);
    quaternion_law::turn_rotation(t.data(), h, Rr, out);
    const Mat3 ref = Eigen::AngleAxisd(h * t.norm(), t.normalized()).toRotationMatrix() * R;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(out[3 * r + c], ref(r, c), 1e-15);
  }
  // No turn: R itself, to the bit.
  const double zero[3] = {0.0, 0.0, 0.0};
  const double R[9] = {0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0};
  double out[9];
  quaternion_law::turn_rotation(zero, 0.01, R, out);
  for (int e = 0; e < 9; ++e) EXPECT_EQ(out[e], R[e]);
}

}  // namespace
}  // namespace featherdrive
