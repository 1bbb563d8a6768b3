// joint_transform_law for double against Eigen's angle-axis rotations and matrix products (a
// second implementation) and against closed forms (docs/math/joint_transform.md).
#include "featherdrive/spatial/joint_transform_law.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "featherdrive/spatial/types.hpp"

namespace featherdrive {
namespace {

Mat3 random_rotation(std::mt19937_64& rng) {
  std::normal_distribution<double> n;
  return Quat(n(rng), n(rng), n(rng), n(rng)).normalized().toRotationMatrix();
}

void expect_near(const Mat3& a, const Mat3& b, double tol) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(a(r, c), b(r, c), tol) << r << ", " << c;
}

TEST(JointTransformLaw, AxisRotationIsEigensAngleAxis) {  // JT-1
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> angle(-10.0, 10.0);
  std::normal_distribution<double> n;
  for (int k = 0; k < 200; ++k) {
    const Vec3 a = Vec3(n(rng), n(rng), n(rng)).normalized();
    const double x = angle(rng);
    Mat3 J;
    joint_transform_law::axis_rotation(a.x(), a.y(), a.z(), std::sin(x), std::cos(x), J);
    expect_near(J, Eigen::AngleAxisd(x, a).toRotationMatrix(), 1e-15);
    // Row-major storage through rows(): the same matrix.
    double m[9];
    joint_transform_law::axis_rotation(a.x(), a.y(), a.z(), std::sin(x), std::cos(x),
                                       joint_transform_law::rows(m));
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) EXPECT_EQ(m[3 * r + c], J(r, c));
  }
}

TEST(JointTransformLaw, AxisRotationFixesTheAxisAndTurnsAPerpendicular) {  // JT-1, closed form
  const Vec3 a = Vec3(1.0, 2.0, 2.0) / 3.0;
  const Vec3 u = Vec3(2.0, -1.0, 0.0) / std::sqrt(5.0);  // a . u = 0
  const double x = 0.7;
  Mat3 J;
  joint_transform_law::axis_rotation(a.x(), a.y(), a.z(), std::sin(x), std::cos(x), J);
  EXPECT_NEAR((J * a - a).norm(), 0.0, 1e-15);
  // Rodrigues for u perpendicular to a: cos x u + sin x (a x u).
  EXPECT_NEAR((J * u - (std::cos(x) * u + std::sin(x) * a.cross(u))).norm(), 0.0, 1e-15);
}

TEST(JointTransformLaw, CoordinateTurnsAreTheAxisRotation) {  // JT-2 to JT-4
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> angle(-4.0, 4.0);
  for (int k = 0; k < 60; ++k) {
    const int axis = k % 3;
    const double x = angle(rng), s = std::sin(x), c = std::cos(x);
    const Mat3 P = random_rotation(rng);
    const Mat3 Re = Eigen::AngleAxisd(x, Vec3::Unit(axis)).toRotationMatrix();
    Mat3 R, E;
    joint_transform_law::turn_columns(P, axis, s, c, R);
    expect_near(R, P * Re, 1e-15);
    joint_transform_law::turn_rows(P, axis, s, c, E);
    expect_near(E, Re.transpose() * P, 1e-15);
    // A row-major array turned by rows() is the same matrix, to the bit.
    double p[9], r[9];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) p[3 * i + j] = P(i, j);
    joint_transform_law::turn_columns(joint_transform_law::rows(p), axis, s, c,
                                      joint_transform_law::rows(r));
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) EXPECT_EQ(r[3 * i + j], R(i, j));
  }
}

TEST(JointTransformLaw, FrameAndCompositionAreMatrixProducts) {  // JT-5, JT-6
  std::mt19937_64 rng(13);
  for (int k = 0; k < 50; ++k) {
    const Mat3 Rp = random_rotation(rng), E = random_rotation(rng), J = random_rotation(rng);
    Mat3 P, R;
    joint_transform_law::joint_frame(Rp, E, P);
    expect_near(P, Rp * E.transpose(), 1e-15);
    joint_transform_law::compose(P, J, R);
    expect_near(R, P * J, 1e-15);
    // The link's rotation is the parent's times X_i's E transposed, X_i = X_J X_T.
    expect_near(R, Rp * (J.transpose() * E).transpose(), 1e-14);
  }
}

TEST(JointTransformLaw, PrismaticSlideMovesTheOriginAlongTheAxis) {  // JT-7 to JT-9
  std::mt19937_64 rng(17);
  std::normal_distribution<double> n;
  for (int k = 0; k < 50; ++k) {
    const Mat3 Rp = random_rotation(rng), E = random_rotation(rng);
    const Vec3 a = Vec3(n(rng), n(rng), n(rng)).normalized();
    const Vec3 r_T(n(rng), n(rng), n(rng)), pp(n(rng), n(rng), n(rng));
    const double x = 2.0 * n(rng);
    Mat3 P;
    joint_transform_law::joint_frame(Rp, E, P);
    Vec3 a_w, p, p0;
    joint_transform_law::joint_axis(P, -1, 1.0, a, a_w);
    EXPECT_NEAR((a_w - Rp * E.transpose() * a).norm(), 0.0, 1e-15);
    joint_transform_law::link_position(pp, Rp, r_T, p0);
    p = p0;
    joint_transform_law::slide(a_w, x, p);
    // Eigen's products of X_i = X_J(x) X_T: the origin is r_T + E_T^T (a x) in the parent.
    EXPECT_NEAR((p - (pp + Rp * (r_T + E.transpose() * (a * x)))).norm(), 0.0, 1e-14);
    // Closed form: the origin moves by |x| along the axis.
    EXPECT_NEAR((p - p0).norm(), std::abs(x), 1e-14);
    // A coordinate axis -e_k: minus P's column k, the product's value.
    const int c = k % 3;
    joint_transform_law::joint_axis(P, c, -1.0, a, a_w);
    EXPECT_NEAR((a_w - P * (-Vec3::Unit(c))).norm(), 0.0, 1e-16);
    // The same bits on a row-major rotation.
    double m[9], q[3];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) m[3 * i + j] = Rp(i, j);
    joint_transform_law::link_position(pp, joint_transform_law::rows(m), r_T, q);
    for (int i = 0; i < 3; ++i) EXPECT_EQ(q[i], p0[i]);
  }
}

TEST(JointTransformLaw, OneDofSubspaceMovesTheLinkAboutOrAlongItsAxis) {  // JT-10
  std::mt19937_64 rng(23);
  std::normal_distribution<double> n;
  for (int k = 0; k < 50; ++k) {
    const Vec3 a = Vec3(n(rng), n(rng), n(rng)).normalized(), p(n(rng), n(rng), n(rng));
    Vec6 S;
    joint_transform_law::one_dof_subspace(a.data(), p, true, S);
    // A revolute joint's twist [w; v_O] turns frame 0 about the line through p along a: every
    // point p + t a on it stands still (v_O + w x x = 0), a point off it moves by w x (x - p).
    const Vec3 w = S.head<3>(), v0 = S.tail<3>();
    EXPECT_EQ(w, a);
    for (const double t : {-1.5, 0.0, 2.0}) {
      const Vec3 x = p + t * a;
      EXPECT_NEAR((v0 + w.cross(x)).norm(), 0.0, 1e-14);
    }
    const Vec3 off(n(rng), n(rng), n(rng));
    EXPECT_NEAR((v0 + w.cross(off) - a.cross(off - p)).norm(), 0.0, 1e-14);
    // A prismatic joint's moves every point along a.
    joint_transform_law::one_dof_subspace(a.data(), p, false, S);
    EXPECT_EQ(S.head<3>(), Vec3::Zero());
    EXPECT_EQ(S.tail<3>(), a);
  }
}

TEST(JointTransformLaw, BallSubspaceTurnsTheLinkAboutItsOrigin) {  // JT-11
  std::mt19937_64 rng(29);
  std::normal_distribution<double> n;
  for (int k = 0; k < 50; ++k) {
    const Mat3 R = random_rotation(rng);
    const Vec3 p(n(rng), n(rng), n(rng)), w_link(n(rng), n(rng), n(rng));
    Mat6N S(6, 3);
    joint_transform_law::ball_subspace(R, p, joint_transform_law::columns(S.data()));
    // S w_link is the link turning at w_link (its own axes) about its origin: the angular
    // velocity R w_link, the origin p standing still, another point x moving by w x (x - p).
    const Vec6 twist = S * w_link;
    const Vec3 w = twist.head<3>(), v0 = twist.tail<3>();
    EXPECT_NEAR((w - R * w_link).norm(), 0.0, 1e-14);
    EXPECT_NEAR((v0 + w.cross(p)).norm(), 0.0, 1e-14);
    const Vec3 x(n(rng), n(rng), n(rng));
    EXPECT_NEAR((v0 + w.cross(x) - (R * w_link).cross(x - p)).norm(), 0.0, 1e-14);
    // Each column a revolute joint's S about R's column a through p (JT-10), bit for bit; and the
    // same bits from a row-major rotation (the lanes').
    double m[9], s[18];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) m[3 * i + j] = R(i, j);
    joint_transform_law::ball_subspace(joint_transform_law::rows(m), p,
                                       joint_transform_law::columns(s));
    for (int a = 0; a < 3; ++a) {
      const Vec3 axis = R.col(a);
      Vec6 S1;
      joint_transform_law::one_dof_subspace(axis.data(), p, true, S1);
      for (int r = 0; r < 6; ++r) {
        EXPECT_EQ(S(r, a), S1[r]);
        EXPECT_EQ(s[6 * a + r], S1[r]);
      }
    }
  }
}

}  // namespace
}  // namespace featherdrive
