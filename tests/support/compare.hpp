// Small helpers the test files share (they are compiled several to a translation unit, so each
// name may be defined once: CMakeLists.txt, featherdrive_test_batches).
#pragma once

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
