#include "featherdrive/io/format.hpp"

#include <charconv>

namespace featherdrive {

std::string format_double(double value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  return std::string(buffer, result.ptr);
}

std::string format_vec3(const Vec3& v) {
  return "[" + format_double(v.x()) + ", " + format_double(v.y()) + ", " + format_double(v.z()) +
         "]";
}

}  // namespace featherdrive
