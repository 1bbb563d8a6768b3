// A robot as a person wants to read it (`featherdrive info`): the tree, dofs, masses, inertias
// and limits.
#pragma once

#include <string>

#include "featherdrive/io/urdf.hpp"

namespace featherdrive {

/// Also lists the collision shapes per link, what contacts cannot use yet and the file's floor.
std::string describe(const UrdfRobot& robot);

/// One line per link with shapes: "  <indent><link>: capsule 'shin' (r 0.05, half length 0.1)
/// at [0, 0, -0.1] m, box (half extents [..]) ..."; "" for a model without shapes.
std::string describe_shapes(const Model& model, const std::string& indent);

/// "height 0 m, normal [0, 0, 1], friction 0.5 / 0.5, restitution 0" (static / dynamic).
std::string describe_ground(const Ground& ground);

}  // namespace featherdrive
