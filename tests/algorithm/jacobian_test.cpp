// Frame kinematics, Jacobians, their time variation, the centre of mass and the RNEA's bias and
// gravity terms against finite differences of poses and energies along the simulator's
// integrator (integrate_configuration: a floating base and spherical joints move by the
// exponential map), and against ABA. Random trees with fixed and floating roots.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "featherdrive/algorithm/aba.hpp"
#include "featherdrive/algorithm/center_of_mass.hpp"
#include "featherdrive/algorithm/crba.hpp"
#include "featherdrive/algorithm/energy.hpp"
#include "featherdrive/algorithm/jacobian.hpp"
#include "featherdrive/algorithm/joint_motion.hpp"
#include "featherdrive/algorithm/kinematics.hpp"
#include "featherdrive/algorithm/rnea.hpp"
#include "support/models.hpp"

namespace featherdrive {
namespace {

constexpr double kStep = 1e-5;  // central differences: truncation ~1e-10, rounding ~1e-11
constexpr double kTol = 1e-7;   // relative agreement with the differences

struct FrameCase {
  unsigned seed;
  int links;
  bool floating;
};

class Frames : public ::testing::TestWithParam<FrameCase> {
 protected:
  void SetUp() override {
    const FrameCase c = GetParam();
    model = test::make_random_tree(c.seed, c.links, c.floating, true, 0.05);
    data = std::make_unique<Data>(*model);
    std::mt19937 rng(c.seed + 77);
    q = test::random_configuration(*model, rng);
    v = test::random_vector(model->nv, rng, 1.5);
    point = test::random_vector(3, rng, 0.3);
  }
  // q (+) s * dq on the joints' manifolds, as the simulator integrates.
  VecX moved(const VecX& dq, double s) const {
    VecX out(model->nq);
    integrate_configuration(*model, q, dq, s, out);
    return out;
  }
  std::shared_ptr<const Model> model;
  std::unique_ptr<Data> data;
  VecX q, v;
  Vec3 point;
};

// The world-aligned velocity [omega; point velocity] of the frame at `point` on `link` while q
// moves along dq, from its poses at q (+) -h dq and q (+) h dq.
Vec6 differentiated_pose(const Model& model, Data& data, const VecX& q_minus, const VecX& q_plus,
                         int link, const Vec3& point) {
  forward_kinematics(model, data, q_plus);
  const Mat3 R_plus = data.world_rotation[link];
  const Vec3 p_plus = frame_position(model, data, link, point);
  forward_kinematics(model, data, q_minus);
  const Mat3 R_minus = data.world_rotation[link];
  const Vec3 p_minus = frame_position(model, data, link, point);
  const Eigen::AngleAxisd turn(R_plus * R_minus.transpose());  // world axes
  Vec6 out;
  out.head<3>() = turn.angle() * turn.axis() / (2 * kStep);
  out.tail<3>() = (p_plus - p_minus) / (2 * kStep);
  return out;
}

double relative_error(const MatX& a, const MatX& b) {
  return (a - b).norm() / (1.0 + b.norm());
}

TEST_P(Frames, JacobianColumnsAreDerivativesOfPoses) {
  const int nv = model->nv;
  MatX J_fd(6, nv), J_world, J_local, J_link;
  for (int link = 0; link < model->num_links(); ++link) {
    for (int k = 0; k < nv; ++k) {
      const VecX e = VecX::Unit(nv, k);
      J_fd.col(k) = differentiated_pose(*model, *data, moved(e, -kStep), moved(e, kStep), link,
                                        point);
    }
    forward_kinematics(*model, *data, q);
    frame_jacobian(*model, *data, link, point, ReferenceFrame::world_aligned, J_world);
    frame_jacobian(*model, *data, link, point, ReferenceFrame::local, J_local);
    EXPECT_LT(relative_error(J_world, J_fd), kTol) << "link " << link;
    // local = the world-aligned columns in the link's axes.
    const Mat3& R = data->world_rotation[link];
    MatX J_rotated(6, nv);
    if (nv > 0) {  // a block of a 6 x 0 matrix offsets its null data pointer (UBSan)
      J_rotated.topRows<3>() = R.transpose() * J_fd.topRows<3>();
      J_rotated.bottomRows<3>() = R.transpose() * J_fd.bottomRows<3>();
    }
    EXPECT_LT(relative_error(J_local, J_rotated), kTol) << "link " << link;
    // The link's own frame: the point 0; local columns times v are the kinematics' velocity.
    link_jacobian(*model, *data, link, ReferenceFrame::local, J_link);
    forward_kinematics(*model, *data, q, v);
    EXPECT_LT((J_link * v - data->velocity[link]).norm(), 1e-12 * (1.0 + v.norm()));
    EXPECT_LT((J_world * v - frame_velocity(*model, *data, link, point,
                                           ReferenceFrame::world_aligned)).norm(),
              1e-12 * (1.0 + J_world.norm() * v.norm()));
    EXPECT_LT((J_local * v - frame_velocity(*model, *data, link, point, ReferenceFrame::local))
                  .norm(),
              1e-12 * (1.0 + J_local.norm() * v.norm()));
  }
}

TEST_P(Frames, JacobianDotTimesVIsDerivativeOfJacobianTimesV) {
  // Along q(t) = q (+) t v with v constant (qdd = 0): d/dt (J(q(t)) v) = dJ/dt v.
  const VecX q_plus = moved(v, kStep), q_minus = moved(v, -kStep);
  MatX J_plus, J_minus;
  for (ReferenceFrame reference : {ReferenceFrame::world_aligned, ReferenceFrame::local}) {
    for (int link = 0; link < model->num_links(); ++link) {
      forward_kinematics(*model, *data, q_plus);
      frame_jacobian(*model, *data, link, point, reference, J_plus);
      forward_kinematics(*model, *data, q_minus);
      frame_jacobian(*model, *data, link, point, reference, J_minus);
      const Vec6 expected = (J_plus - J_minus) * v / (2 * kStep);
      forward_kinematics(*model, *data, q, v);
      const Vec6 got = jacobian_dot_times_v(*model, *data, link, point, reference);
      EXPECT_LT((got - expected).norm(), kTol * (1.0 + expected.norm()))
          << "link " << link << (reference == ReferenceFrame::local ? " local" : " world");
    }
  }
}

TEST_P(Frames, CenterOfMassIsMassWeightedSumOfLinkCentres) {
  forward_kinematics(*model, *data, q, v);
  Vec3 moment = Vec3::Zero(), momentum = Vec3::Zero();
  double mass = 0.0;
  MatX J_sum = MatX::Zero(3, model->nv), J_point;
  for (int i = 0; i < model->num_links(); ++i) {
    const Link& l = model->links[i];
    mass += l.mass;
    moment += l.mass * frame_position(*model, *data, i, l.com);
    momentum += l.mass * frame_velocity(*model, *data, i, l.com, ReferenceFrame::world_aligned)
                             .tail<3>();
    frame_jacobian(*model, *data, i, l.com, ReferenceFrame::world_aligned, J_point);
    if (model->nv > 0) J_sum += l.mass * J_point.bottomRows<3>();  // (no block of 6 x 0: UBSan)
  }
  const Vec3 com = center_of_mass(*model, *data);
  EXPECT_LT((com - moment / mass).norm(), 1e-12 * (1.0 + com.norm()));
  EXPECT_LT((center_of_mass_velocity(*model, *data) - momentum / mass).norm(),
            1e-12 * (1.0 + momentum.norm() / mass));
  MatX J_com;
  center_of_mass_jacobian(*model, *data, J_com);
  EXPECT_LT(relative_error(J_com, J_sum / mass), 1e-12);
  EXPECT_LT((J_com * v - center_of_mass_velocity(*model, *data)).norm(), 1e-12 * (1 + v.norm()));
  // Against differences of the centre of mass.
  MatX J_fd(3, model->nv);
  for (int k = 0; k < model->nv; ++k) {
    const VecX e = VecX::Unit(model->nv, k);
    forward_kinematics(*model, *data, moved(e, kStep));
    const Vec3 plus = center_of_mass(*model, *data);
    forward_kinematics(*model, *data, moved(e, -kStep));
    J_fd.col(k) = (plus - center_of_mass(*model, *data)) / (2 * kStep);
  }
  EXPECT_LT(relative_error(J_com, J_fd), kTol);
}

TEST_P(Frames, MassMatrixColumnsAreAbaResponses) {
  // M^-1 e_k is ABA's acceleration under tau = e_k at rest without gravity.
  Model still = *model;
  still.gravity.setZero();
  const MatX M = crba(still, *data, q);
  const VecX zero = VecX::Zero(still.nv);
  MatX M_inv(still.nv, still.nv);
  for (int k = 0; k < still.nv; ++k)
    M_inv.col(k) = aba(still, *data, q, zero, VecX::Unit(still.nv, k));
  EXPECT_LT((M * M_inv - MatX::Identity(still.nv, still.nv)).norm(), 1e-9);
  EXPECT_LE((M - M.transpose()).norm(), 1e-12 * M.norm());
}

TEST_P(Frames, BiasAndGravityForcesGiveZeroAcceleration) {
  // tau = b(q, v) holds qdd at 0; tau = g(q) holds the robot still.
  const VecX b = nonlinear_effects(*model, *data, q, v);
  const VecX zero = VecX::Zero(model->nv);
  EXPECT_LT(aba(*model, *data, q, v, b).norm(), 1e-10 * (1.0 + b.norm()));
  const VecX g = generalized_gravity(*model, *data, q);
  EXPECT_LT(aba(*model, *data, q, zero, g).norm(), 1e-10 * (1.0 + g.norm()));
  EXPECT_LT((b - rnea(*model, *data, q, v, zero)).norm(), 1e-13 * (1.0 + b.norm()));
  // Inverse dynamics round trip: aba(q, v, rnea(q, v, a)) = a.
  std::mt19937 rng(GetParam().seed);
  const VecX a = test::random_vector(model->nv, rng, 3.0);
  const VecX tau = rnea(*model, *data, q, v, a);
  EXPECT_LT((aba(*model, *data, q, v, tau) - a).norm(), 1e-10 * (1.0 + a.norm()));
}

TEST_P(Frames, GravityIsGradientOfPotentialEnergy) {
  VecX grad(model->nv);
  for (int k = 0; k < model->nv; ++k) {
    const VecX e = VecX::Unit(model->nv, k);
    forward_kinematics(*model, *data, moved(e, kStep));
    const double plus = potential_energy(*model, *data);
    forward_kinematics(*model, *data, moved(e, -kStep));
    grad[k] = (plus - potential_energy(*model, *data)) / (2 * kStep);
  }
  const VecX g = generalized_gravity(*model, *data, q);
  EXPECT_LT((g - grad).norm(), kTol * (1.0 + grad.norm()));
}

TEST_P(Frames, CoriolisPowerIsHalfMassMatrixRate) {
  // v^T (b - g) = v^T C v = 1/2 v^T dM/dt v (dM/dt - 2C is skew; Featherstone 2008, sec. 1.6).
  const VecX b = nonlinear_effects(*model, *data, q, v);  // copies: both return data.tau
  const VecX c = b - generalized_gravity(*model, *data, q);
  const MatX M_plus = crba(*model, *data, moved(v, kStep));
  const MatX M_minus = crba(*model, *data, moved(v, -kStep));
  const double rate = 0.5 * v.dot((M_plus - M_minus) * v) / (2 * kStep);
  EXPECT_NEAR(v.dot(c), rate, kTol * (1.0 + std::abs(rate)));
}

std::vector<FrameCase> cases() {
  std::vector<FrameCase> out;
  unsigned seed = 301;
  for (int n : {1, 3, 7, 12, 20})
    for (bool floating : {false, true}) out.push_back({seed++, n, floating});
  return out;
}

INSTANTIATE_TEST_SUITE_P(Trees, Frames, ::testing::ValuesIn(cases()), [](const auto& p) {
  return "seed" + std::to_string(p.param.seed) + "_n" + std::to_string(p.param.links) +
         (p.param.floating ? "_floating" : "_fixed");
});

TEST(Frames, BadLinkIndexIsRefused) {
  auto model = test::make_random_tree(5, 4, false);
  Data data(*model);
  MatX J;
  try {
    frame_jacobian(*model, data, 4, Vec3::Zero(), ReferenceFrame::local, J);
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "link index 4 is out of range [0, 4)");
  }
  EXPECT_THROW(link_velocity(*model, data, -1, ReferenceFrame::local), std::invalid_argument);
  EXPECT_THROW(jacobian_dot_times_v(*model, data, 9, Vec3::Zero(), ReferenceFrame::local),
               std::invalid_argument);
  EXPECT_THROW(frame_position(*model, data, 4, Vec3::Zero()), std::invalid_argument);
}

}  // namespace
}  // namespace featherdrive
