// Passive motion without drives: momentum conservation. The pendulum's period and the chain's
// energy drift, 100 000 steps each, run in the Release build (tests/peers/long_runs_test.cpp).
#include <gtest/gtest.h>

#include <cmath>

#include "featherdrive/algorithm/aba.hpp"
#include "featherdrive/algorithm/energy.hpp"
#include "featherdrive/algorithm/joint_motion.hpp"
#include "featherdrive/algorithm/kinematics.hpp"
#include "featherdrive/sim/simulation.hpp"
#include "support/models.hpp"

namespace featherdrive {
namespace {

// Without gravity a free-floating tree's momentum h = A(q) v is constant: dh/dt = 0 along the
// dynamics. Checked by a central difference of h along (qdot, qdd) from ABA, which is independent of
// how ABA computes qdd.
TEST(Passive, FloatingTreeDynamicsConserveMomentum) {
  for (unsigned seed : {3u, 11u, 42u, 77u}) {
    Model zero_g = *test::make_random_tree(seed, 8 + static_cast<int>(seed % 7), true, true, 0.0);
    zero_g.gravity = Vec3::Zero();
    Data data(zero_g);
    std::mt19937 rng(seed);
    const VecX q = test::random_configuration(zero_g, rng);
    const VecX v = test::random_vector(zero_g.nv, rng, 1.0);
    const VecX qdd = aba(zero_g, data, q, v, VecX::Zero(zero_g.nv));
    const double eps = 1e-5;
    auto h_at = [&](double s) {
      VecX qs(zero_g.nq);
      integrate_configuration(zero_g, q, v, s, qs);  // q(t + s) to first order
      const VecX vs = v + s * qdd;
      forward_kinematics(zero_g, data, qs, vs);
      return momentum(zero_g, data);
    };
    // The configuration path q + s v is only first-order accurate, but dh/dt needs only the
    // tangent: h(q(s), v(s)) with q'(0) = v, v'(0) = qdd.
    const Vec6 dh = (h_at(eps) - h_at(-eps)) / (2 * eps);
    const Vec6 h = h_at(0.0);
    EXPECT_LT(dh.norm(), 1e-9 * (1.0 + h.norm())) << "seed " << seed << " dh/dt = " << dh.transpose();
  }
}

// Semi-implicit Euler does not keep a free-floating robot's momentum exactly: the velocity update at
// q0 and the position update each change it at first order, and the two cancel only to O(dt^2) per
// step (../shared/physx/NOTES.md). The drift over a fixed time is therefore first order in dt.
TEST(Passive, FloatingTreeMomentumDriftIsFirstOrderInDt) {
  Model zero_g = *test::make_random_tree(5, 8, true, true, 0.0);
  zero_g.gravity = Vec3::Zero();
  auto model = std::make_shared<const Model>(zero_g);
  std::mt19937 rng(5);
  const VecX q0 = test::random_configuration(*model, rng);
  const VecX v0 = test::random_vector(model->nv, rng, 1.0);
  Data data(*model);
  forward_kinematics(*model, data, q0, v0);
  const Vec6 h0 = momentum(*model, data);
  auto drift = [&](double dt) {
    SimulationOptions o;
    o.dt = dt;
    Simulation sim(model, o);
    sim.set_q(q0);
    sim.set_qd(v0);
    sim.step(static_cast<int>(std::lround(0.5 / dt)));
    forward_kinematics(*model, data, sim.q(), sim.qd());
    return (momentum(*model, data) - h0).norm();
  };
  const double d1 = drift(1e-3), d2 = drift(5e-4), d3 = drift(2.5e-4);
  EXPECT_NEAR(d1 / d2, 2.0, 0.2);
  EXPECT_NEAR(d2 / d3, 2.0, 0.2);
}

}  // namespace
}  // namespace featherdrive
