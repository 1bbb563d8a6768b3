// sweep_law (a link's part of the Gauss-Seidel sweep, docs/math/implicit_drives.md eq. SW0-SW14,
// GS1-GS3) and the sweep built on it: SW0's sum against Eigen's 6-vector product, bit for bit (the
// scalar step's bits rest on it), the hand-over (SW12-SW14) through Eigen's expressions and entry
// by entry against the same sums written out, bit for bit, and every row's velocity in a sweep of given impulses on random
// trees against the dense joint-space inertia: q̇ + M^-1 (the impulses applied before it), as
// "Propagating impulses" claims; every link's velocity change when entered (SW2, SW8) against
// the sum of its path's S_j M^-1 (the impulses so far), with external impulses on the links that
// the leaving (SW3, SW9) and finishing (SW4, SW5, SW10, SW11) must carry.
#include "featherdrive/solver/sweep_law.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "featherdrive/algorithm/aba.hpp"
#include "featherdrive/algorithm/crba.hpp"
#include "featherdrive/algorithm/inverse_mass_diagonal.hpp"
#include "featherdrive/algorithm/kinematics.hpp"
#include "featherdrive/solver/gauss_seidel.hpp"
#include "support/models.hpp"

namespace featherdrive {
namespace {

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

TEST(SweepLaw, SumIsEigensSixVectorProduct) {  // SW0
#ifdef EIGEN_VECTORIZE_AVX
  GTEST_SKIP() << "Eigen sums a 6-vector in 4- and 2-wide packets with AVX: another order";
#endif
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0), e(-3.0, 3.0);
  int differ_from_left_to_right = 0;
  for (int k = 0; k < 20000; ++k) {
    Vec6 a, b;
    for (int r = 0; r < 6; ++r) a[r] = u(rng) * std::pow(10.0, e(rng)), b[r] = u(rng);
    // The lanes' path: entries through operator[] of plain arrays.
    const double law = sweep_law::dot6<double>(a.data(), b.data());
    EXPECT_TRUE(same_bits(law, a.dot(b))) << k;
    EXPECT_TRUE(same_bits(law, sweep_law::dot6<double>(a, b))) << k;
    double left = 0.0;
    for (int r = 0; r < 6; ++r) left += a[r] * b[r];
    differ_from_left_to_right += !same_bits(law, left);
  }
  // Not vacuous: another order differs in the last bit often.
  EXPECT_GT(differ_from_left_to_right, 1000);
}

// The hand-over to the parent (SW3, SW12-SW14): the scalar step's Eigen vectors and the lanes'
// entry-by-entry path (plain arrays here) against the sums written out, rows of Lambda pa left to
// right.
TEST(SweepLaw, HandOverIsTheSameSumsEitherWay) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0), e(-3.0, 3.0);
  auto draw = [&] {
    Vec6 x;
    for (int r = 0; r < 6; ++r) x[r] = u(rng) * std::pow(10.0, e(rng));
    return x;
  };
  int differ_from_pairs = 0;
  for (int k = 0; k < 5000; ++k) {
    const Vec6 pA = draw(), U = draw(), start = draw(), dv0 = draw();
    const double beta = u(rng);
    Mat6 Lambda;
    for (int c = 0; c < 6; ++c) Lambda.col(c) = draw();
    const bool first = k % 2 == 0;
    Vec6 pa, parent, dv;  // written out
    for (int r = 0; r < 6; ++r) pa[r] = pA[r] + beta * U[r];
    for (int r = 0; r < 6; ++r) parent[r] = first ? pa[r] : start[r] + pa[r];
    for (int r = 0; r < 6; ++r) {
      double sum = Lambda(r, 0) * pa[0];
      for (int c = 1; c < 6; ++c) sum += Lambda(r, c) * pa[c];
      dv[r] = dv0[r] - sum;
    }
    // A pairwise order, as a check that the row order is seen: it differs in the last bit often.
    const double pairs = (Lambda(0, 0) * pa[0] + Lambda(0, 1) * pa[1]) +
                         ((Lambda(0, 2) * pa[2] + Lambda(0, 3) * pa[3]) +
                          (Lambda(0, 4) * pa[4] + Lambda(0, 5) * pa[5]));
    differ_from_pairs += !same_bits(dv0[0] - pairs, dv[0]);
    // Eigen's.
    Vec6 parent_e = start, after_e = Vec6::Zero(), dv_e = dv0;
    const auto pa_e = sweep_law::handed(pA, beta, U);
    sweep_law::hand_over<double>(pa_e, first, parent_e);
    sweep_law::record_after<double>(parent_e, after_e);
    sweep_law::correct_parent<double>(Lambda, Vec6(pa_e), dv_e);
    // Entry by entry.
    double parent_a[6], after_a[6], dv_a[6], pa_a[6];
    for (int r = 0; r < 6; ++r) parent_a[r] = start[r], dv_a[r] = dv0[r];
    const auto pa_h = sweep_law::handed(pA.data(), beta, U.data());
    for (int r = 0; r < 6; ++r) pa_a[r] = pa_h[r];
    sweep_law::hand_over<double>(pa_h, first, parent_a);
    sweep_law::record_after<double>(parent_a, after_a);
    sweep_law::correct_parent<double>([&](int r, int c) { return Lambda(r, c); }, pa_a, dv_a);
    for (int r = 0; r < 6; ++r) {
      EXPECT_TRUE(same_bits(pa_a[r], pa[r])) << k;
      EXPECT_TRUE(same_bits(parent_e[r], parent[r])) << k;
      EXPECT_TRUE(same_bits(parent_a[r], parent[r])) << k;
      EXPECT_TRUE(same_bits(after_e[r], parent[r])) << k;
      EXPECT_TRUE(same_bits(after_a[r], parent[r])) << k;
      EXPECT_TRUE(same_bits(dv_e[r], dv[r])) << k;
      EXPECT_TRUE(same_bits(dv_a[r], dv[r])) << k;
    }
  }
  EXPECT_GT(differ_from_pairs, 100);
}

// A sweep whose rows apply given impulses: each row sees q̇ + M^-1 (the impulses before it in
// the sweep's order, its own dof's earlier axes included), and q̇ ends at q̇ + M^-1 impulses.
TEST(SweepLaw, RowsSeeTheDenseResponseToEarlierImpulses) {
  for (unsigned seed = 1; seed <= 6; ++seed)
    for (const bool floating : {false, true}) {
      auto model = test::make_random_tree(seed, 14, floating, true, 0.02);
      std::mt19937 rng(seed);
      const VecX q = test::random_configuration(*model, rng);
      Data data(*model);
      const MatX M = crba(*model, data, q);
      inverse_mass_diagonal(*model, data, q);  // kinematics, articulated inertias, response
      const Eigen::LDLT<MatX> M_inv(M);
      SweepWorkspace ws(*model);
      std::uniform_real_distribution<double> u(-1.0, 1.0);
      VecX given(model->nv), qd0(model->nv);
      for (int d = 0; d < model->nv; ++d) given[d] = u(rng), qd0[d] = u(rng);
      // A floating root's dofs take no rows: the sweep finishes them after the others.
      for (int d = 0; d < model->nv; ++d) ws.has_rows[d] = !(floating && d < 6);
      VecX applied = VecX::Zero(model->nv), qd = qd0;
      double worst = 0.0;
      int rows = 0;
      gauss_seidel_sweep(*model, data, ws, qd, [&](int d, double current) {
        const VecX expected = qd0 + M_inv.solve(applied);
        worst = std::max(worst, std::abs(current - expected[d]) / (1.0 + std::abs(expected[d])));
        applied[d] = given[d];
        ++rows;
        return given[d];
      });
      EXPECT_EQ(rows, model->nv - (floating ? 6 : 0));
      EXPECT_LT(worst, 1e-12) << "seed " << seed << (floating ? ", floating" : ", fixed");
      const VecX expected = qd0 + M_inv.solve(applied);
      EXPECT_LT((qd - expected).cwiseAbs().maxCoeff() / (1.0 + expected.cwiseAbs().maxCoeff()),
                1e-12)
          << "seed " << seed << (floating ? ", floating" : ", fixed");
    }
}

// Every link's velocity change when its rows are done, Delta v_i = sum over j on its path to the
// root of S_j (M^-1 applied)_j, and every row's and the final velocities against the dense
// response, with a random spatial impulse f_i on each link right after its rows (the sweep's
// contact hook: the generalized impulse J_i^T f_i = S_j^T f_i at each joint j on its path). On
// random trees with spherical joints, fixed and floating, with and without rows at the floating
// root's dofs (then its six dofs go the way of a spherical joint's three).
TEST(SweepLaw, LinkVelocityChangesAreTheDenseResponse) {
  for (unsigned seed = 1; seed <= 6; ++seed)
    for (const int root : {0, 1, 2}) {  // fixed; floating, its dofs rowless; floating with rows
      const bool floating = root > 0;
      auto model = test::make_random_tree(seed + 10, 12, floating, true, 0.02);
      std::mt19937 rng(seed);
      const VecX q = test::random_configuration(*model, rng);
      Data data(*model);
      const MatX M = crba(*model, data, q);
      inverse_mass_diagonal(*model, data, q);
      const Eigen::LDLT<MatX> M_inv(M);
      const int n = model->num_links(), nv = model->nv;
      // S_i in frame 0 as a 6 x nv block of the link's own columns.
      auto S_of = [&](int i) {
        MatX S = MatX::Zero(6, nv);
        const int v0 = model->links[i].v_index, k = model->links[i].nv;
        if (k == 1)
          S.col(v0) = data.one_dof[i].S;
        else if (k == 3)
          S.middleCols(v0, k) = data.motion_subspace[i];
        else if (k == 6)  // the floating root's diag(R, R): its origin is frame 0's
          S.block<3, 3>(0, v0) = S.block<3, 3>(3, v0 + 3) = data.world_rotation[i];
        return S;
      };
      std::vector<MatX> J(n);  // the link's Jacobian in frame 0: its path's S
      for (int i = 0; i < n; ++i) {
        const int p = model->links[i].parent;
        J[i] = (p >= 0 ? J[p] : MatX::Zero(6, nv)) + S_of(i);
      }
      SweepWorkspace ws(*model);
      ws.set_contact_links(std::vector<char>(n, 1));
      std::uniform_real_distribution<double> u(-1.0, 1.0);
      VecX given(nv), qd0(nv);
      for (int d = 0; d < nv; ++d) given[d] = u(rng), qd0[d] = u(rng);
      for (int d = 0; d < nv; ++d) ws.has_rows[d] = !(root == 1 && d < 6);
      VecX applied = VecX::Zero(nv), qd = qd0;
      double worst_row = 0.0, worst_link = 0.0;
      int links = 0;
      auto relative = [](const VecX& a, const VecX& b) {
        return (a - b).cwiseAbs().maxCoeff() / (1.0 + b.cwiseAbs().maxCoeff());
      };
      gauss_seidel_sweep(
          *model, data, ws, qd,
          [&](int d, double current) {
            const VecX expected = qd0 + M_inv.solve(applied);
            worst_row = std::max(worst_row,
                                 std::abs(current - expected[d]) / (1.0 + std::abs(expected[d])));
            applied[d] += given[d];
            return given[d];
          },
          [&](int i, Vec6& dv) {
            worst_link = std::max(worst_link, relative(dv, J[i] * M_inv.solve(applied)));
            Vec6 f;
            for (int r = 0; r < 6; ++r) f[r] = u(rng);
            applied += J[i].transpose() * f;
            dv = J[i] * M_inv.solve(applied);  // its own impulse's change added, as contacts do
            ++links;
            return f;
          });
      const std::string where = "seed " + std::to_string(seed) + ", root " + std::to_string(root);
      EXPECT_EQ(links, n) << where;
      EXPECT_LT(worst_link, 1e-12) << where;
      EXPECT_LT(worst_row, 1e-12) << where;
      EXPECT_LT(relative(qd, qd0 + M_inv.solve(applied)), 1e-12) << where;
    }
}

}  // namespace
}  // namespace featherdrive
