#pragma once

// sin and cos of one angle from + - * / only, inline: glibc's sincos is a call of about 97
// instructions, a third of the kinematics. Written once over the number type (docs/math/sincos.md):
// double here, SIMD packs of environments in the lanes (LaneStep::sincos), so the two agree to
// the bit for |x| <= 1e5. Only <cmath> and core/select.hpp, so that the lanes' units compiled for
// AVX2 and AVX-512 take in no inline function of the rest of the library.

#include <cmath>

#include "featherdrive/core/select.hpp"

namespace featherdrive {

namespace sincos_law {

/// s = sin x, c = cos x by eq. SC-1 to SC-4, for |x| <= 1e5 (beyond, the reduction loses digits);
/// T: double or a pack, choosing only through select. Needs round-to-nearest, no -ffast-math.
template <class T>
void sincos(const T& x, T& s, T& c) {
  // j = round(2 x / pi) by adding and subtracting 1.5 * 2^52 (eq. SC-1).
  const T round(6755399441055744.0);
  const T j = (x * T(0.63661977236758134308) + round) - round;
  // r = x - j pi / 2 with pi / 2 in three parts (Cody and Waite); j times each of the first two
  // is exact (eq. SC-2).
  const T r = ((x - j * T(1.57079625129699707031)) - j * T(7.54978941586159635336e-8)) -
              j * T(5.39030285815811905290e-15);
  // Minimax polynomials on [-pi/4, pi/4] (Cephes's sin.c coefficients; eq. SC-3).
  const T z = r * r;
  T ps(1.58962301576546568060e-10);
  ps = ps * z - T(2.50507477628578072866e-8);
  ps = ps * z + T(2.75573136213857245213e-6);
  ps = ps * z - T(1.98412698295895385996e-4);
  ps = ps * z + T(8.33333333332211858878e-3);
  ps = ps * z - T(1.66666666666666307295e-1);
  T pc(-1.13585365213876817300e-11);
  pc = pc * z + T(2.08757008419747316778e-9);
  pc = pc * z - T(2.75573141792967388112e-7);
  pc = pc * z + T(2.48015872888517045348e-5);
  pc = pc * z - T(1.38888888888730564116e-3);
  pc = pc * z + T(4.16666666666665929218e-2);
  const T sr = r + r * z * ps;
  const T cr = (T(1.0) - T(0.5) * z) + z * z * pc;
  // The quadrant j mod 4, exactly: floor(j / 4) = round((j - 1.5) / 4) for an integer j; it picks
  // and signs them (eq. SC-4).
  const T quadrant = j - T(4.0) * (((j - T(1.5)) * T(0.25) + round) - round);
  const auto odd = (quadrant == T(1.0)) | (quadrant == T(3.0));
  const T sin_r = select(odd, cr, sr), cos_r = select(odd, sr, cr);
  s = select(quadrant >= T(2.0), -sin_r, sin_r);
  c = select((quadrant == T(1.0)) | (quadrant == T(2.0)), -cos_r, cos_r);
}

}  // namespace sincos_law

/// s = sin x, c = cos x, within 2 ulp of glibc's for |x| <= 1e5 (tests/spatial/sincos_test.cpp);
/// beyond, and for inf or NaN, glibc's own.
inline void sincos_inline(double x, double& s, double& c) {
  if (!(std::abs(x) <= 1e5)) {
    s = std::sin(x);
    c = std::cos(x);
    return;
  }
  sincos_law::sincos(x, s, c);
}

}  // namespace featherdrive
