// Numbers as text for files and messages: the shortest form that reads back to the same double.
#pragma once

#include <string>

#include "featherdrive/spatial/types.hpp"

namespace featherdrive {

std::string format_double(double value);
std::string format_vec3(const Vec3& v);  ///< "[x, y, z]"
/// A count and its noun: "1 dof", "3 dofs" (the noun in the singular; an s makes the plural).
std::string count_of(long n, const char* noun);

}  // namespace featherdrive
