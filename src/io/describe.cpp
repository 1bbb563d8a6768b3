#include "featherdrive/io/describe.hpp"

#include "featherdrive/core/format.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <map>
#include <sstream>
#include <utility>
#include <vector>

namespace featherdrive {
namespace {

// Six significant digits: for reading, not for reading back.
std::string num(double v) {
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  std::ostringstream s;
  s << std::setprecision(6) << v;
  return s.str();
}

std::string vec(const Vec3& v) {
  return "[" + num(v.x()) + ", " + num(v.y()) + ", " + num(v.z()) + "]";
}

std::string inertia(const Mat3& I) {
  const bool diagonal = I(0, 1) == 0.0 && I(0, 2) == 0.0 && I(1, 2) == 0.0;
  if (diagonal) return "diag " + vec(I.diagonal());
  return "ixx " + num(I(0, 0)) + ", iyy " + num(I(1, 1)) + ", izz " + num(I(2, 2)) + ", ixy " +
         num(I(0, 1)) + ", ixz " + num(I(0, 2)) + ", iyz " + num(I(1, 2));
}

// Indentation shows the tree up to this depth; deeper links print their depth as a number, so a
// long chain's output stays linear in its length.
constexpr int kMaxIndent = 32;

void link_line(std::ostringstream& out, const Model& model, const std::string& merged, int i,
               int depth) {
  const Link& link = model.links[i];
  const std::string pad(2 * std::min(depth, kMaxIndent), ' ');
  const std::string more = pad + "      ";
  const bool angular = link.joint_type == JointType::revolute;
  const char* pos_unit = angular ? "rad" : "m";
  const char* force_unit = angular ? "Nm" : "N";
  out << pad << "- ";
  if (depth > kMaxIndent) out << "(depth " << depth << ") ";
  out << link.name;
  if (link.parent < 0) {
    out << "  (root, "
        << (link.joint_type == JointType::floating ? "floating" : "welded to the world") << ")\n";
  } else {
    const Vec3 xyz = link.tree_transform.r;
    out << "  <- " << link.joint_name << ": " << to_string(link.joint_type);
    if (link.nv == 1) out << " about " << (angular ? "" : "along ") << vec(link.axis);
    out << ", origin " << vec(xyz) << " m\n";
    if (link.nv == 1) {
      const int d = link.v_index;
      out << more << "dof " << d << ", limits ";
      if (std::isinf(model.lower_limit[d]) && std::isinf(model.upper_limit[d]))
        out << "none (continuous)";
      else
        out << "[" << num(model.lower_limit[d]) << ", " << num(model.upper_limit[d]) << "] "
            << pos_unit;
      out << ", effort " << num(model.effort_limit[d]) << " " << force_unit << ", velocity "
          << num(model.velocity_limit[d]) << " " << pos_unit << "/s";
      if (model.damping[d] != 0.0 || model.friction[d] != 0.0)
        out << ", damping " << num(model.damping[d]) << ", friction " << num(model.friction[d]);
      out << "\n";
    }
  }
  out << more << "mass " << num(link.mass) << " kg, com " << vec(link.com) << " m, inertia "
      << inertia(link.inertia_com) << " kg m^2\n";
  if (!merged.empty()) out << more << "merged through fixed joints: " << merged << "\n";
}

// The tree depth first, children in order, with an explicit stack: a chain of any length.
void link_lines(std::ostringstream& out, const UrdfRobot& robot, const Model& model) {
  std::map<std::string, std::string> merged;  // link -> the links merged into it
  for (const auto& [name, m] : robot.merged) {
    std::string& list = merged[m.into];
    list += (list.empty() ? "" : ", ") + name;
  }
  std::vector<std::pair<int, int>> stack{{0, 0}};  // link, depth
  while (!stack.empty()) {
    const auto [i, depth] = stack.back();
    stack.pop_back();
    const auto it = merged.find(model.links[i].name);
    link_line(out, model, it == merged.end() ? std::string() : it->second, i, depth);
    const std::vector<int>& children = model.links[i].children;
    for (auto c = children.rbegin(); c != children.rend(); ++c) stack.emplace_back(*c, depth + 1);
  }
}

std::string shape_text(const CollisionShape& s) {
  std::string out = to_string(s.type);
  if (!s.name.empty()) out += " '" + s.name + "'";
  if (s.type == ShapeType::box)
    out += " (half extents " + vec(s.size) + ")";
  else if (s.type == ShapeType::ellipsoid)
    out += " (semi-axes " + vec(s.size) + ")";
  else if (s.type == ShapeType::convex)
    out += " (" + std::to_string(s.vertices.size()) + " hull vertices)";
  else if (s.type == ShapeType::capsule || s.type == ShapeType::cylinder)
    out += " (r " + num(s.size.x()) + ", half length " + num(s.size.y()) + ")";
  else
    out += " (r " + num(s.size.x()) + ")";
  return out + " at " + vec(s.position) + " m";
}

}  // namespace

std::string describe_shapes(const Model& model, const std::string& indent) {
  std::ostringstream out;
  for (size_t i = 0; i < model.shapes.size(); ++i) {
    const CollisionShape& s = model.shapes[i];
    const bool first = i == 0 || model.shapes[i - 1].link != s.link;
    if (first) out << indent << model.links[static_cast<size_t>(s.link)].name << ": ";
    else out << ", ";
    out << shape_text(s);
    if (i + 1 == model.shapes.size() || model.shapes[i + 1].link != s.link) out << "\n";
  }
  return out.str();
}

std::string describe_ground(const Ground& g) {
  return "height " + num(g.height) + " m, normal " + vec(g.normal) + ", friction " +
         num(g.material.static_friction) + " / " + num(g.material.dynamic_friction) +
         ", restitution " + num(g.material.restitution);
}

std::string describe(const UrdfRobot& robot) {
  const Model& model = *robot.model;
  double total = 0.0;
  for (const Link& l : model.links) total += l.mass;
  std::ostringstream out;
  out << "robot '" << robot.name << "' from " << robot.path.string() << "\n";
  out << "  " << count_of(static_cast<long>(robot.joint_order.size()), "joint") << " in the file, "
      << count_of(model.num_links(), "link") << " after merging " << robot.merged.size()
      << " fixed, " << count_of(model.nv, "dof") << ", "
      << (model.floating_base() ? "floating base" : "fixed base") << ", total mass " << num(total)
      << " kg\n\ntree (inertia about the centre of mass, link axes):\n";
  link_lines(out, robot, model);
  out << "\ndofs in the file's order:";
  for (int d : robot.dof_order) out << " " << model.dof_names[d];
  out << "\n";
  for (const UrdfMimic& m : robot.mimics)
    out << "mimic: " << m.joint << " = " << num(m.multiplier) << " * " << m.leader << " + "
        << num(m.offset) << " (a mimic joint in scenes)\n";
  for (const UrdfRobot::Spring& s : robot.springs)
    out << "joint spring: " << s.joint << ", stiffness " << num(s.stiffness) << ", reference "
        << num(s.reference) << " (the joint_spring row in scenes)\n";
  if (!model.shapes.empty())
    out << "\ncollision shapes (" << model.shapes.size() << ", poses in the link frame):\n"
        << describe_shapes(model, "  ");
  for (const std::string& what : model.unsupported_shapes)
    out << "not usable by contacts yet: " << what << "\n";
  if (robot.ground)
    out << "ground (the file's floor): " << describe_ground(*robot.ground) << "\n";
  return out.str();
}

}  // namespace featherdrive
