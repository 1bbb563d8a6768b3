// sweep_law (a one-dof link's part of the Gauss-Seidel sweep, docs/math/implicit_drives.md eq.
// SW0-SW5, GS1-GS3) and the sweep built on it: SW0's sum against Eigen's 6-vector product, bit
// for bit (the scalar step's bits rest on it), and every row's velocity in a sweep of given
// impulses on random trees against the dense joint-space inertia: q̇ + M^-1 (the impulses applied
// before it), as "Propagating impulses" claims.
#include "featherdrive/solver/sweep_law.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <random>
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

}  // namespace
}  // namespace featherdrive
