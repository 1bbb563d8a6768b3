#include "featherdrive/model/model.hpp"

#include <algorithm>

#include <stdexcept>

namespace featherdrive {

const char* to_string(JointType type) {
  switch (type) {
    case JointType::fixed: return "fixed";
    case JointType::revolute: return "revolute";
    case JointType::prismatic: return "prismatic";
    case JointType::spherical: return "spherical";
    case JointType::floating: return "floating";
  }
  return "unknown";
}

const char* to_string(ShapeType type) {
  switch (type) {
    case ShapeType::sphere: return "sphere";
    case ShapeType::capsule: return "capsule";
    case ShapeType::box: return "box";
    case ShapeType::ellipsoid: return "ellipsoid";
    case ShapeType::cylinder: return "cylinder";
    case ShapeType::convex: return "convex";
  }
  return "unknown";
}

namespace {

// Edit distance with adjacent transpositions (optimal string alignment): "tpc" is 1 from "tcp".
size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::vector<size_t>> d(a.size() + 1, std::vector<size_t>(b.size() + 1));
  for (size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (size_t i = 1; i <= a.size(); ++i)
    for (size_t j = 1; j <= b.size(); ++j) {
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1,
                          d[i - 1][j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1)});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  return d[a.size()][b.size()];
}

// "; nearest: 'a', 'b', 'c'": the three names closest to `name`, nearest first.
std::string nearest(const std::string& name, std::vector<std::string> names) {
  std::stable_sort(names.begin(), names.end(), [&](const std::string& a, const std::string& b) {
    return edit_distance(name, a) < edit_distance(name, b);
  });
  std::string out;
  for (size_t i = 0; i < std::min<size_t>(names.size(), 3); ++i)
    out += (i ? ", '" : "; nearest: '") + names[i] + "'";
  return out;
}

}  // namespace

int Model::link_index(const std::string& name) const {
  for (int i = 0; i < num_links(); ++i)
    if (links[i].name == name) return i;
  std::vector<std::string> names;
  for (const Link& l : links) names.push_back(l.name);
  throw std::invalid_argument("no link named '" + name + "' in the model" + nearest(name, names));
}

NamedFrame Model::frame(const std::string& name) const {
  for (int i = 0; i < num_links(); ++i)
    if (links[i].name == name) return NamedFrame{name, i, Vec3::Zero(), Mat3::Identity()};
  for (const NamedFrame& f : frames)
    if (f.name == name) return f;
  std::vector<std::string> names;
  for (const Link& l : links) names.push_back(l.name);
  for (const NamedFrame& f : frames) names.push_back(f.name);
  throw std::invalid_argument("no link or frame named '" + name + "'" + nearest(name, names));
}

int Model::joint_link_index(const std::string& joint_name) const {
  for (int i = 0; i < num_links(); ++i)
    if (links[i].joint_name == joint_name) return i;
  throw std::invalid_argument("no joint named '" + joint_name + "' in the model");
}

int Model::dof_index(const std::string& joint_name) const {
  // One axis of a multi-dof joint by its dof name ("ball:swing1"); joint names come first.
  const bool is_joint = std::any_of(links.begin(), links.end(),
                                    [&](const Link& l) { return l.joint_name == joint_name; });
  if (!is_joint)
    for (size_t d = 0; d < dof_names.size(); ++d)
      if (dof_names[d] == joint_name) return static_cast<int>(d);
  const Link& link = links[joint_link_index(joint_name)];
  if (link.nv == 0)
    throw std::invalid_argument("joint '" + joint_name + "' is fixed and has no degree of freedom");
  return link.v_index;
}

VecX Model::neutral_configuration() const {
  VecX q = VecX::Zero(nq);
  for (const Link& link : links) {
    if (link.joint_type == JointType::spherical) q[link.q_index] = 1.0;      // w of (w, x, y, z)
    if (link.joint_type == JointType::floating) q[link.q_index + 3] = 1.0;  // after the position
  }
  return q;
}

}  // namespace featherdrive
