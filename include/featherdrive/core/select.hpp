// Branch-free choices over a number type T: double here, a SIMD pack of environments in the lanes
// (sim/simd_lane_step.hpp, whose own select argument-dependent lookup finds). The laws written
// once over T (constraint/drive.hpp, constraint/row_laws.hpp) choose only through these, so a lane
// runs the operations a lone dof runs.
#pragma once

namespace featherdrive {

inline double select(bool c, double a, double b) { return c ? a : b; }

/// std::clamp's operations: lo if x < lo, else hi if hi < x, else x.
template <class T>
T clamp_select(const T& x, const T& lo, const T& hi) {
  return select(x < lo, lo, select(hi < x, hi, x));
}

/// |x| as a select (-0 stays -0: every use compares it or adds it to a non-negative term).
template <class T>
T magnitude(const T& x) {
  return select(x < T(0.0), -x, x);
}

}  // namespace featherdrive
