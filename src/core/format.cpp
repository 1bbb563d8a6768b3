#include "featherdrive/core/format.hpp"

#include <charconv>

namespace featherdrive {

std::string format_double(double value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  return std::string(buffer, result.ptr);
}

std::string format_vec3(const Vec3& v) {
  std::string s = "[";  // built in steps: GCC 12 -O3 misreports -Wrestrict on a + chain
  s += format_double(v.x());
  s += ", ";
  s += format_double(v.y());
  s += ", ";
  s += format_double(v.z());
  s += "]";
  return s;
}

std::string count_of(long n, const char* noun) {
  return std::to_string(n) + " " + noun + (n == 1 ? "" : "s");
}

}  // namespace featherdrive
