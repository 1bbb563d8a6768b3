// Small helpers the test files share (they are compiled several to a translation unit, so each
// name may be defined once: CMakeLists.txt, featherdrive_test_batches).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>

namespace featherdrive::test {

inline constexpr double kInf = std::numeric_limits<double>::infinity();

/// Bit equality of two arrays of doubles (Eigen vectors, matrices or maps): same size, same bytes.
template <class A, class B>
bool same_bits(const A& a, const B& b) {
  return a.size() == b.size() &&
         std::memcmp(a.data(), b.data(), sizeof(double) * static_cast<size_t>(a.size())) == 0;
}

/// The largest |a - b| / max(1, |b|) over two arrays of doubles of one size (e.g. the lanes' result
/// against Simulation's, whose operation order differs); +inf for other sizes.
template <class A, class B>
double relative_difference(const A& a, const B& b) {
  if (a.size() != b.size()) return kInf;
  double worst = 0.0;
  for (long i = 0; i < static_cast<long>(a.size()); ++i)
    worst = std::max(worst, std::abs(a.data()[i] - b.data()[i]) / std::max(1.0, std::abs(b.data()[i])));
  return worst;
}

/// The message of the std::invalid_argument f throws, or "(no error)".
inline std::string invalid_argument_message(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace featherdrive::test
