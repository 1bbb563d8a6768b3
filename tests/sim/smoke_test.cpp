#include <gtest/gtest.h>

#include "featherdrive/sim/simulation.hpp"
#include "support/models.hpp"

namespace featherdrive {
TEST(Smoke, PendulumSteps) {
  auto model = test::make_pendulum(1.0, 1.0);
  Simulation sim(model);
  VecX q(1);
  q << 0.1;
  sim.set_q(q);
  sim.step(10);
  EXPECT_TRUE(sim.q().allFinite());
}
}  // namespace featherdrive
