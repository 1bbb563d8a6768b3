// articulated_law (ABA passes 2 and 3 at a one-dof joint, docs/math/unit_response.md eq. AP1-AP6)
// for double against Eigen's dense products on random symmetric positive definite inertias, read
// and accumulated both as a full 6 x 6 (Simulation's Mat6) and as the packed 21 entries (the
// lanes'), and on random chains against the dense M^-1 (tau - gravity's force).
#include "featherdrive/algorithm/articulated_law.hpp"

#include <gtest/gtest.h>

#include <random>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "featherdrive/sim/link_laws.hpp"
#include "featherdrive/spatial/types.hpp"
#include "support/symmetric6.hpp"

namespace featherdrive::test {  // support/symmetric6.hpp's adapters and inputs
namespace {

TEST(ArticulatedLaw, PackedIndexIsLinkLawsLayout) {
  Mat6 m;
  for (int c = 0; c < 6; ++c)
    for (int r = 0; r < 6; ++r) m(r, c) = r <= c ? 10 * r + c : 10 * c + r;
  const PackedSymmetric p = pack(m);
  for (int a = 0; a < 6; ++a)
    for (int b = 0; b < 6; ++b) EXPECT_EQ(p(a, b), m(a, b)) << a << ", " << b;
}

TEST(ArticulatedLaw, JointInertiaAndForceAreTheDenseProducts) {  // AP1, AP2
  std::mt19937_64 rng(11);
  for (int k = 0; k < 200; ++k) {
    const Mat6 IA = random_spd(rng);
    const Vec6 S = random_vec6(rng), pA = random_vec6(rng);
    const double armature = 0.01 * k, tau = 0.5 - 0.003 * k;
    const Vec6 U_dense = IA * S;
    const double D = S.dot(IA * S) + armature;
    for (const bool packed : {false, true}) {
      Vec6 U;
      const double D_inv =
          packed ? articulated_law::joint_inertia(pack(IA), S.data(), armature, U.data())
                 : articulated_law::joint_inertia(FullSymmetric{IA}, S.data(), armature, U.data());
      EXPECT_LT((U - U_dense).norm(), 1e-13 * U_dense.norm()) << k;
      EXPECT_NEAR(D_inv * D, 1.0, 1e-13) << k;
    }
    EXPECT_NEAR(articulated_law::joint_force(tau, S.data(), pA.data()), tau - S.dot(pA),
                1e-13 * (std::abs(tau) + S.norm() * pA.norm()));
  }
}

TEST(ArticulatedLaw, ProjectionIsEigensDenseForm) {  // AP3, AP4
  std::mt19937_64 rng(12);
  for (int k = 0; k < 200; ++k) {
    const Mat6 IA = random_spd(rng), IA_parent = random_spd(rng);
    const Vec6 S = random_vec6(rng), pA = random_vec6(rng), c = random_vec6(rng);
    const Vec6 pA_parent = random_vec6(rng);
    const double armature = 0.02 * k, tau = 1.0 - 0.01 * k;
    // The unsimplified form: Ia = IA - U U^T / D, pa = pA + Ia c + U u / D.
    const Vec6 U_dense = IA * S;
    const double D = S.dot(U_dense) + armature;
    const double u_dense = tau - S.dot(pA);
    const Mat6 Ia = IA - U_dense * U_dense.transpose() / D;
    const Mat6 expected_inertia = IA_parent + Ia;
    const Vec6 expected_bias = pA_parent + pA + Ia * c + U_dense * (u_dense / D);
    const double scale = IA.norm() + IA_parent.norm();

    Vec6 U;
    FullSymmetric full{IA_parent};
    const double D_inv = articulated_law::joint_inertia(FullSymmetric{IA}, S.data(), armature, U.data());
    const double u = articulated_law::joint_force(tau, S.data(), pA.data());
    articulated_law::project_inertia(FullSymmetric{IA}, U.data(), D_inv, full);
    Vec6 bias = pA_parent;
    articulated_law::project_bias(FullSymmetric{IA}, pA.data(), c.data(), U.data(), D_inv, u, bias.data());
    EXPECT_LT((full.m - expected_inertia).norm(), 1e-12 * scale) << k;
    EXPECT_LT((bias - expected_bias).norm(), 1e-12 * (scale + expected_bias.norm())) << k;

    // The packed 21 take the same operations on the upper triangle: the same bits.
    PackedSymmetric packed = pack(IA_parent);
    const PackedSymmetric IA_packed = pack(IA);
    Vec6 U_packed;
    const double D_inv_packed =
        articulated_law::joint_inertia(IA_packed, S.data(), armature, U_packed.data());
    articulated_law::project_inertia(IA_packed, U_packed.data(), D_inv_packed, packed);
    Vec6 bias_packed = pA_parent;
    articulated_law::project_bias(IA_packed, pA.data(), c.data(), U_packed.data(), D_inv_packed, u,
                                  bias_packed.data());
    EXPECT_EQ(D_inv_packed, D_inv);
    for (int r = 0; r < 6; ++r) {
      EXPECT_EQ(U_packed[r], U[r]);
      EXPECT_EQ(bias_packed[r], bias[r]);
      for (int b = r; b < 6; ++b) EXPECT_EQ(packed(r, b), full.m(r, b)) << r << ", " << b;
    }
  }
}

TEST(ArticulatedLaw, ProjectionRemovesTheJointsDirection) {  // AP3: (IA - U U^T / D) S = 0
  std::mt19937_64 rng(13);
  for (int k = 0; k < 100; ++k) {
    const Mat6 IA = random_spd(rng);
    const Vec6 S = random_vec6(rng);
    Vec6 U;
    const double D_inv = articulated_law::joint_inertia(FullSymmetric{IA}, S.data(), 0.0, U.data());
    FullSymmetric projected{Mat6::Zero()};
    articulated_law::project_inertia(FullSymmetric{IA}, U.data(), D_inv, projected);
    EXPECT_LT((projected.m * S).norm(), 1e-12 * IA.norm() * S.norm()) << k;
  }
}

// AP5, AP6 with AP1-AP4 on random chains of one-dof joints in frame 0 at rest, gravity as the
// world's upward acceleration a0: qdd against the dense M^-1 (tau - sum_k J_k^T I_k a0), with
// M = sum_k J_k^T I_k J_k + diag(armature) and J_k = [S_0 ... S_k 0 ...].
TEST(ArticulatedLaw, ChainAccelerationsAreTheDenseSolution) {
  std::mt19937_64 rng(14);
  std::normal_distribution<double> n;
  for (int trial = 0; trial < 20; ++trial) {
    const int links = 2 + trial % 9;
    std::vector<Mat6> I(links);
    std::vector<Vec6> S(links);
    std::vector<double> armature(links), tau(links);
    for (int k = 0; k < links; ++k) {
      I[k] = random_spd(rng);
      S[k] = random_vec6(rng);
      armature[k] = trial % 2 ? 0.05 * (k + 1) : 0.0;
      tau[k] = n(rng);
    }
    const Vec6 a0(0.0, 0.0, 0.0, 0.1 * n(rng), 0.2 * n(rng), 9.81);
    Eigen::MatrixXd M = Eigen::MatrixXd::Zero(links, links);
    Eigen::VectorXd rhs = Eigen::Map<const Eigen::VectorXd>(tau.data(), links);
    for (int k = 0; k < links; ++k) {
      Eigen::Matrix<double, 6, Eigen::Dynamic> J = Eigen::MatrixXd::Zero(6, links);
      for (int j = 0; j <= k; ++j) J.col(j) = S[j];
      M += J.transpose() * I[k] * J;
      M(k, k) += armature[k];
      rhs -= J.transpose() * (I[k] * a0);
    }
    const Eigen::VectorXd expected = M.ldlt().solve(rhs);

    std::vector<FullSymmetric> IA(links);
    for (int k = 0; k < links; ++k) IA[k].m = I[k];
    std::vector<Vec6> U(links), pA(links, Vec6::Zero());
    std::vector<double> D_inv(links), u(links);
    const Vec6 c = Vec6::Zero();  // at rest
    for (int k = links - 1; k >= 0; --k) {
      D_inv[k] = articulated_law::joint_inertia(IA[k], S[k].data(), armature[k], U[k].data());
      u[k] = articulated_law::joint_force(tau[k], S[k].data(), pA[k].data());
      if (k == 0) continue;
      articulated_law::project_bias(IA[k], pA[k].data(), c.data(), U[k].data(), D_inv[k], u[k],
                                    pA[k - 1].data());
      articulated_law::project_inertia(IA[k], U[k].data(), D_inv[k], IA[k - 1]);
    }
    Vec6 a = a0;
    for (int k = 0; k < links; ++k) {
      const double qdd = articulated_law::joint_acceleration(U[k].data(), D_inv[k], u[k], a.data());
      articulated_law::add_joint_motion(qdd, S[k].data(), a.data());
      EXPECT_NEAR(qdd, expected[k], 1e-9 * (1.0 + expected.norm())) << trial << ", " << k;
    }
  }
}

}  // namespace
}  // namespace featherdrive::test
