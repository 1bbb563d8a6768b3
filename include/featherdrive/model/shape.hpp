// A link's collision geometry (docs/math/contact.md, section 1): primitives with a pose in the
// link frame and a material. Part of the Model: a robot's description fixes its shapes.
#pragma once

#include <string>
#include <vector>

#include "featherdrive/spatial/spatial.hpp"

namespace featherdrive {

enum class ShapeType {
  sphere,   ///< size = (radius, 0, 0)
  capsule,  ///< size = (radius, half length of the segment, 0); the segment along the shape's z
  box,      ///< size = half extents along the shape's x, y, z
  ellipsoid,  ///< size = the semi-axes along the shape's x, y, z
  cylinder,   ///< size = (radius, half length, 0); the axis along the shape's z
  convex,     ///< size unused (0); CollisionShape::vertices, a convex hull's, in the shape frame
};

const char* to_string(ShapeType type);

/// Friction and restitution of a surface. A contact uses the average of its two surfaces'
/// values (PhysX's default combine mode; docs/math/contact.md, section 1).
struct Material {
  double static_friction = 0.5;
  double dynamic_friction = 0.5;
  double restitution = 0.0;
};

struct CollisionShape {
  std::string name;                    ///< for messages: the URDF/MJCF element's name, or ""
  int link = 0;                        ///< the link that carries it
  ShapeType type = ShapeType::sphere;
  Vec3 size = Vec3::Zero();            ///< see ShapeType
  Vec3 position = Vec3::Zero();        ///< the shape frame's origin in the link frame
  Mat3 rotation = Mat3::Identity();    ///< the shape frame's axes in the link frame
  Material material;
  std::vector<Vec3> vertices;          ///< convex: the hull's vertices in the shape frame
};

}  // namespace featherdrive
