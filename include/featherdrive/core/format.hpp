// Numbers as text for files and messages: the shortest form that reads back to the same double.
#pragma once

#include <string>

#include "featherdrive/spatial/types.hpp"

namespace featherdrive {

std::string format_double(double value);
std::string format_vec3(const Vec3& v);  ///< "[x, y, z]"

}  // namespace featherdrive
