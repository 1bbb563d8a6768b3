#pragma once

// sin and cos of one angle from + - * / only, inline: glibc's sincos is a call of about 97
// instructions, a third of the kinematics. The same method as the SIMD lanes' LaneStep::sincos
// (docs/math/sincos.md), so the two agree to the last bits or nearly.

#include <cmath>

namespace featherdrive {

/// s = sin x, c = cos x, within 2 ulp of glibc's for |x| <= 1e5 (tests/spatial/sincos_test.cpp);
/// beyond, and for inf or NaN, glibc's own (the reduction below loses digits there, and the
/// quadrant would not fit a long long). Needs round-to-nearest and no -ffast-math.
inline void sincos_inline(double x, double& s, double& c) {
  if (!(std::abs(x) <= 1e5)) {
    s = std::sin(x);
    c = std::cos(x);
    return;
  }
  // j = round(2 x / pi) by adding and subtracting 1.5 * 2^52 (eq. SC-1).
  constexpr double kRound = 6755399441055744.0;
  const double j = (x * 0.63661977236758134308 + kRound) - kRound;
  // r = x - j pi / 2 with pi / 2 in three parts (Cody and Waite); j times each of the first two
  // is exact (eq. SC-2).
  const double r = ((x - j * 1.57079625129699707031) - j * 7.54978941586159635336e-8) -
                   j * 5.39030285815811905290e-15;
  // Minimax polynomials on [-pi/4, pi/4] (Cephes's sin.c coefficients; eq. SC-3).
  const double z = r * r;
  double ps = 1.58962301576546568060e-10;
  ps = ps * z - 2.50507477628578072866e-8;
  ps = ps * z + 2.75573136213857245213e-6;
  ps = ps * z - 1.98412698295895385996e-4;
  ps = ps * z + 8.33333333332211858878e-3;
  ps = ps * z - 1.66666666666666307295e-1;
  double pc = -1.13585365213876817300e-11;
  pc = pc * z + 2.08757008419747316778e-9;
  pc = pc * z - 2.75573141792967388112e-7;
  pc = pc * z + 2.48015872888517045348e-5;
  pc = pc * z - 1.38888888888730564116e-3;
  pc = pc * z + 4.16666666666665929218e-2;
  const double sr = r + r * z * ps;
  const double cr = (1.0 - 0.5 * z) + z * z * pc;
  // The quadrant j mod 4 picks and signs them (eq. SC-4); j fits a long for |x| < 2^62.
  const unsigned quadrant = static_cast<unsigned>(static_cast<long long>(j)) & 3u;
  const double sin_r = (quadrant & 1u) ? cr : sr, cos_r = (quadrant & 1u) ? sr : cr;
  s = (quadrant & 2u) ? -sin_r : sin_r;
  c = ((quadrant + 1u) & 2u) ? -cos_r : cos_r;
}

}  // namespace featherdrive
