// What the URDF, MJCF and scene readers share: "no limit", and the one-line error that names the
// file (the io library is compiled as one unit, so each lives here once).
#pragma once

#include <limits>
#include <string>

#include "featherdrive/io/error.hpp"

namespace featherdrive::io_detail {

inline constexpr double kInf = std::numeric_limits<double>::infinity();

[[noreturn]] inline void fail(const std::string& file, const std::string& what) {
  throw InputError(file + ": " + what);
}

}  // namespace featherdrive::io_detail
