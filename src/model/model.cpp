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

int Model::link_index(const std::string& name) const {
  for (int i = 0; i < num_links(); ++i)
    if (links[i].name == name) return i;
  throw std::invalid_argument("no link named '" + name + "' in the model");
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
