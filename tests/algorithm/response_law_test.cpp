// response_law (the whole-articulation response, docs/math/unit_response.md eq. R1-R10) for
// double: at a one-dof joint and at one of 3 or 6 dofs against its definition
// Lambda_i = S D^-1 S^T + P T P^T on random matrices, and on random chains of one-dof joints
// against J_k M^-1 J_k^T with M formed densely from the links' Jacobians; the full 6 x 6
// (Simulation's Mat6) and the packed 21 entries (the lanes') give the same bits.
#include "featherdrive/algorithm/response_law.hpp"

#include <gtest/gtest.h>

#include <random>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "featherdrive/algorithm/multi_dof_law.hpp"
#include "featherdrive/sim/link_laws.hpp"
#include "featherdrive/spatial/types.hpp"
#include "support/symmetric6.hpp"

namespace featherdrive::test {  // support/symmetric6.hpp's adapters and inputs
namespace {

TEST(ResponseLaw, IsTheProjectedParentResponse) {  // R1-R4 against Lambda = S D^-1 S^T + P T P^T
  std::mt19937_64 rng(21);
  for (int k = 0; k < 200; ++k) {
    const Mat6 IA = random_spd(rng);
    const Mat6 T = k % 10 == 0 ? Mat6::Zero() : random_spd(rng);  // the world's, or a parent's
    const Vec6 S = random_vec6(rng);
    const double armature = 0.01 * (k % 7);
    const Vec6 U = IA * S;
    const double D = S.dot(U) + armature;
    const Mat6 P = Mat6::Identity() - S * U.transpose() / D;
    const Mat6 expected = S * S.transpose() / D + P * T * P.transpose();
    const double expected_r = 1.0 / D + U.dot(T * U) / (D * D);
    const Vec6 expected_W = T * U;
    const double scale = expected.norm() + T.norm();

    Vec6 W, G;
    FullSymmetric L{Mat6::Zero()};
    const double r =
        response_law::response(FullSymmetric{T}, S.data(), U.data(), 1.0 / D, W.data(), G.data(), L);
    EXPECT_LT((L.m - expected).norm(), 1e-12 * scale) << k;
    EXPECT_NEAR(r, expected_r, 1e-12 * expected_r) << k;
    EXPECT_LE((W - expected_W).norm(), 1e-12 * (T.norm() * U.norm())) << k;
    EXPECT_LT((G - (expected_r * S - expected_W / D)).norm(), 1e-12 * scale * S.norm()) << k;

    // The packed 21 take the same operations on the upper triangle: the same bits.
    PackedSymmetric packed;
    Vec6 W_packed, G_packed;
    const double r_packed = response_law::response(pack(T), S.data(), U.data(), 1.0 / D,
                                                   W_packed.data(), G_packed.data(), packed);
    EXPECT_EQ(r_packed, r);
    for (int a = 0; a < 6; ++a) {
      EXPECT_EQ(W_packed[a], W[a]);
      EXPECT_EQ(G_packed[a], G[a]);
      for (int b = a; b < 6; ++b) EXPECT_EQ(packed(a, b), L.m(a, b)) << a << ", " << b;
    }
  }
}

// A chain of one-dof joints in frame 0 (random S_i, inertias, armatures): ABA pass 2 by
// articulated_law, then response_law root to tip, against the dense J_k M^-1 J_k^T, with
// M = sum_k J_k^T I_k J_k + diag(armature), J_k = [S_0 ... S_k 0 ...] (v_k = sum_{j<=k} S_j qd_j).
TEST(ResponseLaw, ChainResponsesAreTheDenseOperationalSpaceInverses) {
  std::mt19937_64 rng(22);
  for (int trial = 0; trial < 20; ++trial) {
    const int n = 2 + trial % 9;
    std::vector<Mat6> I(n);
    std::vector<Vec6> S(n);
    std::vector<double> armature(n);
    for (int k = 0; k < n; ++k) {
      I[k] = random_spd(rng);
      S[k] = random_vec6(rng);
      armature[k] = trial % 2 ? 0.05 * (k + 1) : 0.0;
    }
    Eigen::MatrixXd M = Eigen::MatrixXd::Zero(n, n);
    std::vector<Eigen::Matrix<double, 6, Eigen::Dynamic>> J(n);
    for (int k = 0; k < n; ++k) {
      J[k] = Eigen::Matrix<double, 6, Eigen::Dynamic>::Zero(6, n);
      for (int j = 0; j <= k; ++j) J[k].col(j) = S[j];
      M += J[k].transpose() * I[k] * J[k];
      M(k, k) += armature[k];
    }
    const Eigen::MatrixXd M_inv = M.inverse();

    std::vector<FullSymmetric> IA(n);
    for (int k = 0; k < n; ++k) IA[k].m = I[k];
    std::vector<Vec6> U(n);
    std::vector<double> D_inv(n);
    for (int k = n - 1; k >= 0; --k) {
      D_inv[k] = articulated_law::joint_inertia(IA[k], S[k].data(), armature[k], U[k].data());
      if (k > 0) articulated_law::project_inertia(IA[k], U[k].data(), D_inv[k], IA[k - 1]);
    }
    std::vector<FullSymmetric> L(n);
    std::vector<Vec6> W(n), G(n);
    std::vector<double> r(n);
    for (int k = 0; k < n; ++k) {
      const FullSymmetric parent{k > 0 ? L[k - 1].m : Mat6::Zero()};
      r[k] = response_law::response(parent, S[k].data(), U[k].data(), D_inv[k], W[k].data(),
                                    G[k].data(), L[k]);
      const Mat6 expected = J[k] * M_inv * J[k].transpose();
      EXPECT_LT((L[k].m - expected).norm(), 1e-10 * expected.norm()) << trial << ", " << k;
      EXPECT_NEAR(r[k], M_inv(k, k), 1e-10 * M_inv(k, k)) << trial << ", " << k;
      if (k == 0) continue;
      // R5: an impulse lambda at joint k-1 alone changes qd_k by M^-1(k, k-1) lambda, which is
      // the sweep's b^lambda (implicit_drives.md, GS2, with nothing else applied).
      const response_law::Chain<double> c = response_law::chain(
          U[k].data(), D_inv[k], S[k - 1].data(), W[k - 1].data(), D_inv[k - 1], r[k - 1]);
      EXPECT_NEAR(c.parent_S, U[k].dot(S[k - 1]), 1e-12 * U[k].norm() * S[k - 1].norm());
      EXPECT_EQ(c.base_per_parent_base, -D_inv[k] * c.parent_S);
      EXPECT_NEAR(c.base_per_parent_impulse, M_inv(k, k - 1),
                  1e-10 * std::sqrt(M_inv(k, k) * M_inv(k - 1, k - 1)))
          << trial << ", " << k;
    }
  }
}

// D^-1 as the lanes store it: N x N row by row.
template <int N>
struct RowMajor {
  const double* m;
  double operator()(int a, int b) const { return m[N * a + b]; }
};

template <int N>
using Mat6K = Eigen::Matrix<double, 6, N>;
template <int N>
using MatK = Eigen::Matrix<double, N, N, Eigen::RowMajor>;

// R6-R10 at a joint of N dofs against Lambda = S D^-1 S^T + P T P^T, P = 1 - S D^-1 U^T,
// (M^-1)_ii = D^-1 + D^-1 U^T T U D^-1 and W = T U, formed densely by Eigen's products. S: a
// random 6 x 3; for N = 6 a floating root's diag(R, R) (a random 6 x 6 leaves D's condition, and
// so the dense reference's error, unbounded).
template <int N>
void check_multi_dof(std::mt19937_64& rng, int k) {
  const Mat6 IA = random_spd(rng);
  const Mat6 T = k % 10 == 0 ? Mat6::Zero() : random_spd(rng);
  Mat6K<N> S;  // a spherical joint's random 6 x 3; a floating root's diag(R, R)
  if constexpr (N == 6) {
    const Eigen::Quaterniond q(Eigen::Vector4d(random_vec6(rng).head<4>()).normalized());
    S.setZero();
    S.template topLeftCorner<3, 3>() = q.toRotationMatrix();
    S.template bottomRightCorner<3, 3>() = q.toRotationMatrix();
  } else {
    for (int c = 0; c < N; ++c) S.col(c) = random_vec6(rng);
  }
  const double armature = 0.01 * (k % 7);
  const Mat6K<N> U = IA * S;
  const MatK<N> D = S.transpose() * U + armature * MatK<N>::Identity();
  MatK<N> D_inv = D.inverse();
  D_inv = (0.5 * (D_inv + D_inv.transpose())).eval();  // symmetric to the bit, as the lanes'
  const Mat6 P = Mat6::Identity() - S * D_inv * U.transpose();
  const Mat6 expected = S * D_inv * S.transpose() + P * T * P.transpose();
  const MatK<N> expected_Minv = D_inv + D_inv * U.transpose() * T * U * D_inv;
  const Mat6K<N> expected_W = T * U;
  const double scale = expected.norm() + T.norm();

  const response_law::Columns<double> S_cols{S.data()};
  const RowMajor<N> D_rows{D_inv.data()};
  FullSymmetric L{Mat6::Zero()};
  Mat6K<N> W;
  MatK<N> Minv;
  response_law::response_n<N>(FullSymmetric{T}, S_cols, U.data(), D_rows, W.data(), Minv.data(), L);
  EXPECT_LT((L.m - expected).norm(), 1e-12 * scale) << N << ", " << k;
  EXPECT_LT((Minv - expected_Minv).norm(), 1e-12 * expected_Minv.norm()) << N << ", " << k;
  EXPECT_LE((W - expected_W).norm(), 1e-12 * (T.norm() * U.norm())) << N << ", " << k;

  // The packed 21 take the same operations on the upper triangle: the same bits.
  PackedSymmetric packed;
  Mat6K<N> W_packed;
  MatK<N> Minv_packed;
  response_law::response_n<N>(pack(T), S_cols, U.data(), D_rows, W_packed.data(),
                              Minv_packed.data(), packed);
  EXPECT_TRUE(W_packed == W);
  EXPECT_TRUE(Minv_packed == Minv);
  for (int a = 0; a < 6; ++a)
    for (int b = a; b < 6; ++b) EXPECT_EQ(packed(a, b), L.m(a, b)) << a << ", " << b;

  // On the world (T = 0) R10 drops terms that are exactly zero: the same bits as R6-R9's
  // Lambda, which is S D^-1 S^T; W = 0 and (M^-1)_ii = D^-1 exactly.
  if (k % 10 != 0) return;
  FullSymmetric world{Mat6::Zero()};
  response_law::world_response<N, double>(S_cols, D_rows, world);
  EXPECT_TRUE(world.m == L.m) << N << ", " << k;
  EXPECT_TRUE(Minv == D_inv) << N << ", " << k;
  EXPECT_TRUE(W.isZero(0.0)) << N << ", " << k;
}

TEST(ResponseLaw, MultiDofIsTheProjectedParentResponse) {
  std::mt19937_64 rng(23);
  for (int k = 0; k < 200; ++k) {
    check_multi_dof<3>(rng, k);
    check_multi_dof<6>(rng, k);
  }
}

// A floating root's S = diag(R, R): the sums that skip its zero blocks give the bits of those
// over all six columns (a zero product added changes nothing), and S D^-1 S^T.
TEST(ResponseLaw, FloatingRootSkipsTheZeroBlocks) {
  std::mt19937_64 rng(24);
  for (int k = 0; k < 50; ++k) {
    const Eigen::Quaterniond q(Eigen::Vector4d(random_vec6(rng).head<4>()).normalized());
    const Eigen::Matrix<double, 3, 3, Eigen::RowMajor> R = q.toRotationMatrix();
    Mat6 S = Mat6::Zero();
    S.topLeftCorner<3, 3>() = R;
    S.bottomRightCorner<3, 3>() = R;
    MatK<6> D_inv = random_spd(rng).inverse();
    D_inv = (0.5 * (D_inv + D_inv.transpose())).eval();
    FullSymmetric skipped{Mat6::Zero()}, dense{Mat6::Zero()};
    // diag(R, R) from R alone, as the lanes' root_response reads it: its sums skip the zeros.
    response_law::world_response<6, double>(multi_dof_law::RotationPair<double>{R.data()},
                                            RowMajor<6>{D_inv.data()}, skipped);
    response_law::world_response<6, double>(response_law::Columns<double>{S.data()},
                                             RowMajor<6>{D_inv.data()}, dense);
    EXPECT_TRUE(skipped.m == dense.m) << k;
    const Mat6 expected = S * D_inv * S.transpose();
    EXPECT_LT((skipped.m - expected).norm(), 1e-13 * expected.norm()) << k;
  }
}

}  // namespace
}  // namespace featherdrive::test
