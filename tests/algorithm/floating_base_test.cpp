// A floating root placed in world axes (algorithm/floating_base.hpp): forward kinematics, a second
// algorithm, finds the link where it was put, moving as it was told, whatever the root's joint
// frame; a free body so placed flies the discrete ballistic arc of the step (docs/conventions.md,
// "Floating").
#include "featherdrive/algorithm/floating_base.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "featherdrive/algorithm/frame_kinematics.hpp"
#include "featherdrive/algorithm/kinematics.hpp"
#include "featherdrive/model/model_builder.hpp"
#include "featherdrive/sim/simulation.hpp"
#include "support/models.hpp"

namespace featherdrive {
namespace {

BaseState random_base(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  BaseState b;
  b.position = Vec3(n(rng), n(rng), n(rng));
  b.orientation = Quat(n(rng), n(rng), n(rng), n(rng));  // not unit: normalised
  b.linear_velocity = Vec3(n(rng), n(rng), n(rng));
  b.angular_velocity = Vec3(n(rng), n(rng), n(rng));
  return b;
}

TEST(FloatingBase, KinematicsFindsTheRootWhereItWasPut) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 20; ++trial) {
    Model model = *test::make_random_tree(100 + trial, 4, true);
    if (trial % 2) {  // a root joint frame off the world
      const Quat frame = Quat(Eigen::Vector4d(test::random_vector(4, rng))).normalized();
      model.links[0].tree_transform =
          Transform::from_pose(frame.toRotationMatrix(), test::random_vector(3, rng));
    }
    VecX q = test::random_configuration(model, rng), qd = test::random_vector(model.nv, rng);
    const VecX joints_q = q.tail(model.nq - 7), joints_qd = qd.tail(model.nv - 6);
    const BaseState base = random_base(rng);
    set_base_state(model, base, q, qd);
    EXPECT_EQ(q.tail(model.nq - 7), joints_q);  // the other joints untouched
    EXPECT_EQ(qd.tail(model.nv - 6), joints_qd);
    Data data(model);
    forward_kinematics(model, data, q, qd);
    const Mat3 R = base.orientation.normalized().toRotationMatrix();
    EXPECT_LT((data.world_rotation[0] - R).norm(), 1e-13) << trial;
    EXPECT_LT((data.world_position[0] - base.position).norm(), 1e-13) << trial;
    const Vec6 v = link_velocity(model, data, 0, ReferenceFrame::world_aligned);
    EXPECT_LT((v.head<3>() - base.angular_velocity).norm(), 1e-13) << trial;
    EXPECT_LT((v.tail<3>() - base.linear_velocity).norm(), 1e-13) << trial;
    // And back.
    const BaseState read = base_state(model, q, qd);
    EXPECT_LT((read.position - base.position).norm(), 1e-13);
    EXPECT_LT(read.orientation.angularDistance(base.orientation.normalized()), 1e-12);
    EXPECT_LT((read.linear_velocity - base.linear_velocity).norm(), 1e-13);
    EXPECT_LT((read.angular_velocity - base.angular_velocity).norm(), 1e-13);
  }
}

// A free box without spin, its centre at the link origin, moves by the step's rule v <- v + h g,
// p <- p + h v: p_n = p_0 + n h v_0 + h^2 g n (n + 1) / 2, whatever the orientation it was given.
// Spinning or not, its origin (the centre of mass) follows the arc: the step integrates the
// classical velocity of a floating root's origin (docs/math/contact.md, C26-C28). Isotropic
// inertia keeps omega constant.
class FreeBody : public ::testing::TestWithParam<Vec3> {};

TEST_P(FreeBody, FliesTheDiscreteBallisticArc) {
  ModelBuilder b;
  b.set_gravity(Vec3(0.0, 0.0, -9.81));
  b.add_link(make_link("box", "", 2.0, Vec3::Zero(), 0.3 * Mat3::Identity(),
                       floating_joint("root")));
  const auto model = std::make_shared<const Model>(b.build());
  Simulation sim(model);
  BaseState base;
  base.position = Vec3(0.5, -1.0, 2.0);
  base.orientation = Quat(Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()));
  base.linear_velocity = Vec3(1.0, 0.5, 3.0);
  base.angular_velocity = GetParam();
  VecX q = sim.q(), qd = sim.qd();
  set_base_state(*model, base, q, qd);
  sim.set_q(q);
  sim.set_qd(qd);
  const double h = sim.options().dt;
  const Vec3 g = model->gravity;
  for (int n = 1; n <= 60; ++n) {
    sim.step();
    const BaseState now = base_state(*model, sim.q(), sim.qd());
    const Vec3 expected = base.position + n * h * base.linear_velocity + h * h * g * n * (n + 1) / 2;
    EXPECT_LT((now.position - expected).norm(), 1e-12) << n;
    EXPECT_LT((now.linear_velocity - (base.linear_velocity + n * h * g)).norm(), 1e-12) << n;
    EXPECT_LT((now.angular_velocity - base.angular_velocity).norm(), 1e-12) << n;
    if (base.angular_velocity.norm() == 0.0)
      EXPECT_LT(now.orientation.angularDistance(base.orientation), 1e-12) << n;
  }
}

std::string spin_name(const ::testing::TestParamInfo<Vec3>& info) {
  const char* names[] = {"still", "tumbling", "spinning_10rad_s"};
  return names[info.index];
}

INSTANTIATE_TEST_SUITE_P(Spins, FreeBody,
                         ::testing::Values(Vec3::Zero(), Vec3(0.3, -2.0, 5.0), Vec3(0.0, 10.0, 0.0)),
                         spin_name);

TEST(FloatingBase, BadInputIsRefusedInOneLine) {
  const auto fixed = test::make_pendulum(1.0, 0.5);
  VecX q = VecX::Zero(fixed->nq), qd = VecX::Zero(fixed->nv);
  auto message = [](auto f) {
    try {
      f();
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_EQ(message([&] { set_base_state(*fixed, BaseState{}, q, qd); }),
            "set_base_state: the model has no floating root");
  EXPECT_EQ(message([&] { base_state(*fixed, q, qd); }),
            "base_state: the model has no floating root");
  const auto floating = test::make_random_tree(3, 3, true);
  VecX fq = floating->neutral_configuration(), fqd = VecX::Zero(floating->nv);
  BaseState zero;
  zero.orientation = Quat(0.0, 0.0, 0.0, 0.0);
  EXPECT_EQ(message([&] { set_base_state(*floating, zero, fq, fqd); }),
            "base orientation (w, x, y, z) = (0, 0, 0, 0) has no rotation: its norm must be "
            "finite and > 0");
  BaseState nan;
  nan.linear_velocity[1] = std::nan("");
  EXPECT_EQ(message([&] { set_base_state(*floating, nan, fq, fqd); }),
            "base linear_velocity[1] = nan is not finite");
  EXPECT_EQ(fq, floating->neutral_configuration());  // untouched
  VecX short_q = VecX::Zero(3);
  EXPECT_NE(message([&] { set_base_state(*floating, BaseState{}, short_q, fqd); }), "");
}

}  // namespace
}  // namespace featherdrive
