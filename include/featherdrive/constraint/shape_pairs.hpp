// The narrow phase between two of a robot's shapes for self-collision (docs/math/contact.md,
// section 14): which pairs are tested, and the contact of one posed pair by libccd's MPR.
#pragma once

#include <vector>

#include "featherdrive/algorithm/data.hpp"
#include "featherdrive/constraint/contact_laws.hpp"
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
  Vec3 point = Vec3::Zero();    ///< world frame: midway through the overlap of the grown shapes
  Vec3 normal = Vec3::UnitZ();  ///< unit, from b into a
  double separation = 0.0;      ///< < 0 penetrating
};

/// Whether shapes a and b at their links' poses in data (world) come within contact_distance,
/// and if so their contact (C29): each grown by contact_distance / 2, the penetration of the grown
/// pair (MPR) gives separation = contact_distance - depth. Allocates nothing.
bool shape_pair_contact(const Data& data, const CollisionShape& a, const CollisionShape& b,
                        double contact_distance, PairContact& out);

/// The points of contact between two posed shapes: one patch, one normal (C29a).
struct PairManifold {
  Vec3 normal = Vec3::UnitZ();  ///< unit, from b into a
  int count = 0;
  Vec3 points[contact_laws::kManifoldPoints];  ///< world frame
  double separations[contact_laws::kManifoldPoints] = {};
  double deepest = 0.0;  ///< the least of the separations
};

/// Whether a shape has corners the manifold is gathered from (box, convex hull; C29a).
bool has_vertices(const CollisionShape& shape);

/// Whether shape_pair_manifold gathers more than one point for the pair: a box or hull with a
/// box, a hull or a capsule (its segment's ends; C29a).
bool pair_manifold(const CollisionShape& a, const CollisionShape& b);

/// The scratch of shape_pair_manifold, sized once for a model's shapes so that a step
/// allocates nothing.
class ManifoldWorkspace {
 public:
  ManifoldWorkspace() = default;
  explicit ManifoldWorkspace(const std::vector<CollisionShape>& shapes);

 private:
  friend bool shape_pair_manifold(const Data&, const CollisionShape&, const CollisionShape&, double,
                                  ManifoldWorkspace&, PairManifold&);
  std::vector<Vec3> world_;  ///< both shapes' corners in the world
  std::vector<Eigen::Vector2d>
      face_[2];                    ///< the two facing sides' corners across n, then their outlines
  std::vector<double> height_[2];  ///< those corners along n
  std::vector<Eigen::Vector2d> clipped_, next_;
  std::vector<Vec3> points_;
  std::vector<double> separations_;
  std::vector<char> taken_;
};

/// shape_pair_contact, then, for a pair_manifold pair, up to four points over the patch where
/// their facing sides overlap across the contact's normal (C29a); one point (C29) otherwise.
/// Allocates nothing.
bool shape_pair_manifold(const Data& data, const CollisionShape& a, const CollisionShape& b,
                         double contact_distance, ManifoldWorkspace& work, PairManifold& out);

}  // namespace featherdrive
