#include "featherdrive/constraint/shape_pairs.hpp"

#include <ccd/ccd.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace featherdrive {
namespace {

// A shape posed in the world and grown by `margin`, for libccd's support callbacks.
struct Posed {
  const CollisionShape* shape;
  Vec3 centre;
  Mat3 rotation;  // shape axes in the world
  double margin;
};

Vec3 to_vec(const ccd_vec3_t* v) { return Vec3(v->v[0], v->v[1], v->v[2]); }

// The point of the grown shape farthest along dir (C29).
void support(const void* object, const ccd_vec3_t* dir, ccd_vec3_t* out) {
  const Posed& p = *static_cast<const Posed*>(object);
  Vec3 d = to_vec(dir);
  const double length = d.norm();
  d = length > 0.0 ? Vec3(d / length) : Vec3(Vec3::UnitX());
  const Vec3 local = p.rotation.transpose() * d;
  const Vec3& size = p.shape->size;
  Vec3 x = Vec3::Zero();
  double radius = p.margin;
  switch (p.shape->type) {
    case ShapeType::sphere:
      radius += size.x();
      break;
    case ShapeType::capsule:
      x.z() = local.z() >= 0.0 ? size.y() : -size.y();
      radius += size.x();
      break;
    case ShapeType::box:
      for (int k = 0; k < 3; ++k) x[k] = local[k] >= 0.0 ? size[k] : -size[k];
      break;
    case ShapeType::ellipsoid: {  // A^2 d / |A d| for the semi-axes A
      const Vec3 a = size.cwiseProduct(local);
      const double norm = a.norm();
      if (norm > 0.0) x = size.cwiseProduct(a) / norm;
      break;
    }
    case ShapeType::cylinder: {  // the cap facing d, and the rim point along d across the axis
      x.z() = local.z() >= 0.0 ? size.y() : -size.y();
      const double across = std::hypot(local.x(), local.y());
      if (across > 0.0) {
        x.x() = size.x() * local.x() / across;
        x.y() = size.x() * local.y() / across;
      }
      break;
    }
    case ShapeType::convex: {
      double best = -std::numeric_limits<double>::infinity();
      for (const Vec3& v : p.shape->vertices)
        if (const double h = v.dot(local); h > best) {
          best = h;
          x = v;
        }
      break;
    }
  }
  const Vec3 w = p.centre + p.rotation * x + radius * d;
  for (int k = 0; k < 3; ++k) out->v[k] = w[k];
}

void centre(const void* object, ccd_vec3_t* out) {
  const Posed& p = *static_cast<const Posed*>(object);
  for (int k = 0; k < 3; ++k) out->v[k] = p.centre[k];
}

Posed posed(const Data& data, const CollisionShape& s, double margin) {
  const Mat3& R = data.world_rotation[s.link];
  return {&s, data.world_position[s.link] + R * s.position, R * s.rotation, margin};
}

}  // namespace

std::vector<ShapePair> self_collision_pairs(const Model& model) {
  // A link's body: itself, or, for a massless link without shapes that carries one child (the
  // links an MJCF body with several joints, or a URDF chain of massless links, becomes), the
  // body of that child. Parent and child are compared body to body (C29).
  const int links = model.num_links();
  std::vector<char> has_shapes(static_cast<size_t>(links), 0);
  for (const CollisionShape& s : model.shapes) has_shapes[static_cast<size_t>(s.link)] = 1;
  auto connector = [&](int i) {
    const Link& l = model.links[static_cast<size_t>(i)];
    return l.mass == 0.0 && !has_shapes[static_cast<size_t>(i)] && l.children.size() == 1;
  };
  // The body above a link's body: the first ancestor that is not a connector.
  auto body_parent = [&](int i) {
    int p = model.links[static_cast<size_t>(i)].parent;
    while (p >= 0 && connector(p)) p = model.links[static_cast<size_t>(p)].parent;
    return p;
  };
  std::vector<ShapePair> pairs;
  const int n = static_cast<int>(model.shapes.size());
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b) {
      const int la = model.shapes[static_cast<size_t>(a)].link;
      const int lb = model.shapes[static_cast<size_t>(b)].link;
      if (la == lb || body_parent(la) == lb || body_parent(lb) == la) continue;
      pairs.push_back({a, b});
    }
  return pairs;
}

double bounding_radius(const CollisionShape& s) {
  switch (s.type) {
    case ShapeType::sphere: return s.size.x();
    case ShapeType::capsule: return s.size.x() + s.size.y();
    case ShapeType::box: return s.size.norm();
    case ShapeType::ellipsoid: return s.size.maxCoeff();
    case ShapeType::cylinder: return std::hypot(s.size.x(), s.size.y());
    case ShapeType::convex: {
      double r = 0.0;
      for (const Vec3& v : s.vertices) r = std::max(r, v.norm());
      return r;
    }
  }
  return 0.0;
}

bool shape_pair_contact(const Data& data, const CollisionShape& a, const CollisionShape& b,
                        double contact_distance, PairContact& out) {
  const double margin = 0.5 * contact_distance;
  const Posed pa = posed(data, a, margin), pb = posed(data, b, margin);
  if ((pa.centre - pb.centre).norm() >
      bounding_radius(a) + bounding_radius(b) + contact_distance)
    return false;
  ccd_t ccd;
  CCD_INIT(&ccd);
  ccd.support1 = ccd.support2 = support;
  ccd.center1 = ccd.center2 = centre;
  ccd.max_iterations = 100;
  ccd.mpr_tolerance = 1e-12;
  ccd_real_t depth = 0.0;
  ccd_vec3_t dir, pos;
  if (ccdMPRPenetration(&pa, &pb, &ccd, &depth, &dir, &pos) != 0) return false;
  const Vec3 n = -to_vec(&dir);  // libccd's dir points from a to b
  if (!(depth >= 0.0) || !(std::abs(n.norm() - 1.0) < 1e-6)) return false;
  out.point = to_vec(&pos);
  out.normal = n.normalized();
  out.separation = contact_distance - depth;
  return true;
}

}  // namespace featherdrive
