// sincos_inline against glibc's std::sin and std::cos (docs/math/sincos.md).
#include "featherdrive/spatial/sincos.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace featherdrive {
namespace {

// |a - ref| in units of ulp(ref), ulp taken at no less than `floor` (close to a zero of sin or
// cos the method's error is absolute, not relative: docs/math/sincos.md).
double ulp_distance(double a, double ref, double floor = 0.0) {
  const double m = std::max(std::abs(ref), floor);
  const double ulp = std::nextafter(m, std::numeric_limits<double>::infinity()) - m;
  return std::abs(a - ref) / ulp;
}

void expect_close(double x, double floor = 0.0) {
  double s = 0.0, c = 0.0;
  sincos_inline(x, s, c);
  EXPECT_LE(ulp_distance(s, std::sin(x), floor), 2.0) << "sin(" << x << ")";
  EXPECT_LE(ulp_distance(c, std::cos(x), floor), 2.0) << "cos(" << x << ")";
}

TEST(SincosInline, WithinTwoUlpOfGlibcOnRandomAngles) {
  std::mt19937_64 rng(21);
  for (const double range : {1.0, 4.0, 100.0, 1e4, 1e5}) {
    std::uniform_real_distribution<double> angle(-range, range);
    for (int k = 0; k < 200000; ++k) expect_close(angle(rng));
  }
}

TEST(SincosInline, WithinTwoUlpWhereTheQuadrantChanges) {
  // x = +-pi/4 + k pi/2 and its neighbours: the polynomial switches between sin r and cos r.
  for (int k = -1000; k <= 1000; ++k)
    for (const double offset : {-M_PI / 4, M_PI / 4}) {
      double x = k * M_PI / 2 + offset;
      x = std::nextafter(std::nextafter(x, -INFINITY), -INFINITY);
      for (int step = 0; step < 5; ++step, x = std::nextafter(x, INFINITY)) expect_close(x);
    }
}

TEST(SincosInline, AbsolutelyCloseNearZerosOfSinAndCos) {
  // x near k pi/2: sin or cos is tiny, and the reduction's error is absolute (below 1e-24).
  for (int k = -100000; k <= 100000; k += 7) {
    double x = k * (M_PI / 2);
    x = std::nextafter(std::nextafter(x, -INFINITY), -INFINITY);
    for (int step = 0; step < 5; ++step, x = std::nextafter(x, INFINITY)) {
      double s = 0.0, c = 0.0;
      sincos_inline(x, s, c);
      EXPECT_LE(std::abs(s - std::sin(x)), 1e-24) << x;
      EXPECT_LE(std::abs(c - std::cos(x)), 1e-24) << x;
      expect_close(x, 1e-6);
    }
  }
}

// Beyond 1e5 rad, and for inf and NaN, glibc's values (the fuzzer once gave it 1e300, whose
// quadrant overflowed a long long).
TEST(SincosInline, GlibcBeyondItsRange) {
  for (double x : {1e5 + 1.0, -3e7, 1e300, -1e300}) {
    double s = 0.0, c = 0.0;
    sincos_inline(x, s, c);
    EXPECT_EQ(s, std::sin(x)) << x;
    EXPECT_EQ(c, std::cos(x)) << x;
  }
  for (double x : {std::numeric_limits<double>::infinity(), std::nan("")}) {
    double s = 0.0, c = 0.0;
    sincos_inline(x, s, c);
    EXPECT_TRUE(std::isnan(s) && std::isnan(c)) << x;
  }
}

TEST(SincosInline, ExactAtZero) {
  double s = 1.0, c = 0.0;
  sincos_inline(0.0, s, c);
  EXPECT_EQ(s, 0.0);
  EXPECT_EQ(c, 1.0);
}

}  // namespace
}  // namespace featherdrive
