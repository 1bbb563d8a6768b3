#include "featherdrive/constraint/shape_pairs.hpp"

#include <ccd/ccd.h>

#include <Eigen/Eigenvalues>
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

using Vec2 = Eigen::Vector2d;

double cross(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

// The corners of a shape with vertices, in the world, a box's in PhysX's order (C1a); a capsule's
// segment ends (its surface lies its radius beyond them).
int world_corners(const Posed& p, Vec3* out) {
  if (p.shape->type == ShapeType::capsule) {
    out[0] = p.centre + p.shape->size.y() * p.rotation.col(2);
    out[1] = p.centre - p.shape->size.y() * p.rotation.col(2);
    return 2;
  }
  if (p.shape->type == ShapeType::box) {
    const Vec3& e = p.shape->size;
    for (int v = 0; v < 8; ++v)
      out[v] = p.centre + p.rotation * Vec3(v & 4 ? -e.x() : e.x(), v & 2 ? -e.y() : e.y(),
                                            v & 1 ? -e.z() : e.z());
    return 8;
  }
  int k = 0;
  for (const Vec3& v : p.shape->vertices) out[k++] = p.centre + p.rotation * v;
  return k;
}

// A side's height along n as a plane over the plane across n, fitted by least squares to its
// corners (exact for a flat face; a corner or an edge gives the plane of least slope).
struct Height {
  Vec2 mean = Vec2::Zero();
  double level = 0.0;
  Vec2 slope = Vec2::Zero();
  double at(const Vec2& p) const { return level + slope.dot(p - mean); }
};

Height fit(const Vec2* p, const double* h, int count) {
  Height f;
  for (int i = 0; i < count; ++i) {
    f.mean += p[i];
    f.level += h[i];
  }
  f.mean /= count;
  f.level /= count;
  Eigen::Matrix2d S = Eigen::Matrix2d::Zero();
  Vec2 r = Vec2::Zero();
  for (int i = 0; i < count; ++i) {
    const Vec2 d = p[i] - f.mean;
    S += d * d.transpose();
    r += d * (h[i] - f.level);
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen;
  eigen.computeDirect(S);
  const double largest = eigen.eigenvalues().cwiseAbs().maxCoeff();
  for (int k = 0; k < 2; ++k) {  // the pseudo-inverse: directions the corners do not span add 0
    const double l = eigen.eigenvalues()[k];
    if (l > 1e-12 * largest && l > 0.0) {
      const Vec2 e = eigen.eigenvectors().col(k);
      f.slope += e * (e.dot(r) / l);
    }
  }
  return f;
}

// The convex outline of count points, counter-clockwise, into out (2 count places), without
// repeated or collinear points; returns its size.
int outline(Vec2* p, int count, Vec2* out) {
  std::sort(p, p + count, [](const Vec2& a, const Vec2& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  constexpr double kFlat = 1e-14;  // m^2
  int k = 0;
  for (int i = 0; i < count; ++i) {
    while (k >= 2 && cross(out[k - 1] - out[k - 2], p[i] - out[k - 2]) <= kFlat) --k;
    out[k++] = p[i];
  }
  for (int i = count - 2, t = k + 1; i >= 0; --i) {
    while (k >= t && cross(out[k - 1] - out[k - 2], p[i] - out[k - 2]) <= kFlat) --k;
    out[k++] = p[i];
  }
  if (k > 1) --k;  // the first point came round again
  int n = 0;
  constexpr double kSame = 1e-24;  // m^2
  for (int i = 0; i < k; ++i)
    if (n == 0 || (out[i] - out[n - 1]).squaredNorm() > kSame) out[n++] = out[i];
  while (n > 1 && (out[n - 1] - out[0]).squaredNorm() <= kSame) --n;
  return n;
}

double area(const Vec2* p, int count) {
  double a = 0.0;
  for (int i = 0; i < count; ++i) a += cross(p[i], p[(i + 1) % count]);
  return 0.5 * a;
}

// The part of the convex polygon (or segment, or point) `subject` inside the convex
// counter-clockwise polygon `clip` (Sutherland and Hodgman's clipping); returns its size.
int clip_polygon(const Vec2* clip, int clips, Vec2* subject, int count, Vec2* scratch) {
  Vec2* in = subject;
  Vec2* out = scratch;
  for (int i = 0; i < clips && count > 0; ++i) {
    const Vec2 e0 = clip[i], edge = clip[(i + 1) % clips] - e0;
    auto side = [&](const Vec2& q) { return cross(edge, q - e0); };
    int n = 0;
    for (int j = 0; j < count; ++j) {
      const Vec2& cur = in[j];
      const Vec2& prev = in[(j + count - 1) % count];
      const double sc = side(cur), sp = side(prev);
      if ((sc >= 0.0) != (sp >= 0.0)) out[n++] = prev + (cur - prev) * (sp / (sp - sc));
      if (sc >= 0.0) out[n++] = cur;
    }
    count = n;
    std::swap(in, out);
  }
  if (in != subject) std::copy(in, in + count, subject);
  return count;
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

bool has_vertices(const CollisionShape& s) {
  return s.type == ShapeType::box || s.type == ShapeType::convex;
}

bool pair_manifold(const CollisionShape& a, const CollisionShape& b) {
  auto flat = [](const CollisionShape& s) {
    return has_vertices(s) || s.type == ShapeType::capsule;
  };
  return flat(a) && flat(b) && (has_vertices(a) || has_vertices(b));
}

ManifoldWorkspace::ManifoldWorkspace(const std::vector<CollisionShape>& shapes) {
  size_t most = 2;  // a capsule's segment ends
  for (const CollisionShape& s : shapes)
    if (has_vertices(s)) most = std::max(most, s.type == ShapeType::box ? 8 : s.vertices.size());
  world_.resize(2 * most);
  for (int k = 0; k < 2; ++k) {
    face_[k].resize(most);
    height_[k].resize(most);
  }
  clipped_.resize(4 * most + 4);
  next_.resize(4 * most + 4);
  points_.resize(4 * most + 5);
  separations_.resize(4 * most + 5);
  taken_.resize(4 * most + 5);
}

bool shape_pair_manifold(const Data& data, const CollisionShape& a, const CollisionShape& b,
                         double contact_distance, ManifoldWorkspace& w, PairManifold& out) {
  PairContact contact;
  if (!shape_pair_contact(data, a, b, contact_distance, contact)) return false;
  auto single = [&] {
    out.normal = contact.normal;
    out.count = 1;
    out.points[0] = contact.point;
    out.separations[0] = out.deepest = contact.separation;
    return true;
  };
  if (!pair_manifold(a, b)) return single();
  // The patch's normal: MPR's, or a box's face normal along which the pair penetrates less (MPR's
  // depth is along the portal it converges on, which for two boxes side by side can lean far
  // from the face they rest on); depth(d) = max_b d . y - min_a d . x (C29a).
  Vec3* corners[2] = {w.world_.data(), nullptr};
  int counts[2];
  counts[0] = world_corners(posed(data, a, 0.0), corners[0]);
  corners[1] = corners[0] + counts[0];
  counts[1] = world_corners(posed(data, b, 0.0), corners[1]);
  const double radius[2] = {a.type == ShapeType::capsule ? a.size.x() : 0.0,
                            b.type == ShapeType::capsule ? b.size.x() : 0.0};
  auto depth = [&](const Vec3& d) {
    double low = std::numeric_limits<double>::infinity(), high = -low;
    for (int i = 0; i < counts[0]; ++i) low = std::min(low, d.dot(corners[0][i]));
    for (int i = 0; i < counts[1]; ++i) high = std::max(high, d.dot(corners[1][i]));
    return high + radius[1] - (low - radius[0]);
  };
  Vec3 n = contact.normal;
  double least = depth(n);
  bool faced = false;
  constexpr double kLess = 1e-9;  // m: a face normal replaces MPR's only where clearly better
  for (const CollisionShape* s : {&a, &b}) {
    if (s->type != ShapeType::box) continue;
    const Mat3 axes = posed(data, *s, 0.0).rotation;
    for (int k = 0; k < 6; ++k) {
      const Vec3 d = (k < 3 ? 1.0 : -1.0) * axes.col(k % 3);
      if (const double e = depth(d); e < least - kLess) {
        least = e;
        n = d;
        faced = true;
      }
    }
  }
  out.normal = n;
  // C29a: each shape's side facing the other (a lies along +n of b), across n as an outline with
  // a fitted height; the two outlines' overlap, each of its corners a point with separation
  // height_a - height_b.
  const Vec3 u = contact_laws::fallback_tangent(n), v = n.cross(u);
  Height height[2];
  int sizes[2];
  for (int k = 0; k < 2; ++k) {
    // a's lowest side along n, b's highest; a capsule's side its radius beyond its segment.
    const double toward = k == 0 ? -1.0 : 1.0, beyond = toward * radius[k];
    double lowest = std::numeric_limits<double>::infinity(), highest = -lowest;
    for (int i = 0; i < counts[k]; ++i) {
      const double h = toward * n.dot(corners[k][i]);
      lowest = std::min(lowest, h);
      highest = std::max(highest, h);
    }
    // The facing side: corners within a quarter of the shape's extent along n of its extreme,
    // and within the contact distance.
    double within = std::min(contact_distance, 0.25 * (highest - lowest));
    if (radius[k] > 0.0) {  // a capsule: both ends (the ground's rule) unless it leans past 45 deg
      const Vec3 axis = corners[k][0] - corners[k][1];
      const double along = std::abs(n.dot(axis)), across = (axis - n * n.dot(axis)).norm();
      within = along <= across ? contact_distance : 0.0;
    }
    int m = 0;
    for (int i = 0; i < counts[k]; ++i) {
      const Vec3& x = corners[k][i];
      if (toward * n.dot(x) >= highest - within) {
        w.face_[k][static_cast<size_t>(m)] = Vec2(u.dot(x), v.dot(x));
        w.height_[k][static_cast<size_t>(m++)] = n.dot(x) + beyond;
      }
    }
    height[k] = fit(w.face_[k].data(), w.height_[k].data(), m);
    sizes[k] = outline(w.face_[k].data(), m, w.next_.data());
    std::copy(w.next_.begin(), w.next_.begin() + sizes[k], w.face_[k].begin());
  }
  // b's outline clips a's; a's clips b's when b's has no area (an edge, a corner).
  const double areas[2] = {sizes[0] >= 3 ? area(w.face_[0].data(), sizes[0]) : 0.0,
                           sizes[1] >= 3 ? area(w.face_[1].data(), sizes[1]) : 0.0};
  constexpr double kFlat = 1e-14;  // m^2
  const int clip = areas[1] > kFlat ? 1 : 0;
  int count = 0;
  if (areas[clip] > kFlat) {
    const int subject = 1 - clip;
    std::copy(w.face_[subject].begin(), w.face_[subject].begin() + sizes[subject],
              w.clipped_.begin());
    const int m = clip_polygon(w.face_[clip].data(), sizes[clip], w.clipped_.data(), sizes[subject],
                               w.next_.data());
    for (int i = 0; i < m; ++i) {
      const Vec2& p = w.clipped_[static_cast<size_t>(i)];
      const double ha = height[0].at(p), d = ha - height[1].at(p);
      if (!(d <= contact_distance)) continue;
      bool repeated = false;
      for (int j = 0; j < count && !repeated; ++j)
        repeated =
            (w.points_[static_cast<size_t>(j)] - (p.x() * u + p.y() * v + ha * n)).squaredNorm() <=
            1e-24;
      if (repeated) continue;
      w.points_[static_cast<size_t>(count)] = p.x() * u + p.y() * v + ha * n;
      w.separations_[static_cast<size_t>(count++)] = d;
    }
  }
  if (count == 0) return single();
  double deepest = w.separations_[0];
  for (int i = 1; i < count; ++i)
    deepest = std::min(deepest, w.separations_[static_cast<size_t>(i)]);
  // Sides that are not flat faces fit their planes only roughly: MPR's point joins when the
  // outlines' miss its depth along its own normal.
  constexpr double kMissed = 1e-6;  // m
  if (!faced && deepest > contact.separation + kMissed) {
    w.points_[static_cast<size_t>(count)] = contact.point;
    w.separations_[static_cast<size_t>(count++)] = deepest = contact.separation;
  }
  if (count > contact_laws::kManifoldPoints) {
    contact_laws::reduce_points(w.points_.data(), w.separations_.data(), w.taken_.data(), count, n);
    count = contact_laws::kManifoldPoints;
  }
  out.count = count;
  for (int i = 0; i < count; ++i) {
    out.points[i] = w.points_[static_cast<size_t>(i)];
    out.separations[i] = w.separations_[static_cast<size_t>(i)];
  }
  out.deepest = deepest;
  return true;
}

}  // namespace featherdrive
