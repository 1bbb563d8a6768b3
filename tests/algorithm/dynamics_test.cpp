// Cross-algorithm identities on random trees (after Pinocchio's unittest/aba.cpp): ABA against
// RNEA and against CRBA, and the O(n) diag(M^-1) against the dense inverse.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include "featherdrive/algorithm/aba.hpp"
#include "featherdrive/algorithm/crba.hpp"
#include "featherdrive/algorithm/inverse_mass_diagonal.hpp"
#include "featherdrive/algorithm/rnea.hpp"
#include "support/models.hpp"

namespace featherdrive {
namespace {

struct TreeCase {
  unsigned seed;
  int links;
  bool floating;
  double armature;
};

class RandomTree : public ::testing::TestWithParam<TreeCase> {};

TEST_P(RandomTree, AbaInvertsRnea) {
  const TreeCase c = GetParam();
  auto model = test::make_random_tree(c.seed, c.links, c.floating, true, c.armature);
  Data data(*model);
  std::mt19937 rng(c.seed + 1000);
  for (int trial = 0; trial < 3; ++trial) {
    const VecX q = test::random_configuration(*model, rng);
    const VecX v = test::random_vector(model->nv, rng, 2.0);
    const VecX a = test::random_vector(model->nv, rng, 3.0);
    const VecX tau = rnea(*model, data, q, v, a);
    const VecX a2 = aba(*model, data, q, v, tau);
    EXPECT_LT((a2 - a).norm(), 1e-10 * (1.0 + a.norm())) << "seed " << c.seed;
  }
}

TEST_P(RandomTree, AbaEqualsInverseMassTimesForces) {
  const TreeCase c = GetParam();
  auto model = test::make_random_tree(c.seed, c.links, c.floating, true, c.armature);
  Data data(*model);
  std::mt19937 rng(c.seed + 2000);
  const VecX q = test::random_configuration(*model, rng);
  const VecX v = test::random_vector(model->nv, rng, 2.0);
  const VecX tau = test::random_vector(model->nv, rng, 5.0);
  const VecX bias = rnea(*model, data, q, v, VecX::Zero(model->nv));  // c(q, v) - g(q)
  const MatX M = crba(*model, data, q);
  const VecX expected = M.lu().solve(tau - bias);
  const VecX qdd = aba(*model, data, q, v, tau);
  EXPECT_LT((qdd - expected).norm(), 1e-10 * (1.0 + expected.norm()));
  // The step's form (step.cpp) on the kinematics aba left: ABA's first two passes, then its third
  // with the response in one pass; (M^-1)_jj too.
  articulated_bodies(*model, data, v, tau);
  const VecX qdd_step = accelerations_and_response(*model, data);
  EXPECT_LT((qdd_step - expected).norm(), 1e-10 * (1.0 + expected.norm()));
  const MatX Minv = M.inverse();
  for (int j = 0; j < model->nv; ++j)
    EXPECT_NEAR(data.inverse_mass_diagonal[j], Minv(j, j), 1e-10 * std::abs(Minv(j, j)))
        << "dof " << j;
  // M is symmetric positive definite.
  EXPECT_LT((M - M.transpose()).norm(), 1e-12 * M.norm());
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<MatX>(M).eigenvalues().minCoeff(), 0.0);
}

TEST_P(RandomTree, InverseMassDiagonalEqualsDenseInverse) {
  const TreeCase c = GetParam();
  auto model = test::make_random_tree(c.seed, c.links, c.floating, true, c.armature);
  Data data(*model);
  std::mt19937 rng(c.seed + 3000);
  const VecX q = test::random_configuration(*model, rng);
  const MatX Minv = crba(*model, data, q).inverse();
  const VecX diag = inverse_mass_diagonal(*model, data, q);
  for (int j = 0; j < model->nv; ++j)
    EXPECT_NEAR(diag[j], Minv(j, j), 1e-10 * std::abs(Minv(j, j))) << "dof " << j;
  // The diagonal blocks too (used by the solver for multi-dof joints).
  for (int i = 0; i < model->num_links(); ++i) {
    const Link& l = model->links[i];
    if (l.nv == 0) continue;
    const MatX block = Minv.block(l.v_index, l.v_index, l.nv, l.nv);
    EXPECT_LT((data.inverse_mass_block[i] - block).norm(), 1e-10 * block.norm()) << "link " << i;
  }
}

std::vector<TreeCase> tree_cases() {
  std::vector<TreeCase> cases;
  const int sizes[] = {2, 5, 9, 14, 20, 30};
  unsigned seed = 1;
  for (int n : sizes)
    for (bool floating : {false, true}) {
      cases.push_back({seed++, n, floating, 0.0});
      cases.push_back({seed++, n, floating, 0.05});
    }
  return cases;  // 24 trees
}

INSTANTIATE_TEST_SUITE_P(Trees, RandomTree, ::testing::ValuesIn(tree_cases()),
                         [](const auto& p) {
                           const TreeCase& c = p.param;
                           return "seed" + std::to_string(c.seed) + "_n" + std::to_string(c.links) +
                                  (c.floating ? "_floating" : "_fixed") +
                                  (c.armature > 0 ? "_armature" : "");
                         });

}  // namespace
}  // namespace featherdrive
