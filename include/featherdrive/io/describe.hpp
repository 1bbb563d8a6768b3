// A robot as a person wants to read it (`featherdrive info`): the tree, dofs, masses, inertias
// and limits.
#pragma once

#include <string>

#include "featherdrive/io/urdf.hpp"

namespace featherdrive {

std::string describe(const UrdfRobot& robot);

}  // namespace featherdrive
