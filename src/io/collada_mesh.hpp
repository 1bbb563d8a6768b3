// The vertex positions of a COLLADA (.dae) file, all a convex hull needs (docs/math/contact.md,
// G3): every <library_geometries> <mesh>'s POSITION source, placed by the visual scene's nodes,
// in metres (<asset><unit meter>). <up_axis> is checked but not applied, as ROS's mesh readers do.
#pragma once

#include <string>
#include <vector>

#include "featherdrive/spatial/spatial.hpp"

namespace featherdrive::collada {

/// The deepest element nesting read (TinyXML recurses once per level).
inline constexpr int kMaxColladaDepth = 1000;

/// The positions of every mesh the scene instantiates (<instance_visual_scene>, else the first
/// <visual_scene>; every geometry, unplaced, where the file has no visual scene), each moved by its
/// nodes' <matrix>, <translate>, <rotate> and <scale> in document order, then scaled to metres.
/// Throws std::runtime_error with a one-line reason (no file name): not UTF-8, not XML, not
/// <COLLADA>, no mesh, a <float_array> whose count differs from its numbers, a number that is not
/// finite, an accessor beyond its array, a reference to another file or to no element.
std::vector<Vec3> vertices(const std::string& xml);

}  // namespace featherdrive::collada
