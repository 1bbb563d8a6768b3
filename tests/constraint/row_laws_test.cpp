// The position limit law against docs/math/joint_constraints.md's J2-J4 written out here, and
// its skip test (limit_may_act) against the law itself: where the test says the law cannot act,
// the law must change no sum it enters, bit for bit.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "featherdrive/constraint/row_laws.hpp"

namespace featherdrive {
namespace {

row_law::LimitPhase phase_of(double h, double erp, bool velocity_iteration) {
  return {h, 1.0 / h, erp, velocity_iteration};
}

// J2: inside, about to cross the lower limit in this step: the impulse that arrives exactly on it.
TEST(LimitLaw, SpeculativeLowerLimitIsJ2) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int k = 0; k < 1000; ++k) {
    const double h = 1e-3 + 1e-2 * u(rng), recip = 0.1 + 10.0 * u(rng);
    const double error_low = 1e-3 * u(rng) + 1e-6, dx = 0.0;
    const double v = -(error_low / h) * (1.5 + u(rng));  // crosses by the step's end
    double low = 0.0, high = 0.0;
    const double delta = row_law::limit(low, high, v, recip, error_low, 1.0, dx,
                                        phase_of(h, 0.8, false));
    const double expected = (-(error_low + dx) / h - v) * recip;  // (J2)
    EXPECT_NEAR(delta, expected, 1e-12 * std::abs(expected));
    EXPECT_EQ(low, delta);
    EXPECT_EQ(high, 0.0);
  }
}

// J3: past the upper limit in a position iteration: erp of the violation pulled back per step.
TEST(LimitLaw, ViolatedUpperLimitIsJ3) {
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int k = 0; k < 1000; ++k) {
    const double h = 1e-3 + 1e-2 * u(rng), recip = 0.1 + 10.0 * u(rng), erp = u(rng);
    const double error_high = -1e-3 * u(rng) - 1e-6;  // past it
    const double v = 0.5 * u(rng);                    // still moving out
    double low = 0.0, high = 0.0;
    const double delta = row_law::limit(low, high, v, recip, 1.0, error_high, 0.0,
                                        phase_of(h, erp, false));
    const double expected = std::min((error_high * erp / h - v) * recip, 0.0);  // (J3), <= 0
    EXPECT_NEAR(delta, expected, 1e-12 * std::abs(expected));
    EXPECT_EQ(high, delta);
  }
}

// Where limit_may_act is false the law leaves low and high at +0 and returns a zero, so a sum it
// enters keeps its bits; wherever the law changes anything, limit_may_act is true.
TEST(LimitLaw, SkipTestAgreesWithTheLaw) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int skipped = 0, acted = 0;
  for (int k = 0; k < 20000; ++k) {
    const double h = 1e-3 * (1.0 + std::abs(u(rng))), recip = 1.0 + std::abs(u(rng));
    const double v = u(rng), dx = k % 2 ? 0.0 : 1e-3 * u(rng);
    const double error_low = 2e-3 * u(rng) + 1e-3, error_high = 2e-3 * u(rng) + 1e-3;
    const bool accumulated = k % 5 == 0;
    double low = accumulated ? std::abs(u(rng)) : 0.0;
    double high = accumulated && k % 3 == 0 ? -std::abs(u(rng)) : 0.0;
    const double low0 = low, high0 = high;
    const auto phase = phase_of(h, 0.8, k % 7 == 0);
    const bool may_act = row_law::limit_may_act(low, high, v, error_low, error_high, dx, phase);
    // Its terms apart (the lanes test the ones in v alone where the others hold in no lane): past
    // a limit or an impulse left, whatever v; else the test is whether v crosses a limit.
    const bool held = row_law::limit_held(low, high, error_low, error_high, dx);
    EXPECT_EQ(held, error_low + dx < 0.0 || error_high - dx < 0.0 || low != 0.0 || high != 0.0);
    if (!held)
      EXPECT_EQ(may_act, row_law::limit_crossing(v, error_low, error_high, dx, phase)) << k;
    const double delta = row_law::limit(low, high, v, recip, error_low, error_high, dx, phase);
    const bool changed = delta != 0.0 || low != low0 || high != high0;
    if (changed) {
      EXPECT_TRUE(may_act) << k;
      ++acted;
    }
    if (!may_act) {
      ++skipped;
      EXPECT_EQ(delta, 0.0) << k;
      EXPECT_FALSE(std::signbit(low)) << k;
      EXPECT_FALSE(std::signbit(high)) << k;
      for (const double total : {0.0, 0.25}) {  // a dof's sum of impulse changes starts at +0
        EXPECT_EQ(total + delta, total);
        EXPECT_FALSE(std::signbit(total + delta));
      }
      EXPECT_EQ(v + recip * delta, v) << k;  // v is never 0 here
      EXPECT_EQ(std::signbit(v + recip * delta), std::signbit(v)) << k;
    }
  }
  EXPECT_GT(skipped, 1000);  // both kinds of sample were drawn
  EXPECT_GT(acted, 1000);
}

}  // namespace
}  // namespace featherdrive
