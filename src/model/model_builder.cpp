#include "featherdrive/model/model_builder.hpp"

#include "featherdrive/core/format.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>

namespace featherdrive {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

std::string fmt(double v) { return format_double(v); }
std::string fmt(const Vec3& v) { return format_vec3(v); }

[[noreturn]] void fail(const std::string& what) { throw ModelError("model: " + what); }

int dof_count(JointType t) {
  switch (t) {
    case JointType::fixed: return 0;
    case JointType::revolute:
    case JointType::prismatic: return 1;
    case JointType::spherical: return 3;
    case JointType::floating: return 6;
  }
  return 0;
}

int config_count(JointType t) {
  switch (t) {
    case JointType::spherical: return 4;
    case JointType::floating: return 7;
    default: return dof_count(t);
  }
}

void check_finite(const std::string& who, const char* field, double v) {
  if (!std::isfinite(v)) fail(who + ": " + field + " = " + fmt(v) + " is not finite");
}
void check_finite(const std::string& who, const char* field, const Vec3& v) {
  if (!v.allFinite()) fail(who + ": " + field + " = " + fmt(v) + " is not finite");
}

void check_inertia(const std::string& who, const Mat3& I) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      if (!std::isfinite(I(r, c)))
        fail(who + ": inertia(" + std::to_string(r) + "," + std::to_string(c) + ") = " +
             fmt(I(r, c)) + " is not finite");
  const double scale = std::max(I.cwiseAbs().maxCoeff(), 1e-300);
  for (int r = 0; r < 3; ++r)
    for (int c = r + 1; c < 3; ++c)
      if (std::abs(I(r, c) - I(c, r)) > 1e-9 * scale)
        fail(who + ": inertia is not symmetric: inertia(" + std::to_string(r) + "," +
             std::to_string(c) + ") = " + fmt(I(r, c)) + " but inertia(" + std::to_string(c) +
             "," + std::to_string(r) + ") = " + fmt(I(c, r)));
  const Mat3 sym = 0.5 * (I + I.transpose());
  Eigen::SelfAdjointEigenSolver<Mat3> eig(sym);
  const Vec3 p = eig.eigenvalues();  // ascending
  if (!(p[0] > 0.0))
    fail(who + ": inertia is not positive definite: principal moments " + fmt(p));
  // Triangle inequality of the principal moments (a physical mass distribution needs it).
  if (p[0] + p[1] < p[2] * (1.0 - 1e-9))
    fail(who + ": inertia breaks the triangle inequality: principal moments " + fmt(p) +
         " (" + fmt(p[0]) + " + " + fmt(p[1]) + " < " + fmt(p[2]) + ")");
}

}  // namespace

std::string name_problem(const std::string& name) {
  static const char* const kHex = "0123456789abcdef";
  std::string shown, first;
  for (const char c : name) {
    const auto byte = static_cast<unsigned char>(c);
    if (byte >= 0x20 && byte != 0x7f) {
      shown += c;
      continue;
    }
    const std::string code = {'x', kHex[byte >> 4], kHex[byte & 15]};
    if (first.empty()) first = "0" + code;
    shown += "\\" + code;
  }
  if (first.empty()) return "";
  return "name '" + shown + "' contains a control character (" + first + ")";
}

namespace {
JointSpec joint_of(std::string name, JointType type, const Vec3& axis, const Vec3& xyz,
                   const Vec3& rpy) {
  JointSpec j;
  j.name = std::move(name);
  j.type = type;
  j.axis = axis;
  j.origin_xyz = xyz;
  j.origin_rpy = rpy;
  return j;
}
}  // namespace

JointSpec fixed_joint(std::string name, const Vec3& xyz, const Vec3& rpy) {
  return joint_of(std::move(name), JointType::fixed, Vec3::UnitX(), xyz, rpy);
}
JointSpec revolute_joint(std::string name, const Vec3& axis, const Vec3& xyz, const Vec3& rpy) {
  return joint_of(std::move(name), JointType::revolute, axis, xyz, rpy);
}
JointSpec prismatic_joint(std::string name, const Vec3& axis, const Vec3& xyz, const Vec3& rpy) {
  return joint_of(std::move(name), JointType::prismatic, axis, xyz, rpy);
}
JointSpec spherical_joint(std::string name, const Vec3& xyz, const Vec3& rpy) {
  return joint_of(std::move(name), JointType::spherical, Vec3::UnitX(), xyz, rpy);
}
JointSpec floating_joint(std::string name) {
  return joint_of(std::move(name), JointType::floating, Vec3::UnitX(), Vec3::Zero(), Vec3::Zero());
}

void set_link_inertial(Link& link, double mass, const Vec3& com, const Mat3& inertia,
                       bool can_move) {
  const std::string who_link = "link '" + link.name + "'";
  check_finite(who_link, "mass", mass);
  check_finite(who_link, "com", com);
  if (can_move || mass != 0.0) {
    if (!(mass > 0.0))
      fail(who_link + ": mass = " + fmt(mass) +
           (can_move ? " must be > 0 for a link that can move" : " must be >= 0"));
    check_inertia(who_link, inertia);
  } else if (!inertia.allFinite() || !inertia.isZero(0.0)) {
    check_inertia(who_link, inertia);  // names a non-finite entry first
    const Mat3 sym = 0.5 * (inertia + inertia.transpose());
    fail(who_link + ": inertia must be zero for a massless link (mass = 0), got principal " +
         "moments " + fmt(Eigen::SelfAdjointEigenSolver<Mat3>(sym).eigenvalues()));
  }
  link.mass = mass;
  link.com = com;
  link.inertia_com = 0.5 * (inertia + inertia.transpose());
  link.inertia = spatial_inertia(mass, com, link.inertia_com);
  // Finite inputs whose products or sums overflow would fail later, naming no field.
  if (!link.inertia.allFinite())
    fail(who_link + ": mass = " + fmt(mass) + " at com = " + fmt(com) +
         ": the spatial inertia (m c, m c c^T) overflows");
}

LinkSpec make_link(std::string name, std::string parent, double mass, const Vec3& com,
                   const Mat3& inertia, JointSpec joint) {
  LinkSpec l;
  l.name = std::move(name);
  l.parent = std::move(parent);
  l.mass = mass;
  l.com = com;
  l.inertia = inertia;
  l.joint = std::move(joint);
  return l;
}

ModelBuilder& ModelBuilder::set_gravity(const Vec3& gravity) {
  gravity_ = gravity;
  return *this;
}

ModelBuilder& ModelBuilder::add_link(LinkSpec link) {
  links_.push_back(std::move(link));
  return *this;
}

ModelBuilder& ModelBuilder::add_frame(std::string name, std::string link, const Vec3& xyz,
                                      const Mat3& rotation) {
  NamedFrame f;
  f.name = std::move(name);
  f.position = xyz;
  f.rotation = rotation;
  frames_.emplace_back(std::move(f), std::move(link));
  return *this;
}

ModelBuilder& ModelBuilder::add_shape(std::string link, CollisionShape shape) {
  shapes_.emplace_back(std::move(shape), std::move(link));
  return *this;
}

// A shape's sizes, pose and material (docs/math/contact.md, section 1).
void check_shape(const std::string& who, const CollisionShape& s) {
  const char* names[3] = {"radius", "half_length", ""};
  int count = 1;
  if (s.type == ShapeType::capsule || s.type == ShapeType::cylinder) count = 2;
  if (s.type == ShapeType::box || s.type == ShapeType::ellipsoid) {
    const bool box = s.type == ShapeType::box;
    names[0] = box ? "half_extent.x" : "semi_axis.x";
    names[1] = box ? "half_extent.y" : "semi_axis.y";
    names[2] = box ? "half_extent.z" : "semi_axis.z";
    count = 3;
  }
  if (s.type == ShapeType::convex) {
    count = 0;
    if (s.vertices.empty()) fail(who + ": vertices: a convex shape needs at least one");
    for (size_t k = 0; k < s.vertices.size(); ++k)
      check_finite(who, ("vertices[" + std::to_string(k) + "]").c_str(), s.vertices[k]);
  }
  for (int k = 0; k < count; ++k)
    if (!(std::isfinite(s.size[k]) && s.size[k] > 0.0))
      fail(who + ": " + names[k] + " = " + fmt(s.size[k]) + " must be finite and > 0");
  check_finite(who, "position", s.position);
  if (!s.rotation.allFinite())
    fail(who + ": rotation has an entry that is not finite (" +
         fmt(Vec3(s.rotation.row(0).transpose())) + " ...)");
  const double off = (s.rotation.transpose() * s.rotation - Mat3::Identity()).cwiseAbs().maxCoeff();
  const double det = s.rotation.determinant();
  if (!(off <= 1e-9) || det < 0.0)
    fail(who + ": rotation is not a rotation matrix (max |R^T R - I| = " + fmt(off) +
         ", det R = " + fmt(det) + ")");
  const Material& m = s.material;
  auto check_friction = [&](const char* field, double v) {
    if (!(std::isfinite(v) && v >= 0.0))
      fail(who + ": " + field + " = " + fmt(v) + " must be finite and >= 0");
  };
  check_friction("static_friction", m.static_friction);
  check_friction("dynamic_friction", m.dynamic_friction);
  if (!(m.restitution >= 0.0 && m.restitution <= 1.0))
    fail(who + ": restitution = " + fmt(m.restitution) + " must be in [0, 1]");
}

std::string shape_label(const CollisionShape& shape, size_t index, const std::string& link) {
  return "shape " + (shape.name.empty() ? "#" + std::to_string(index) : "'" + shape.name + "'") +
         " (" + to_string(shape.type) + ") of link '" + link + "'";
}

ModelBuilder& ModelBuilder::add_unsupported_shape(std::string description) {
  unsupported_shapes_.push_back(std::move(description));
  return *this;
}

Model ModelBuilder::build() const {
  if (!gravity_.allFinite()) fail("gravity = " + fmt(gravity_) + " is not finite");
  if (links_.empty()) fail("the model has no links");

  // Names and the tree.
  std::map<std::string, int> by_name;
  std::map<std::string, int> joint_names;
  for (int i = 0; i < static_cast<int>(links_.size()); ++i) {
    const LinkSpec& l = links_[i];
    if (l.name.empty()) fail("link #" + std::to_string(i) + ": name is empty");
    if (const std::string why = name_problem(l.name); !why.empty()) fail("link " + why);
    if (const std::string why = name_problem(l.joint.name); !why.empty()) fail("joint " + why);
    if (!by_name.emplace(l.name, i).second) fail("link '" + l.name + "': duplicate link name");
    if (l.joint.name.empty()) fail("link '" + l.name + "': joint name is empty");
    if (auto [it, added] = joint_names.emplace(l.joint.name, i); !added)
      fail("joint '" + l.joint.name + "': duplicate joint name (links '" + links_[it->second].name +
           "' and '" + l.name + "')");
  }
  int root = -1;
  std::vector<int> parent(links_.size(), -1);
  for (int i = 0; i < static_cast<int>(links_.size()); ++i) {
    const LinkSpec& l = links_[i];
    if (l.parent.empty()) {
      if (root >= 0)
        fail("more than one root: links '" + links_[root].name + "' and '" + l.name +
             "' have no parent");
      root = i;
      continue;
    }
    auto it = by_name.find(l.parent);
    if (it == by_name.end())
      fail("link '" + l.name + "': parent = '" + l.parent + "' is not a link of the model");
    parent[i] = it->second;
  }
  if (root < 0) fail("the model has no root link (every link names a parent)");
  // Every walk up from a link must reach the root. Each link is marked by the first walk that
  // reaches it, so a walk stops at a link seen before: O(n) however long the chain.
  std::vector<int> walk(links_.size(), -1);
  for (int i = 0; i < static_cast<int>(links_.size()); ++i) {
    int j = i;
    while (j >= 0 && walk[j] < 0) {
      walk[j] = i;
      j = parent[j];
    }
    if (j < 0 || walk[j] != i) continue;  // the root, or a link an earlier walk took to it
    // Back on this walk: a cycle. Name it once around, starting 2n + 1 steps up from i (where
    // messages have always started it).
    j = i;
    for (size_t n = 0; n <= 2 * links_.size(); ++n) j = parent[j];
    if (parent[j] == j)
      fail("link '" + links_[j].name + "': parent = '" + links_[j].name + "' is the link itself");
    std::string cycle = "'" + links_[j].name + "'";
    for (int k = parent[j]; k != j; k = parent[k]) cycle += " -> '" + links_[k].name + "'";
    fail("links " + cycle + " -> '" + links_[j].name +
         "' form a cycle (each names the next as parent)");
  }

  // Children in insertion order; depth-first preorder from the root.
  std::vector<std::vector<int>> children(links_.size());
  for (int i = 0; i < static_cast<int>(links_.size()); ++i)
    if (parent[i] >= 0) children[parent[i]].push_back(i);
  std::vector<int> order;
  std::vector<int> stack{root};
  while (!stack.empty()) {
    const int i = stack.back();
    stack.pop_back();
    order.push_back(i);
    for (auto c = children[i].rbegin(); c != children[i].rend(); ++c) stack.push_back(*c);
  }
  std::vector<int> new_index(links_.size());
  for (int k = 0; k < static_cast<int>(order.size()); ++k) new_index[order[k]] = k;

  Model model;
  model.gravity = gravity_;
  model.links.resize(order.size());
  std::vector<double> armature, lower, upper, effort, velocity, damping, friction;
  std::vector<bool> can_move(order.size(), false);
  // A moving link may be massless when a link below it has mass (the links of an MJCF body with
  // several joints): its dof then moves that mass, so ABA's divisor is not zero.
  std::vector<bool> mass_below(order.size(), false);
  for (int k = static_cast<int>(order.size()) - 1; k > 0; --k) {
    const int p = new_index[parent[order[k]]];
    mass_below[p] = mass_below[p] || mass_below[k] || links_[order[k]].mass > 0.0;
  }
  double total_mass = 0.0, inertia_sum = 0.0;
  for (int k = 0; k < static_cast<int>(order.size()); ++k) {
    const LinkSpec& s = links_[order[k]];
    const JointSpec& j = s.joint;
    const std::string who_link = "link '" + s.name + "'";
    const std::string who_joint = "joint '" + j.name + "'";
    Link& link = model.links[k];
    link.name = s.name;
    link.joint_name = j.name;
    link.parent = parent[order[k]] >= 0 ? new_index[parent[order[k]]] : -1;
    if (link.parent >= 0) model.links[link.parent].children.push_back(k);
    link.joint_type = j.type;
    if (j.type == JointType::floating && link.parent >= 0)
      fail(who_joint + ": type = floating is allowed only for the root link's joint");
    link.nq = config_count(j.type);
    link.nv = dof_count(j.type);
    link.q_index = model.nq;
    link.v_index = model.nv;
    model.nq += link.nq;
    model.nv += link.nv;
    can_move[k] = link.nv > 0 || (link.parent >= 0 && can_move[link.parent]);

    // Joint geometry.
    check_finite(who_joint, "origin_xyz", j.origin_xyz);
    check_finite(who_joint, "origin_rpy", j.origin_rpy);
    check_finite(who_joint, "axis", j.axis);
    link.tree_transform = Transform::from_pose(rotation_from_rpy(j.origin_rpy), j.origin_xyz);
    if (j.type == JointType::revolute || j.type == JointType::prismatic) {
      const double n = j.axis.norm();
      if (!(n > 1e-12)) fail(who_joint + ": axis = " + fmt(j.axis) + " is zero");
      link.axis = j.axis / n;
    }
    link.motion_subspace = Mat6N::Zero(6, link.nv);
    switch (j.type) {
      case JointType::revolute: link.motion_subspace.col(0).head<3>() = link.axis; break;
      case JointType::prismatic: link.motion_subspace.col(0).tail<3>() = link.axis; break;
      case JointType::spherical: link.motion_subspace.topRows<3>().setIdentity(); break;
      case JointType::floating: link.motion_subspace.setIdentity(); break;
      case JointType::fixed: break;
    }

    set_link_inertial(link, s.mass, s.com, s.inertia, can_move[k] && !mass_below[k]);
    total_mass += s.mass;
    inertia_sum += link.inertia.cwiseAbs().sum();
    if (!std::isfinite(total_mass) || !std::isfinite(inertia_sum))
      fail(who_link + ": mass = " + fmt(s.mass) + ", inertia " + fmt(s.inertia.diagonal()) +
           ": the model's total mass or inertia overflows");

    // Per-dof parameters.
    if (!j.armature.empty() && link.nv == 0)
      fail(who_joint + ": armature is set but a fixed joint has no degree of freedom");
    if (!j.armature.empty() && static_cast<int>(j.armature.size()) != 1 &&
        static_cast<int>(j.armature.size()) != link.nv)
      fail(who_joint + ": armature has " + std::to_string(j.armature.size()) + " values, expected " +
           (link.nv == 1 ? std::string("1") : "1 or " + std::to_string(link.nv)) + " (one per dof)");
    for (double a : j.armature)
      if (!std::isfinite(a) || a < 0.0)
        fail(who_joint + ": armature = " + fmt(a) + " must be finite and >= 0");
    if (std::isnan(j.lower_limit)) fail(who_joint + ": lower_limit is NaN");
    if (std::isnan(j.upper_limit)) fail(who_joint + ": upper_limit is NaN");
    if (j.lower_limit == kInf) fail(who_joint + ": lower_limit = inf leaves no position");
    if (j.upper_limit == -kInf) fail(who_joint + ": upper_limit = -inf leaves no position");
    if (j.lower_limit > j.upper_limit)
      fail(who_joint + ": lower_limit = " + fmt(j.lower_limit) + " is above upper_limit = " +
           fmt(j.upper_limit));
    if (std::isnan(j.effort_limit) || j.effort_limit < 0.0)
      fail(who_joint + ": effort_limit = " + fmt(j.effort_limit) + " must be >= 0");
    if (std::isnan(j.velocity_limit) || j.velocity_limit < 0.0)
      fail(who_joint + ": velocity_limit = " + fmt(j.velocity_limit) + " must be >= 0");
    if (!std::isfinite(j.damping) || j.damping < 0.0)
      fail(who_joint + ": damping = " + fmt(j.damping) + " must be finite and >= 0");
    if (!std::isfinite(j.friction) || j.friction < 0.0)
      fail(who_joint + ": friction = " + fmt(j.friction) + " must be finite and >= 0");
    const bool bounded = link.nv == 1;
    for (int d = 0; d < link.nv; ++d) {
      armature.push_back(j.armature.empty() ? 0.0
                         : j.armature.size() == 1 ? j.armature[0]
                                                  : j.armature[d]);
      lower.push_back(bounded ? j.lower_limit : -std::numeric_limits<double>::infinity());
      upper.push_back(bounded ? j.upper_limit : std::numeric_limits<double>::infinity());
      effort.push_back(j.effort_limit);
      velocity.push_back(j.velocity_limit);
      damping.push_back(j.damping);
      friction.push_back(j.friction);
      model.dof_link.push_back(k);
    }
    // PhysX's axes of a spherical joint: eTWIST, eSWING1, eSWING2 about the joint frame's x, y, z.
    static const char* const kSpherical[] = {"twist", "swing1", "swing2"};
    static const char* const kFloating[] = {"wx", "wy", "wz", "vx", "vy", "vz"};
    for (int d = 0; d < link.nv; ++d) {
      if (link.nv == 1) model.dof_names.push_back(j.name);
      else if (link.nv == 3) model.dof_names.push_back(j.name + ":" + kSpherical[d]);
      else model.dof_names.push_back(j.name + ":" + kFloating[d]);
    }
  }
  for (int k = static_cast<int>(order.size()) - 1; k >= 0; --k) {
    Link& link = model.links[k];
    link.subtree_end = link.children.empty() ? k + 1 : model.links[link.children.back()].subtree_end;
  }
  auto to_vec = [](const std::vector<double>& v) {
    return VecX(Eigen::Map<const VecX>(v.data(), static_cast<Eigen::Index>(v.size())));
  };
  model.armature = to_vec(armature);
  model.lower_limit = to_vec(lower);
  model.upper_limit = to_vec(upper);
  model.effort_limit = to_vec(effort);
  model.velocity_limit = to_vec(velocity);
  model.damping = to_vec(damping);
  model.friction = to_vec(friction);
  std::map<std::string, int> frame_names;
  for (auto [frame, link] : frames_) {
    const std::string who = "frame '" + frame.name + "'";
    if (const std::string why = name_problem(frame.name); !why.empty()) fail("frame " + why);
    if (by_name.count(frame.name)) fail(who + ": a link has this name");
    if (!frame_names.emplace(frame.name, 0).second) fail(who + ": duplicate frame name");
    const auto it = by_name.find(link);
    if (it == by_name.end()) fail(who + ": link = '" + link + "' is not a link of the model");
    check_finite(who, "xyz", frame.position);
    if (!frame.rotation.allFinite()) fail(who + ": rotation is not finite");
    frame.link = new_index[it->second];
    model.frames.push_back(std::move(frame));
  }
  for (auto [shape, link] : shapes_) {
    const std::string who = shape_label(shape, model.shapes.size(), link);
    check_shape(who, shape);
    if (const auto it = by_name.find(link); it != by_name.end()) {
      shape.link = new_index[it->second];
    } else {
      const std::string& frame = link;  // this clang cannot capture a structured binding
      const auto f = std::find_if(model.frames.begin(), model.frames.end(),
                                  [&frame](const NamedFrame& x) { return x.name == frame; });
      if (f == model.frames.end()) fail(who + ": the link is not a link or frame of the model");
      shape.link = f->link;  // a merged link: its pose in the link it went into
      shape.position = f->position + f->rotation * shape.position;
      shape.rotation = f->rotation * shape.rotation;
    }
    model.shapes.push_back(std::move(shape));
  }
  std::stable_sort(model.shapes.begin(), model.shapes.end(),
                   [](const CollisionShape& a, const CollisionShape& b) { return a.link < b.link; });
  model.unsupported_shapes = unsupported_shapes_;
  return model;
}

}  // namespace featherdrive
