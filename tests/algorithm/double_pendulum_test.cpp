// The double pendulum's M, Coriolis and gravity terms against the textbook closed form
// (two links with masses m1, m2, lengths l1, l2, centres of mass lc1, lc2 along each link, rotational
// inertias I1, I2 about the centres; angles measured from the downward vertical; see e.g.
// Spong, Hutchinson & Vidyasagar, "Robot Modeling and Control", sec. 7.3, with gravity along -z).
#include <gtest/gtest.h>

#include <cmath>

#include "featherdrive/algorithm/crba.hpp"
#include "featherdrive/algorithm/rnea.hpp"
#include "featherdrive/model/model_builder.hpp"

namespace featherdrive {
namespace {

TEST(DoublePendulum, MatchesClosedForm) {
  const double m1 = 1.3, m2 = 0.7, l1 = 0.9, lc1 = 0.4, lc2 = 0.35, I1 = 0.05, I2 = 0.03, g = 9.81;
  ModelBuilder b;
  b.set_gravity(Vec3(0, 0, -g));
  b.add_link(make_link("base", "", 1.0, Vec3::Zero(), Mat3::Identity(), fixed_joint("fix")));
  // Rotation about y; links hang along -z at q = 0. Inertia about y is the planar one.
  b.add_link(make_link("l1", "base", m1, Vec3(0, 0, -lc1), Vec3(I1, I1, I1).asDiagonal(),
                       revolute_joint("q1", Vec3::UnitY())));
  b.add_link(make_link("l2", "l1", m2, Vec3(0, 0, -lc2), Vec3(I2, I2, I2).asDiagonal(),
                       revolute_joint("q2", Vec3::UnitY(), Vec3(0, 0, -l1))));
  const Model model = b.build();
  Data data(model);
  for (double q1 : {0.0, 0.4, -1.2}) {
    for (double q2 : {0.0, 0.9, 2.5}) {
      const double qd1 = 0.7, qd2 = -1.3;
      VecX q(2), v(2);
      q << q1, q2;
      v << qd1, qd2;
      const double c2 = std::cos(q2), s2 = std::sin(q2);
      Eigen::Matrix2d M;
      M(0, 0) = m1 * lc1 * lc1 + m2 * (l1 * l1 + lc2 * lc2 + 2 * l1 * lc2 * c2) + I1 + I2;
      M(0, 1) = M(1, 0) = m2 * (lc2 * lc2 + l1 * lc2 * c2) + I2;
      M(1, 1) = m2 * lc2 * lc2 + I2;
      // Rotation about +y turns -z towards -x, so the bob's height is -l cos(q).
      const double h = -m2 * l1 * lc2 * s2;
      Eigen::Vector2d coriolis(h * (2 * qd1 * qd2 + qd2 * qd2), -h * qd1 * qd1);
      Eigen::Vector2d gravity((m1 * lc1 + m2 * l1) * g * std::sin(q1) + m2 * lc2 * g * std::sin(q1 + q2),
                              m2 * lc2 * g * std::sin(q1 + q2));
      const MatX Mf = crba(model, data, q);
      EXPECT_LT((Mf - M).norm(), 1e-12);
      const VecX bias = rnea(model, data, q, v, VecX::Zero(2));
      EXPECT_LT((bias - (coriolis + gravity)).norm(), 1e-12) << q1 << " " << q2;
      // Gravity alone.
      const VecX gq = rnea(model, data, q, VecX::Zero(2), VecX::Zero(2));
      EXPECT_LT((gq - gravity).norm(), 1e-12);
    }
  }
}

}  // namespace
}  // namespace featherdrive
