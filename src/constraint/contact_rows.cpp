#include "featherdrive/constraint/contact_rows.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "featherdrive/algorithm/multi_dof_law.hpp"
#include "featherdrive/constraint/contact_laws.hpp"

namespace featherdrive {
using namespace contact_laws;  // constants, row_mass, fallback_tangent, spatial_force
namespace {

// PhysX 5.6.1's constants (docs/math/contact.md, section 8).
constexpr double kFrictionOffsetThreshold = 0.04;  // m: anchors lie closer (section 4)
constexpr double kCorrelationDistance = 0.025;    // m: a kept anchor's drift along n (C9)
constexpr double kSameNormal = 0.999;              // PXC_SAME_NORMAL: cos of about 2.6 degrees
constexpr double kAnchorSeparation2 = 1e-8;       // m^2: a second anchor lies farther (C9a)

constexpr int kConvexPoints = kManifoldPoints;  // G3

// The points the narrow phase may consider for a shape, and the most it keeps.
int shape_candidates(const CollisionShape& s) {
  switch (s.type) {
    case ShapeType::sphere: return 1;
    case ShapeType::capsule: return 2;
    case ShapeType::box: return 8;
    case ShapeType::ellipsoid: return 1;
    case ShapeType::cylinder: return 8;
    case ShapeType::convex: return static_cast<int>(s.vertices.size());
  }
  return 0;
}
int shape_points(const CollisionShape& s) {
  return s.type == ShapeType::convex ? std::min(shape_candidates(s), kConvexPoints)
                                     : shape_candidates(s);
}



}  // namespace

double tgs_penetration_share(int position_iterations) {
  return std::min(kPgsBias, 2.0 * std::sqrt(1.0 / position_iterations));
}

void setup_normal_law(ContactNormalRow& row, double d, double vn, double restitution,
                      const ContactOptions& options, const ContactPhase& phase, double tgs_share) {
  const double dt = phase.dt;
  const double p0 = d - 2.0 * options.rest_offset;  // C1, C2
  row.impulse = 0.0;
  row.dx = 0.0;
  // C8: an impact faster than the threshold that closes the gap within the step bounces.
  const bool bounce = restitution > 0.0 && vn < -options.bounce_threshold && -vn > p0 / dt;
  row.target = bounce ? -restitution * vn : 0.0;
  if (!phase.tgs) {
    row.separation = p0;
    const double push_dt = phase.push_dt > 0.0 ? phase.push_dt : dt;
    row.bias = bounce ? 0.0 : (p0 >= 0.0 ? p0 / dt : kPgsBias * p0 / push_dt);  // C3, (G-3b)
  } else {
    // C6, C7: the bounce leaves from where the body meets the ground.
    row.separation = bounce ? p0 + row.target * (dt + p0 / vn) : p0;
    row.bias = p0 > 0.0 ? -1.0 / phase.h : -tgs_share / phase.h;
  }
}

double normal_row_delta(const ContactNormalRow& row, double vn, const ContactPhase& phase) {
  if (!phase.tgs) {
    // C4; C5 in the velocity iterations: the push-out goes, a gap still limits the approach.
    const double b = phase.velocity_iteration ? std::max(row.bias, 0.0) : row.bias;
    return std::max(row.mass * (row.target - b - vn), -row.impulse);
  }
  // C7: the separation tracked through the sub-steps.
  double sigma = row.separation + row.dx - row.target * phase.elapsed;
  if (phase.velocity_iteration) sigma = std::max(sigma, 0.0);
  return std::max(row.mass * (row.bias * sigma + row.target - vn), -row.impulse);
}

// v_i = v_parent + S_i qd_i; a spherical joint's and a floating root's S qd by AP14
// (multi_dof_law::joint_motion, unit_response.md), as ABA's pass 1 and the lanes'
// contact_velocities form them (the root's S is diag(R0, R0): its origin is frame 0's).
void link_velocities0(const Model& model, const Data& data, const VecX& qd, std::vector<Vec6>& V) {
  for (int i = 0; i < model.num_links(); ++i) {
    const Data::LinkInfo& link = data.info[i];
    Vec6 v = link.parent >= 0 ? V[link.parent] : Vec6(Vec6::Zero());
    const double* x = qd.data() + link.v_index;
    double J[6];
    if (link.nv == 1) {
      v += data.one_dof[i].S * qd[link.v_index];
    } else if (link.nv == 3) {
      multi_dof_law::joint_motion(
          multi_dof_law::DenseSubspace<double, 3>{data.motion_subspace[i].data()}, x, J);
      v += Vec6::Map(J);
    } else if (link.nv == 6) {
      multi_dof_law::joint_motion(
          multi_dof_law::RotationPair<double, true>{data.world_rotation[i].data()}, x, J);
      v += Vec6::Map(J);
    }
    V[i] = v;
  }
}

ContactRows::ContactRows(const Model& model) {
  const auto n = static_cast<size_t>(model.num_links());
  has_shapes_.assign(n, 0);
  link_first_patch_.assign(n, 0);
  link_end_patch_.assign(n, 0);
  int points = 0, candidates = 0;
  for (const CollisionShape& s : model.shapes) {
    has_shapes_[static_cast<size_t>(s.link)] = 1;
    points += shape_points(s);
    candidates = std::max(candidates, shape_candidates(s));
  }
  reach_.assign(model.shapes.size(), 0.0);
  for (size_t k = 0; k < model.shapes.size(); ++k)
    for (const Vec3& v : model.shapes[k].vertices) reach_[k] = std::max(reach_[k], v.norm());
  points_.resize(static_cast<size_t>(candidates));
  separations_.resize(static_cast<size_t>(candidates));
  taken_.resize(static_cast<size_t>(candidates));
  normals_.resize(static_cast<size_t>(points));
  frictions_.resize(4 * model.shapes.size());
  patches_.resize(model.shapes.size());
  anchors_.assign(model.shapes.size(), FrictionAnchors{});
  next_anchors_ = anchors_;
  shape_patch_.assign(model.shapes.size(), -1);
}

void ContactRows::set_anchors(const std::vector<FrictionAnchors>& anchors) {
  check_anchors(anchors);
  anchors_ = anchors;
}

void ContactRows::check_anchors(const std::vector<FrictionAnchors>& anchors) const {
  if (anchors.size() != anchors_.size())
    throw std::invalid_argument("friction_anchors: expected " + std::to_string(anchors_.size()) +
                                " shapes, got " + std::to_string(anchors.size()));
  for (size_t k = 0; k < anchors.size(); ++k) {
    const FrictionAnchors& a = anchors[k];
    bool finite = a.normal.allFinite();
    for (int j = 0; j < 2; ++j) finite = finite && a.body[j].allFinite() && a.ground[j].allFinite();
    if (a.count < 0 || a.count > 2 || !finite)
      throw std::invalid_argument("friction_anchors[" + std::to_string(k) + "]: count " +
                                  std::to_string(a.count) + " must be 0, 1 or 2 with finite points");
  }
}

void ContactRows::clear_anchors() {
  for (FrictionAnchors& a : anchors_) a.count = 0;
}

void ContactRows::conclude() {
  for (size_t k = 0; k < anchors_.size(); ++k) {
    const int p = shape_patch_[k];
    if (p >= 0 && !patches_[static_cast<size_t>(p)].broken) anchors_[k] = next_anchors_[k];
    else anchors_[k].count = 0;
  }
}

int ContactRows::setup(const Model& model, const Data& data, const Ground& ground,
                        const ContactOptions& options, const std::vector<Vec6>& link_velocity,
                        const VecX& link_cfm, int position_iterations, const ContactPhase& phase,
                        std::vector<ContactReport>& reports) {
  num_normals_ = num_frictions_ = num_patches_ = 0;
  std::fill(shape_patch_.begin(), shape_patch_.end(), -1);
  std::fill(link_first_patch_.begin(), link_first_patch_.end(), 0);
  std::fill(link_end_patch_.begin(), link_end_patch_.end(), 0);
  const Vec3 n = ground.normal;
  normal_ = n;
  const double contact_distance = 2.0 * options.contact_offset;  // C1
  const double rest_distance = 2.0 * options.rest_offset;
  const double dt = phase.dt;
  const Vec3& origin = data.frame_origin;
  const double tgs_share = tgs_penetration_share(position_iterations);
  Vec3* points = points_.data();
  double* separations = separations_.data();
  for (int k = 0; k < static_cast<int>(model.shapes.size()); ++k) {
    const CollisionShape& shape = model.shapes[static_cast<size_t>(k)];
    const int L = shape.link;
    const Mat6& lambda = data.response[L];
    const Mat3 R = data.world_rotation[L] * shape.rotation;
    const Vec3 c = data.world_position[L] + data.world_rotation[L] * shape.position;
    // The narrow phase against the plane n . x = height (section 1): points on the shape.
    int count = 0;
    auto add = [&](const Vec3& x, double d) {
      if (d <= contact_distance) {
        points[count] = x;
        separations[count++] = d;
      }
    };
    switch (shape.type) {
      case ShapeType::sphere:
        add(c - shape.size.x() * n, n.dot(c) - ground.height - shape.size.x());
        break;
      case ShapeType::capsule:
        for (const double side : {1.0, -1.0}) {
          const Vec3 end = c + side * shape.size.y() * R.col(2);
          add(end - shape.size.x() * n, n.dot(end) - ground.height - shape.size.x());
        }
        break;
      case ShapeType::box:
        // PhysX's order (contactPlaneBox): z turns fastest, then y, then x, + before - (C1a); the
        // rows are solved in it.
        for (int v = 0; v < 8; ++v) {
          const Vec3 corner(v & 4 ? -shape.size.x() : shape.size.x(),
                            v & 2 ? -shape.size.y() : shape.size.y(),
                            v & 1 ? -shape.size.z() : shape.size.z());
          const Vec3 x = c + R * corner;
          add(x, n.dot(x) - ground.height);
        }
        break;
      case ShapeType::ellipsoid: {
        // The support point along -n, the deepest one (docs/math/contact.md, G1).
        const Vec3 a2m = shape.size.cwiseProduct(shape.size).cwiseProduct(R.transpose() * n);
        const Vec3 x = c - R * a2m / shape.size.cwiseProduct(R.transpose() * n).norm();
        add(x, n.dot(x) - ground.height);
        break;
      }
      case ShapeType::cylinder: {
        // Per cap four rim points a quarter turn apart, the first the deepest (G2).
        const Vec3 axis = R.col(2);
        Vec3 u = axis * axis.dot(n) - n;  // -n projected onto the caps' plane
        u = u.squaredNorm() > 1e-12 ? Vec3(u.normalized()) : Vec3(R.col(0));
        const Vec3 w = axis.cross(u);
        const Vec3 rim[4] = {u, w, -u, -w};
        for (const double side : {-1.0, 1.0}) {
          const Vec3 cap = c + side * shape.size.y() * axis;
          for (const Vec3& e : rim) {
            const Vec3 x = cap + shape.size.x() * e;
            add(x, n.dot(x) - ground.height);
          }
        }
        break;
      }
      case ShapeType::convex:
        // Every hull vertex within the contact distance (PhysX's plane-convex points; G3); none
        // when the ball about the shape's origin through its farthest vertex is beyond it.
        if (n.dot(c) - ground.height - reach_[static_cast<size_t>(k)] > contact_distance) break;
        for (const Vec3& v : shape.vertices) {
          const Vec3 x = c + R * v;
          add(x, n.dot(x) - ground.height);
        }
        if (count > kConvexPoints) {
          reduce_points(points, separations, taken_.data(), count, n);
          count = kConvexPoints;
        }
        break;
    }
    if (count == 0) continue;
    const double cfm = link_cfm[L];
    // Rows on a link that cannot move along n (a fixed root, a turntable) do nothing (C22a).
    const Vec6 probe = spatial_force(points[0] - origin, n);
    if (!(row_response(probe, lambda * probe, lambda) + cfm > 0.0)) continue;
    ContactPatch& patch = patches_[static_cast<size_t>(num_patches_)];
    shape_patch_[static_cast<size_t>(k)] = num_patches_;
    if (link_end_patch_[L] == 0) link_first_patch_[L] = num_patches_;
    link_end_patch_[L] = ++num_patches_;
    patch.link = L;
    patch.first_normal = num_normals_;
    patch.num_normals = count;
    patch.broken = false;
    const Material& a = shape.material;
    const Material& b = ground.material;
    const double restitution = 0.5 * (a.restitution + b.restitution);
    const Vec6& V = link_velocity[L];
    double min_normal = 0.0;
    for (int p = 0; p < count; ++p) {
      ContactReport& report = reports[static_cast<size_t>(num_normals_)];
      ContactNormalRow& row = normals_[static_cast<size_t>(num_normals_++)];
      report.link = L;
      report.shape = k;
      report.other_link = report.other_shape = -1;  // the ground
      report.position = points[p];
      report.normal = n;
      report.separation = separations[p];
      row.J = spatial_force(points[p] - origin, n);
      row.response = lambda * row.J;
      row.mass = row_mass(1.0, row_response(row.J, row.response, lambda) + cfm);  // C20, C22a
      const double vn = row.J.dot(V);
      setup_normal_law(row, separations[p], vn, restitution, options, phase, tgs_share);
      const double p0 = separations[p] - rest_distance;  // C2
      min_normal += std::max(row.mass * (row.target - vn - std::max(p0 / dt, 0.0)), 0.0);
    }
    patch.min_normal_impulse = kMinNormalShare * min_normal / count;  // C12
    // Anchors (section 4, C9): last step's, while they stuck and stay within the correlation
    // distance of the ground along the normal they were made with; a kept pair clustered in less
    // than half the points' bounding diagonal is made afresh. Then, up to two, the first point
    // near enough, the next one more than 1e-4 m from it, and later points that spread the pair
    // wider (C9a); a kept anchor stays where it is.
    const FrictionAnchors& kept = anchors_[static_cast<size_t>(k)];
    Vec3 anchor_at[2], anchor_ground[2];
    int num_kept = 0;
    // The normal is kept in the link's frame: a link that turned (a rolling ball) drops them.
    const Vec3 kept_normal = data.world_rotation[L] * kept.normal;
    bool patch_kept = false;  // the patch goes on, with the normal it was made with (C9b)
    if (kept.count > 0 && kept_normal.dot(n) > kSameNormal) {
      bool correlated = true;
      for (int j = 0; j < kept.count; ++j) {
        anchor_at[j] = data.world_position[L] + data.world_rotation[L] * kept.body[j];
        anchor_ground[j] = kept.ground[j];
        correlated = correlated && std::abs(kept_normal.dot(anchor_at[j] - anchor_ground[j])) <
                                       kCorrelationDistance;
      }
      if (correlated) num_kept = kept.count;
      patch_kept = correlated;
    }
    if (num_kept == 2) {
      Vec3 low = points[0], high = points[0];
      for (int p = 1; p < count; ++p) {
        low = low.cwiseMin(points[p]);
        high = high.cwiseMax(points[p]);
      }
      if (4.0 * (anchor_at[1] - anchor_at[0]).squaredNorm() < (high - low).squaredNorm()) num_kept = 0;
    }
    int num_anchors = num_kept;
    if (num_kept < 2) {
      Vec3 chosen[2] = {anchor_at[0], anchor_at[1]};
      double spread = 0.0;
      const double anchor_distance = kFrictionOffsetThreshold + rest_distance;
      for (int p = 0; p < count; ++p) {
        if (!(separations[p] < anchor_distance)) continue;
        const Vec3& x = points[p];
        if (num_anchors == 0) {
          chosen[num_anchors++] = x;
        } else if (num_anchors == 1) {
          spread = (x - chosen[0]).squaredNorm();
          if (spread > kAnchorSeparation2) chosen[num_anchors++] = x;
        } else {
          const double d0 = (x - chosen[0]).squaredNorm(), d1 = (x - chosen[1]).squaredNorm();
          if (d0 > d1 ? d0 > spread : d1 > spread) {
            chosen[d0 > d1 ? 1 : 0] = x;
            spread = std::max(d0, d1);
          }
        }
      }
      for (int j = num_kept; j < num_anchors; ++j) anchor_at[j] = anchor_ground[j] = chosen[j];
    }
    // C10: along the link's centre-of-mass velocity, relative to the ground.
    const Vec3 com = data.world_position[L] + data.world_rotation[L] * data.constants[L].com;
    const Vec3 v_com = V.tail<3>() + V.head<3>().cross(com - origin);
    const Vec3 v_t = v_com - n * n.dot(v_com);
    patch.t0 = v_t.squaredNorm() > 1e-4 ? Vec3(v_t.normalized()) : fallback_tangent(n);
    patch.t1 = n.cross(patch.t0);
    const double share = num_anchors == 2 ? 0.5 : 1.0;  // C12
    patch.static_friction = share * 0.5 * (a.static_friction + b.static_friction);
    patch.dynamic_friction = share * 0.5 * (a.dynamic_friction + b.dynamic_friction);
    patch.first_friction = num_frictions_;
    patch.num_anchors = num_anchors;
    FrictionAnchors& next = next_anchors_[static_cast<size_t>(k)];
    next.count = num_anchors;
    // C9b: a patch that goes on keeps the normal it was made with, so the turn is measured from
    // there, not from the last step (a foot rolling 0.3 rad/s drops its anchors after 0.15 s).
    next.normal = patch_kept ? kept.normal : Vec3(data.world_rotation[L].transpose() * n);
    for (int j = 0; j < num_anchors; ++j) {
      next.body[j] = data.world_rotation[L].transpose() * (anchor_at[j] - data.world_position[L]);
      next.ground[j] = anchor_ground[j];
      // The friction impulse is reported on the point nearest the anchor.
      int nearest = 0;
      for (int p = 1; p < count; ++p)
        if ((points[p] - anchor_at[j]).squaredNorm() < (points[nearest] - anchor_at[j]).squaredNorm())
          nearest = p;
      patch.anchor_point[j] = patch.first_normal + nearest;
      const Vec3 drift = anchor_at[j] - anchor_ground[j];
      for (const Vec3* t : {&patch.t0, &patch.t1}) {
        ContactFrictionRow& row = frictions_[static_cast<size_t>(num_frictions_++)];
        row.J = spatial_force(anchor_at[j] - origin, *t);
        row.error = t->dot(drift);
        row.response = lambda * row.J;
        const double u = row_response(row.J, row.response, lambda);
        row.mass = row_mass(kFrictionMassScale, u + cfm);  // C11, C22a
        row.dx = 0.0;
        row.impulse = 0.0;
      }
    }
  }
  return num_normals_;
}

Vec6 ContactRows::solve_link(int link, const Vec6& v, Vec6& dv, const ContactPhase& phase) {
  Vec6 applied = Vec6::Zero();
  Vec6 V = v + dv;
  auto apply = [&](const Vec6& J, const Vec6& response, double delta) {
    V += delta * response;
    dv += delta * response;
    applied += delta * J;
  };
  const int end = link_end_patch_[static_cast<size_t>(link)];
  for (int k = link_first_patch_[static_cast<size_t>(link)]; k < end; ++k) {
    ContactPatch& patch = patches_[static_cast<size_t>(k)];
    double normal_sum = 0.0;
    for (int r = patch.first_normal; r < patch.first_normal + patch.num_normals; ++r) {
      ContactNormalRow& row = normals_[static_cast<size_t>(r)];
      const double delta = normal_row_delta(row, row.J.dot(V), phase);
      row.impulse += delta;
      apply(row.J, row.response, delta);
      normal_sum += row.impulse;
    }
    if (patch.num_anchors == 0) continue;
    // C12: the bound from this iteration's normal impulses, floored by the estimate.
    const double N = std::max(normal_sum, patch.min_normal_impulse);
    const double static_limit = patch.static_friction * N;
    const double dynamic_limit = patch.dynamic_friction * N;
    // The patch slipped when the last iteration clamped a row (C13a): earlier ones do not count.
    patch.broken = false;
    for (int j = 0; j < patch.num_anchors; ++j) {
      ContactFrictionRow* rows = &frictions_[static_cast<size_t>(patch.first_friction + 2 * j)];
      if (!phase.tgs) {
        // C13: each row alone.
        for (int a = 0; a < 2; ++a) {
          ContactFrictionRow& row = rows[a];
          // C9: a kept anchor is pulled back to its ground point in the position iterations.
          const double bias = phase.velocity_iteration ? 0.0 : row.error / phase.dt;
          double next = row.impulse - row.mass * (row.J.dot(V) + bias);
          if (std::abs(next) > static_limit) {
            next = std::clamp(next, -dynamic_limit, dynamic_limit);
            patch.broken = true;
          }
          const double delta = next - row.impulse;
          row.impulse = next;
          apply(row.J, row.response, delta);
        }
      } else {
        // C14: both rows of the anchor together, each pulled back to where the anchor was.
        const double bias_scale = kPgsBias / phase.h;
        double next[2];
        for (int a = 0; a < 2; ++a)
          next[a] = rows[a].impulse -
                    rows[a].mass * (rows[a].J.dot(V) + bias_scale * (rows[a].error + rows[a].dx));
        const double magnitude = std::hypot(next[0], next[1]);
        if (magnitude > static_limit) {
          const double scale = std::min(dynamic_limit, magnitude) / magnitude;
          next[0] *= scale;
          next[1] *= scale;
          patch.broken = true;
        }
        for (int a = 0; a < 2; ++a) {
          const double delta = next[a] - rows[a].impulse;
          rows[a].impulse = next[a];
          apply(rows[a].J, rows[a].response, delta);
        }
      }
    }
  }
  return applied;
}

void ContactRows::track(const std::vector<Vec6>& link_velocity, double h) {
  for (int k = 0; k < num_patches_; ++k) {
    const ContactPatch& patch = patches_[static_cast<size_t>(k)];
    const Vec6& V = link_velocity[static_cast<size_t>(patch.link)];
    for (int r = patch.first_normal; r < patch.first_normal + patch.num_normals; ++r)
      normals_[static_cast<size_t>(r)].dx += h * normals_[static_cast<size_t>(r)].J.dot(V);
    for (int r = patch.first_friction; r < patch.first_friction + 2 * patch.num_anchors; ++r)
      frictions_[static_cast<size_t>(r)].dx += h * frictions_[static_cast<size_t>(r)].J.dot(V);
  }
}

void ContactRows::report(double dt, std::vector<ContactReport>& reports,
                         std::vector<Vec3>& link_force) const {
  std::fill(link_force.begin(), link_force.end(), Vec3::Zero());
  const double inv_dt = 1.0 / dt;
  for (int k = 0; k < num_patches_; ++k) {
    const ContactPatch& patch = patches_[static_cast<size_t>(k)];
    Vec3 total = Vec3::Zero();
    for (int r = patch.first_normal; r < patch.first_normal + patch.num_normals; ++r) {
      const double impulse = normals_[static_cast<size_t>(r)].impulse;
      reports[static_cast<size_t>(r)].normal_impulse = impulse;
      reports[static_cast<size_t>(r)].friction_impulse.setZero();
      total += impulse * normal_;
    }
    for (int j = 0; j < patch.num_anchors; ++j) {
      const ContactFrictionRow* rows = &frictions_[static_cast<size_t>(patch.first_friction + 2 * j)];
      const Vec3 impulse = rows[0].impulse * patch.t0 + rows[1].impulse * patch.t1;
      reports[static_cast<size_t>(patch.anchor_point[j])].friction_impulse = impulse;
      total += impulse;
    }
    link_force[static_cast<size_t>(patch.link)] += inv_dt * total;
  }
}

double ContactRows::work(const std::vector<Vec6>& link_velocity) const {
  double w = 0.0;
  for (int k = 0; k < num_patches_; ++k) {
    const ContactPatch& patch = patches_[static_cast<size_t>(k)];
    const Vec6& V = link_velocity[static_cast<size_t>(patch.link)];
    for (int r = patch.first_normal; r < patch.first_normal + patch.num_normals; ++r)
      w += normals_[static_cast<size_t>(r)].impulse * normals_[static_cast<size_t>(r)].J.dot(V);
    for (int r = patch.first_friction; r < patch.first_friction + 2 * patch.num_anchors; ++r)
      w += frictions_[static_cast<size_t>(r)].impulse * frictions_[static_cast<size_t>(r)].J.dot(V);
  }
  return w;
}

namespace contact_laws {

// Keeps four of count > 4 points in the first four places, as PhysX's reduction of a convex
// mesh's points does (docs/math/contact.md, G3): the deepest, the one farthest from it, the ones
// farthest on either side of the line through the two (the farthest on that side again when all
// lie on one side), then points shallower than 0.02 m swapped for deeper unchosen ones while the
// deepest is within it and some chosen one is not.
void reduce_points(Vec3* points, double* separations, char* taken, int count, const Vec3& n) {
  int chosen[kManifoldPoints];
  std::fill(taken, taken + count, 0);
  auto pick = [&](auto score) {
    int best = -1;
    double best_score = 0.0;
    for (int i = 0; i < count; ++i) {
      if (taken[i]) continue;
      const double v = score(i);
      if (best < 0 || v > best_score) {
        best = i;
        best_score = v;
      }
    }
    taken[best] = 1;
    return best;
  };
  chosen[0] = pick([&](int i) { return -separations[i]; });
  const Vec3 p0 = points[chosen[0]];
  chosen[1] = pick([&](int i) { return (points[i] - p0).squaredNorm(); });
  Vec3 side = (points[chosen[1]] - p0).cross(n);
  side = side.squaredNorm() > 0.0 ? Vec3(side.normalized()) : n;
  double lowest = 0.0;
  int low = -1;
  for (int i = 0; i < count; ++i) {
    const double d = (points[i] - p0).dot(side);
    if (!taken[i] && (low < 0 || d < lowest)) {
      low = i;
      lowest = d;
    }
  }
  chosen[2] = pick([&](int i) { return (points[i] - p0).dot(side); });
  const double highest = (points[chosen[2]] - p0).dot(side);
  if (lowest * highest > 0.0 || low == chosen[2])
    chosen[3] = pick([&](int i) { return (points[i] - p0).dot(side); });
  else
    taken[chosen[3] = low] = 1;
  constexpr double kShallow = 0.02;  // m: 0.02 of PhysX's tolerance length 1
  double deepest = separations[0], shallowest = separations[0];
  for (int i = 1; i < count; ++i) {
    deepest = std::min(deepest, separations[i]);
    shallowest = std::max(shallowest, separations[i]);
  }
  if (deepest < kShallow && shallowest > kShallow)
    for (int& c : chosen) {
      if (!(separations[c] > kShallow)) continue;
      int better = -1;
      for (int i = 0; i < count; ++i)
        if (!taken[i] && separations[i] < separations[c] && separations[i] < kShallow &&
            (better < 0 || separations[i] < separations[better]))
          better = i;
      if (better >= 0) taken[c = better] = 1;
    }
  Vec3 kept[kManifoldPoints];
  double kept_d[kManifoldPoints];
  for (int k = 0; k < kManifoldPoints; ++k) {
    kept[k] = points[chosen[k]];
    kept_d[k] = separations[chosen[k]];
  }
  for (int k = 0; k < kManifoldPoints; ++k) {
    points[k] = kept[k];
    separations[k] = kept_d[k];
  }
}

}  // namespace contact_laws
}  // namespace featherdrive
