// multi_dof_law (ABA passes 2 and 3 at a joint of N dofs, docs/math/unit_response.md eq.
// AP7-AP13) for double against Eigen's dense forms on random symmetric positive definite
// inertias, N = 3 and 6, read and accumulated as a full 6 x 6 (Simulation's) and as the packed 21
// (the lanes'); a floating root's S read from R against the same S dense; and on random chains of
// three-dof joints against the dense M^-1 (tau - gravity's force).
#include "featherdrive/algorithm/multi_dof_law.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Dense>

#include "featherdrive/spatial/types.hpp"
#include "support/symmetric6.hpp"

namespace featherdrive::test {  // support/symmetric6.hpp's adapters and inputs
namespace {

struct Sqrt {
  double operator()(double x) const { return std::sqrt(x); }
};

template <int N>
using MatN = Eigen::Matrix<double, N, N>;
template <int N>
using Mat6K = Eigen::Matrix<double, 6, N>;

template <int N>
Mat6K<N> random_subspace(std::mt19937_64& rng) {
  std::normal_distribution<double> n;
  Mat6K<N> S;
  for (int c = 0; c < N; ++c)
    for (int r = 0; r < 6; ++r) S(r, c) = n(rng);
  return S;
}

template <int N>
void check_spd_inverse(std::mt19937_64& rng) {
  for (int k = 0; k < 200; ++k) {
    const Mat6 A = random_spd(rng);
    const MatN<N> D = A.template topLeftCorner<N, N>();
    MatN<N> D_inv;  // row-major or column-major alike: the law writes both halves
    multi_dof_law::spd_inverse<N>(D.data(), D_inv.data(), Sqrt{});
    const MatN<N> expected = D.inverse();
    EXPECT_LT((D_inv - expected).norm(), 1e-12 * expected.norm()) << k;
    for (int a = 0; a < N; ++a)
      for (int b = 0; b < N; ++b) EXPECT_EQ(D_inv(a, b), D_inv(b, a));
  }
}

TEST(MultiDofLaw, SpdInverseIsEigensInverse) {  // AP9
  std::mt19937_64 rng(21);
  check_spd_inverse<3>(rng);
  check_spd_inverse<6>(rng);
}

// AP7-AP11 against I^a = I^A - U D^-1 U^T, p^a = p^A + I^a c + U D^-1 u by Eigen's products, the
// full and packed storage giving the same bits, and I^a S = U D^-1 diag(armature).
template <int N>
void check_pass2(std::mt19937_64& rng) {
  for (int k = 0; k < 200; ++k) {
    const Mat6 IA = random_spd(rng), IA_parent = random_spd(rng);
    const Mat6K<N> S = random_subspace<N>(rng);
    const Vec6 pA = random_vec6(rng), c = random_vec6(rng), pA_parent = random_vec6(rng);
    Eigen::Matrix<double, N, 1> armature, tau;
    for (int a = 0; a < N; ++a) {
      armature[a] = 0.01 * ((k + a) % 5);
      tau[a] = 0.5 - 0.003 * k + a;
    }
    const Mat6K<N> U_dense = IA * S;
    const MatN<N> D = S.transpose() * U_dense + MatN<N>(armature.asDiagonal());
    const MatN<N> D_inv_dense = D.llt().solve(MatN<N>::Identity());
    const Eigen::Matrix<double, N, 1> u_dense = tau - S.transpose() * pA;
    const Mat6 Ia_dense = IA - U_dense * D_inv_dense * U_dense.transpose();
    const Mat6 expected_inertia = IA_parent + Ia_dense;
    const Vec6 expected_bias = pA_parent + pA + Ia_dense * c + U_dense * (D_inv_dense * u_dense);
    const double scale = IA.norm() + IA_parent.norm();

    const multi_dof_law::DenseSubspace<double, N> s{S.data()};
    auto arm = [&](int a) { return armature[a]; };
    Mat6K<N> U, UD;
    MatN<N> D_inv;
    Eigen::Matrix<double, N, 1> u;
    double Ia[36];
    FullSymmetric full{IA_parent};
    Vec6 bias = pA_parent;
    multi_dof_law::joint_inertia<N>(FullSymmetric{IA}, s, arm, Sqrt{}, U.data(), D_inv.data());
    multi_dof_law::joint_force<N>(tau.data(), s, pA.data(), u.data());
    multi_dof_law::project_inertia<N>(FullSymmetric{IA}, U.data(), D_inv.data(), full, UD.data(),
                                      Ia);
    multi_dof_law::project_bias<N>(Ia, UD.data(), pA.data(), u.data(), c.data(), bias.data());
    EXPECT_LT((U - U_dense).norm(), 1e-13 * U_dense.norm()) << k;
    EXPECT_LT((D_inv - D_inv_dense).norm(), 1e-11 * D_inv_dense.norm()) << k;
    EXPECT_LT((u - u_dense).norm(), 1e-13 * (tau.norm() + S.norm() * pA.norm())) << k;
    EXPECT_LT((full.m - expected_inertia).norm(), 1e-11 * scale) << k;
    EXPECT_LT((bias - expected_bias).norm(), 1e-11 * (scale + expected_bias.norm())) << k;
    // I^a S = U - U D^-1 (D - diag(armature)) = U D^-1 diag(armature): 0 without armature.
    const Mat6K<N> IaS_expected = U_dense * D_inv_dense * armature.asDiagonal();
    EXPECT_LT((Eigen::Map<const Mat6>(Ia) * S - IaS_expected).norm(),
              1e-11 * IA.norm() * S.norm()) << k;

    // The packed 21 take the same operations on the upper triangle: the same bits.
    const PackedSymmetric IA_packed = pack(IA);
    PackedSymmetric packed = pack(IA_parent);
    Mat6K<N> U_p, UD_p;
    MatN<N> D_inv_p;
    double Ia_p[36];
    Vec6 bias_p = pA_parent;
    multi_dof_law::joint_inertia<N>(IA_packed, s, arm, Sqrt{}, U_p.data(), D_inv_p.data());
    multi_dof_law::project_inertia<N>(IA_packed, U_p.data(), D_inv_p.data(), packed, UD_p.data(),
                                      Ia_p);
    multi_dof_law::project_bias<N>(Ia_p, UD_p.data(), pA.data(), u.data(), c.data(),
                                   bias_p.data());
    EXPECT_TRUE(U_p == U && D_inv_p == D_inv && bias_p == bias) << k;
    for (int a = 0; a < 6; ++a)
      for (int b = a; b < 6; ++b) EXPECT_EQ(packed(a, b), full.m(a, b)) << a << ", " << b;
  }
}

TEST(MultiDofLaw, Pass2IsEigensDenseForm) {  // AP7-AP11
  std::mt19937_64 rng(22);
  check_pass2<3>(rng);
  check_pass2<6>(rng);
}

// A floating root's S = diag(R, R) read from R (row- or column-major) takes the operations of the same S dense on its
// non-zero entries: the same values (adding a product with a zero changes no non-zero sum).
TEST(MultiDofLaw, RotationPairIsTheDenseBlockDiagonal) {
  std::mt19937_64 rng(23);
  for (int k = 0; k < 100; ++k) {
    const Mat3 R = Eigen::Quaterniond(Eigen::Vector4d(random_vec6(rng).head<4>())).normalized()
                       .toRotationMatrix();
    Mat6 S = Mat6::Zero();
    S.topLeftCorner<3, 3>() = R;
    S.bottomRightCorner<3, 3>() = R;
    const Eigen::Matrix<double, 3, 3, Eigen::RowMajor> R_rows = R;
    const multi_dof_law::RotationPair<double> pair{R_rows.data()};
    const multi_dof_law::DenseSubspace<double, 6> dense{S.data()};
    const Mat6 IA = random_spd(rng);
    const Vec6 pA = random_vec6(rng), tau = random_vec6(rng), qdd = random_vec6(rng);
    auto arm = [](int a) { return 0.1 * a; };
    Mat6 U1, U2, D1, D2;
    Vec6 u1, u2, a1 = random_vec6(rng), a2 = a1;
    multi_dof_law::joint_inertia<6>(FullSymmetric{IA}, pair, arm, Sqrt{}, U1.data(), D1.data());
    multi_dof_law::joint_inertia<6>(FullSymmetric{IA}, dense, arm, Sqrt{}, U2.data(), D2.data());
    multi_dof_law::joint_force<6>(tau.data(), pair, pA.data(), u1.data());
    multi_dof_law::joint_force<6>(tau.data(), dense, pA.data(), u2.data());
    multi_dof_law::add_joint_motion(pair, qdd.data(), a1.data());
    multi_dof_law::add_joint_motion(dense, qdd.data(), a2.data());
    EXPECT_TRUE(U1 == U2 && D1 == D2 && u1 == u2 && a1 == a2) << k;
    const multi_dof_law::RotationPair<double, true> columns{R.data()};  // Eigen's Mat3
    for (int r = 0; r < 6; ++r)
      for (int c = 0; c < 6; ++c) EXPECT_EQ(columns(r, c), pair(r, c));
  }
}

// AP12, AP13 with AP7-AP11 on random chains of three-dof joints in frame 0 at rest, gravity as
// the world's upward acceleration a0: qdd against the dense M^-1 (tau - sum_k J_k^T I_k a0), with
// M = sum_k J_k^T I_k J_k + diag(armature) and J_k = [S_0 ... S_k 0 ...].
TEST(MultiDofLaw, ChainAccelerationsAreTheDenseSolution) {
  std::mt19937_64 rng(24);
  std::normal_distribution<double> n;
  for (int trial = 0; trial < 20; ++trial) {
    const int links = 2 + trial % 6, nv = 3 * links;
    std::vector<Mat6> I(links);
    std::vector<Mat6K<3>> S(links);
    Eigen::VectorXd armature(nv), tau(nv);
    for (int k = 0; k < links; ++k) {
      I[k] = random_spd(rng);
      S[k] = random_subspace<3>(rng);
    }
    for (int d = 0; d < nv; ++d) {
      armature[d] = trial % 2 ? 0.05 * (d + 1) : 0.0;
      tau[d] = n(rng);
    }
    const Vec6 a0(0.0, 0.0, 0.0, 0.1 * n(rng), 0.2 * n(rng), 9.81);
    Eigen::MatrixXd M = armature.asDiagonal();
    Eigen::VectorXd rhs = tau;
    for (int k = 0; k < links; ++k) {
      Eigen::Matrix<double, 6, Eigen::Dynamic> J = Eigen::MatrixXd::Zero(6, nv);
      for (int j = 0; j <= k; ++j) J.middleCols<3>(3 * j) = S[j];
      M += J.transpose() * I[k] * J;
      rhs -= J.transpose() * (I[k] * a0);
    }
    const Eigen::VectorXd expected = M.ldlt().solve(rhs);

    std::vector<FullSymmetric> IA(links);
    for (int k = 0; k < links; ++k) IA[k].m = I[k];
    std::vector<Mat6K<3>> U(links);
    std::vector<MatN<3>> D_inv(links);
    std::vector<Vec6> pA(links, Vec6::Zero());
    Eigen::VectorXd u(nv);
    const Vec6 c = Vec6::Zero();  // at rest
    for (int k = links - 1; k >= 0; --k) {
      const multi_dof_law::DenseSubspace<double, 3> s{S[k].data()};
      auto arm = [&](int a) { return armature[3 * k + a]; };
      multi_dof_law::joint_inertia<3>(IA[k], s, arm, Sqrt{}, U[k].data(), D_inv[k].data());
      multi_dof_law::joint_force<3>(tau.data() + 3 * k, s, pA[k].data(), u.data() + 3 * k);
      if (k == 0) continue;
      double UD[18], Ia[36];
      multi_dof_law::project_inertia<3>(IA[k], U[k].data(), D_inv[k].data(), IA[k - 1], UD, Ia);
      multi_dof_law::project_bias<3>(Ia, UD, pA[k].data(), u.data() + 3 * k, c.data(),
                                     pA[k - 1].data());
    }
    Vec6 a = a0;
    for (int k = 0; k < links; ++k) {
      double qdd[3];
      multi_dof_law::joint_acceleration<3>(U[k].data(), D_inv[k].data(), u.data() + 3 * k,
                                           a.data(), qdd);
      multi_dof_law::add_joint_motion(multi_dof_law::DenseSubspace<double, 3>{S[k].data()}, qdd,
                                      a.data());
      for (int b = 0; b < 3; ++b)
        EXPECT_NEAR(qdd[b], expected[3 * k + b], 1e-9 * (1.0 + expected.norm()))
            << trial << ", " << k;
    }
  }
}

}  // namespace
}  // namespace featherdrive::test
