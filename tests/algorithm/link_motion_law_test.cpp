// link_motion_law for double against a second form: the 6 x 6 spatial inertia in frame 0 built
// from its definition with Eigen's products, and the spatial cross products as 6 x 6 matrices
// crm(v), crf(v) = -crm(v)^T (docs/math/unit_response.md, eq. P1-1 to P1-5), and a body's motion
// given in its own frame (P1-6, P1-7); compat physx's world velocities (physx_departures.md, PD-6,
// PD-7) against frame_velocity of the same q, qd (the link frames' velocities by the forward
// kinematics' spatial recursion).
#include "featherdrive/algorithm/link_motion_law.hpp"

#include <gtest/gtest.h>

#include <random>

#include "featherdrive/algorithm/frame_kinematics.hpp"
#include "featherdrive/algorithm/kinematics.hpp"
#include "featherdrive/spatial/joint_transform_law.hpp"
#include "featherdrive/spatial/types.hpp"
#include "support/models.hpp"

namespace featherdrive {
namespace {

Mat3 skew3(const Vec3& a) {
  Mat3 m;
  m << 0.0, -a.z(), a.y(), a.z(), 0.0, -a.x(), -a.y(), a.x(), 0.0;
  return m;
}

// crm(v) m = v x m for motion vectors.
Mat6 motion_cross_matrix(const Vec6& v) {
  Mat6 X = Mat6::Zero();
  X.topLeftCorner<3, 3>() = skew3(v.head<3>());
  X.bottomRightCorner<3, 3>() = skew3(v.head<3>());
  X.bottomLeftCorner<3, 3>() = skew3(v.tail<3>());
  return X;
}

Vec3 random_vector(std::mt19937_64& rng, double scale) {
  std::uniform_real_distribution<double> u(-scale, scale);
  return Vec3(u(rng), u(rng), u(rng));
}

struct Body {
  Mat3 R;
  Vec3 p, com;
  double m;
  Mat3 Ic;  // symmetric positive definite
};

Body random_body(std::mt19937_64& rng, bool diagonal) {
  std::normal_distribution<double> n;
  std::uniform_real_distribution<double> u(0.1, 5.0);
  Body b;
  b.R = Quat(n(rng), n(rng), n(rng), n(rng)).normalized().toRotationMatrix();
  b.p = random_vector(rng, 3.0);
  b.com = random_vector(rng, 0.5);
  b.m = u(rng);
  if (diagonal) {
    b.Ic = Vec3(u(rng), u(rng), u(rng)).asDiagonal();
  } else {
    const Mat3 G = Mat3::Random();
    b.Ic = G * G.transpose() + 0.1 * Mat3::Identity();
  }
  return b;
}

// The reference: I = [Ic0 + m cx cx^T, m cx; m cx^T, m 1] with Ic0 = R Ic R^T, c = p + R com.
Mat6 reference_inertia(const Body& b) {
  const Vec3 c = b.p + b.R * b.com;
  const Mat3 C = skew3(c);
  Mat6 I;
  I.topLeftCorner<3, 3>() = b.R * b.Ic * b.R.transpose() + b.m * C * C.transpose();
  I.topRightCorner<3, 3>() = b.m * C;
  I.bottomLeftCorner<3, 3>() = b.m * C.transpose();
  I.bottomRightCorner<3, 3>() = b.m * Mat3::Identity();
  return I;
}

// The law's parts of b's inertia, Ic given as Mat3.
void law_inertia(const Body& b, bool diagonal, double* c, double* mc, double* A) {
  Mat3 RI;
  if (diagonal) link_motion_law::rotate_principal(b.R, b.Ic(0, 0), b.Ic(1, 1), b.Ic(2, 2), RI);
  else link_motion_law::rotate_full(b.R, b.Ic, RI);
  link_motion_law::centre_of_mass(b.R, b.p.data(), b.com.data(), b.m, c, mc);
  link_motion_law::rotational_block(b.R, RI, c, mc, A);
}

Mat6 assemble(const double* A, const double* mc, double m) {
  Mat3 Am;
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 3; ++k) Am(r, k) = A[link_motion_law::kA[r][k]];
  const Mat3 C = skew3(Vec3(mc[0], mc[1], mc[2]));
  Mat6 I;
  I << Am, C, C.transpose(), m * Mat3::Identity();
  return I;
}

TEST(LinkMotionLaw, BodyInertiaIsTheSpatialInertiaInFrame0) {  // P1-1, P1-2
  std::mt19937_64 rng(5);
  for (int k = 0; k < 200; ++k) {
    const bool diagonal = k % 2 == 0;
    const Body b = random_body(rng, diagonal);
    double c[3], mc[3], A[6];
    law_inertia(b, diagonal, c, mc, A);
    const Vec3 c_ref = b.p + b.R * b.com;
    for (int r = 0; r < 3; ++r) {
      EXPECT_NEAR(c[r], c_ref[r], 1e-14) << k;
      EXPECT_NEAR(mc[r], b.m * c_ref[r], 1e-13) << k;
    }
    const Mat6 I_ref = reference_inertia(b);
    EXPECT_LE((assemble(A, mc, b.m) - I_ref).norm(), 1e-13 * I_ref.norm()) << k;
  }
}

TEST(LinkMotionLaw, RowMajorArraysGiveTheSameBits) {  // the lanes' storage
  std::mt19937_64 rng(9);
  for (int k = 0; k < 50; ++k) {
    const Body b = random_body(rng, false);
    double c[3], mc[3], A[6];
    law_inertia(b, false, c, mc, A);
    double R[9], Ic[9], RI[9], c2[3], mc2[3], A2[6];
    for (int r = 0; r < 3; ++r)
      for (int q = 0; q < 3; ++q) R[3 * r + q] = b.R(r, q), Ic[3 * r + q] = b.Ic(r, q);
    link_motion_law::rotate_full(joint_transform_law::rows(R), joint_transform_law::rows(Ic),
                                 joint_transform_law::rows(RI));
    link_motion_law::centre_of_mass(joint_transform_law::rows(R), b.p.data(), b.com.data(), b.m,
                                    c2, mc2);
    link_motion_law::rotational_block(joint_transform_law::rows(R), joint_transform_law::rows(RI),
                                      c2, mc2, A2);
    for (int r = 0; r < 3; ++r) {
      EXPECT_EQ(c2[r], c[r]);
      EXPECT_EQ(mc2[r], mc[r]);
    }
    for (int e = 0; e < 6; ++e) EXPECT_EQ(A2[e], A[e]);
  }
}

TEST(LinkMotionLaw, VelocityProductAndBiasAreSpatialCrossProducts) {  // P1-3 to P1-5
  std::mt19937_64 rng(17);
  for (int k = 0; k < 200; ++k) {
    const Body b = random_body(rng, k % 3 == 0);
    double c[3], mc[3], A[6];
    law_inertia(b, k % 3 == 0, c, mc, A);
    Vec6 v_parent, sqd;
    v_parent << random_vector(rng, 4.0), random_vector(rng, 2.0);
    sqd << random_vector(rng, 3.0), random_vector(rng, 1.0);
    const bool root = k % 5 == 0;
    double v[6], cv[6], p[6];
    link_motion_law::velocity(root ? nullptr : v_parent.data(), sqd.data(), v);
    link_motion_law::velocity_product(v, sqd.data(), cv);
    link_motion_law::bias_force(v, A, mc, b.m, p);

    const Vec6 v_ref = root ? sqd : Vec6(v_parent + sqd);
    const Vec6 c_ref = motion_cross_matrix(v_ref) * sqd;
    const Mat6 I = reference_inertia(b);
    const Vec6 p_ref = -motion_cross_matrix(v_ref).transpose() * (I * v_ref);
    for (int r = 0; r < 6; ++r) {
      EXPECT_EQ(v[r], v_ref[r]) << k;  // one addition each
      EXPECT_NEAR(cv[r], c_ref[r], 1e-13 * (1.0 + c_ref.norm())) << k << ", " << r;
      EXPECT_NEAR(p[r], p_ref[r], 1e-12 * (1.0 + p_ref.norm())) << k << ", " << r;
    }
  }
}

TEST(LinkMotionLaw, BiasForceOfASpinAboutAPrincipalAxisThroughTheComIsZero) {  // P1-5, closed
  // A body spinning about a principal axis through its centre of mass, translating along it: no
  // gyroscopic torque (w x Ic w = 0) and no net force (m w x v_com = 0).
  Body b;
  b.R = Mat3::Identity();
  b.p = Vec3(0.3, -0.2, 0.5);
  b.com = Vec3(0.1, 0.2, -0.4);
  b.m = 2.5;
  b.Ic = Vec3(1.0, 2.0, 3.0).asDiagonal();
  double cg[3], mc[3], A[6];
  law_inertia(b, true, cg, mc, A);
  const Vec3 c(cg[0], cg[1], cg[2]);
  const Vec3 w(0.0, 4.0, 0.0), v_com(0.0, -1.5, 0.0);
  Vec6 v;
  v << w, v_com - w.cross(c);  // the frame origin's velocity
  double p[6];
  link_motion_law::bias_force(v.data(), A, mc, b.m, p);
  for (int r = 0; r < 6; ++r) EXPECT_NEAR(p[r], 0.0, 1e-13) << r;
}

TEST(LinkMotionLaw, CentreOfMassVelocityAndLinkAxesAsTheLinkFrameForms) {  // P1-6, P1-7
  // A body's motion given in its own frame (angular w_L, origin velocity v_L, Featherstone's
  // link-frame velocity) carried into frame 0 with Eigen's products: w = R w_L, the velocity of
  // the body point at frame 0's origin v_O - w x p; the centre of mass moves at R (v_L + w_L x
  // com) and w in the link's axes is w_L.
  std::mt19937_64 rng(17);
  for (int trial = 0; trial < 50; ++trial) {
    const Body b = random_body(rng, trial % 2 == 0);
    const Vec3 w_L = random_vector(rng, 4.0), v_L = random_vector(rng, 3.0);
    const Vec3 w = b.R * w_L;
    Vec6 v;
    v << w, b.R * v_L - w.cross(b.p);
    double c[3], mc[3], v_c[3], local[3];
    link_motion_law::centre_of_mass(b.R, b.p.data(), b.com.data(), b.m, c, mc);
    link_motion_law::point_velocity(v.data(), c, v_c);
    link_motion_law::in_link_axes(b.R, w.data(), local);
    const Vec3 expected = b.R * (v_L + w_L.cross(b.com));
    for (int r = 0; r < 3; ++r) {
      EXPECT_NEAR(v_c[r], expected[r], 1e-13) << trial << " " << r;
      EXPECT_NEAR(local[r], w_L[r], 1e-14) << trial << " " << r;
    }
    // The lanes' storage: R row-major through joint_transform_law::rows, the same bits.
    double Rrows[9], local_rows[3];
    for (int r = 0; r < 3; ++r)
      for (int k = 0; k < 3; ++k) Rrows[3 * r + k] = b.R(r, k);
    link_motion_law::in_link_axes(joint_transform_law::rows(Rrows), w.data(), local_rows);
    for (int r = 0; r < 3; ++r) EXPECT_EQ(local_rows[r], local[r]);
  }
}

// PD-6 link by link from the root's twist in world axes (PD-7) against the angular velocity and
// the centre of mass's velocity that frame_velocity gives in world axes, on random trees of
// every joint type, fixed and floating; the lanes' row-major R gives the same bits.
TEST(LinkMotionLaw, WorldVelocityAsFrameVelocity) {
  using link_motion_law::JointRates;
  for (unsigned seed = 1; seed <= 12; ++seed) {
    const bool floating = seed % 2 == 0;
    const auto model = test::make_random_tree(seed, 9, floating, true);
    std::mt19937 rng(seed);
    const VecX q = test::random_configuration(*model, rng);
    const VecX qd = test::random_vector(model->nv, rng, 2.0);
    Data data(*model);
    forward_kinematics(*model, data, q, qd);
    const int n = model->num_links();
    std::vector<Vec3> w(n), v(n), c(n), w_rows(n), v_rows(n);
    for (int i = 0; i < n; ++i)
      c[i] = data.world_position[i] + data.world_rotation[i] * model->links[i].com;
    Vec3 w0 = Vec3::Zero(), v0 = Vec3::Zero();
    const Link& root = model->links[0];
    if (floating) {
      link_motion_law::in_world_axes(data.world_rotation[0], &qd[root.v_index], w0.data());
      link_motion_law::in_world_axes(data.world_rotation[0], &qd[root.v_index + 3], v0.data());
    }
    for (int i = 0; i < n; ++i) {
      const Link& link = model->links[i];
      const int p = link.parent;
      const JointRates joint = i == 0 ? JointRates::none
                               : link.joint_type == JointType::revolute  ? JointRates::about_axis
                               : link.joint_type == JointType::prismatic ? JointRates::along_axis
                               : link.joint_type == JointType::spherical ? JointRates::ball
                                                                         : JointRates::none;
      const double* x = joint == JointRates::none ? qd.data() : &qd[link.v_index];
      const Mat3& R = data.world_rotation[i];
      link_motion_law::world_velocity(i == 0 ? w0.data() : w[p].data(),
                                      i == 0 ? v0.data() : v[p].data(),
                                      i == 0 ? nullptr : c[p].data(), R,
                                      data.world_position[i].data(), c[i].data(), joint,
                                      link.axis.data(), x, w[i].data(), v[i].data());
      double Rrows[9];
      for (int r = 0; r < 3; ++r)
        for (int k = 0; k < 3; ++k) Rrows[3 * r + k] = R(r, k);
      link_motion_law::world_velocity(i == 0 ? w0.data() : w_rows[p].data(),
                                      i == 0 ? v0.data() : v_rows[p].data(),
                                      i == 0 ? nullptr : c[p].data(),
                                      joint_transform_law::rows(Rrows),
                                      data.world_position[i].data(), c[i].data(), joint,
                                      link.axis.data(), x, w_rows[i].data(), v_rows[i].data());
      const Vec6 expected =
          frame_velocity(*model, data, i, link.com, ReferenceFrame::world_aligned);
      for (int r = 0; r < 3; ++r) {
        EXPECT_NEAR(w[i][r], expected[r], 1e-12) << seed << " link " << i << " " << r;
        EXPECT_NEAR(v[i][r], expected[3 + r], 1e-12) << seed << " link " << i << " " << r;
        EXPECT_EQ(w_rows[i][r], w[i][r]);
        EXPECT_EQ(v_rows[i][r], v[i][r]);
      }
    }
  }
}

}  // namespace
}  // namespace featherdrive
