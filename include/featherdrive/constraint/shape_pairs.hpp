// The narrow phase between two of a robot's shapes for self-collision (docs/math/contact.md,
// section 14): which pairs are tested, and the contact of one posed pair by libccd's MPR.
#pragma once

#include <vector>

#include "featherdrive/algorithm/data.hpp"
#include "featherdrive/model/shape.hpp"

namespace featherdrive {

/// Two shapes (indices into Model::shapes) that self-collision tests.
struct ShapePair {
  int a = 0, b = 0;
};

/// Every pair of shapes on two links that are neither the same link nor parent and child (PhysX's
/// and Isaac Lab's filter), a < b. Massless links without shapes that carry one child (what an
/// MJCF body with several joints becomes) are part of their child: the parent of a link is the
/// first ancestor that is not such a connector.
std::vector<ShapePair> self_collision_pairs(const Model& model);

/// A sphere about the shape frame's origin that holds the shape.
double bounding_radius(const CollisionShape& shape);

/// One point of contact between two posed shapes.
struct PairContact {
  Vec3 point = Vec3::Zero();   ///< world frame: midway through the overlap of the grown shapes
  Vec3 normal = Vec3::UnitZ(); ///< unit, from b into a
  double separation = 0.0;     ///< < 0 penetrating
};

/// Whether shapes a and b at their links' poses in data (world) come within contact_distance,
/// and if so their contact (C29): each grown by contact_distance / 2, the penetration of the grown
/// pair (MPR) gives separation = contact_distance - depth. Allocates nothing.
bool shape_pair_contact(const Data& data, const CollisionShape& a, const CollisionShape& b,
                        double contact_distance, PairContact& out);

}  // namespace featherdrive
