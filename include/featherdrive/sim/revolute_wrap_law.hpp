// A wrapped revolute joint's position after a step (docs/math/revolute_wrap.md, eq. 1), written
// once over the number type: double for Simulation (revolute_wrap.cpp), SIMD packs of
// environments in the lanes (sim/simd_lane_step.hpp). Only core/select.hpp, so that the lanes'
// units compiled for AVX2 and AVX-512 take in no inline function of the rest of the library.
#pragma once

#include "featherdrive/core/select.hpp"

namespace featherdrive::wrap_law {

/// q back into [-2 pi, 2 pi] by one turn of 4 pi where it left it, then clamped to [-4 pi, 4 pi].
template <class T>
T wrapped(const T& q) {
  const T two_pi(2.0 * 3.14159265358979323846), four_pi = T(2.0) * two_pi;
  const T x = select(two_pi < q, q - four_pi, select(q < -two_pi, q + four_pi, q));
  return clamp_select(x, -four_pi, four_pi);
}

}  // namespace featherdrive::wrap_law
