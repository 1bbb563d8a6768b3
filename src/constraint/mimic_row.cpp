#include "featherdrive/constraint/mimic_row.hpp"

#include <cmath>
#include <numeric>
#include <stdexcept>

#include "featherdrive/core/format.hpp"

namespace featherdrive {

std::string describe(const Model& model, const MimicJoint& m) {
  auto name = [&](int dof) {
    return dof >= 0 && dof < model.nv ? "'" + model.dof_names[dof] + "'"
                                      : "dof " + std::to_string(dof);
  };
  return "mimic joint " + name(m.dof_a) + " (follower) of " + name(m.dof_b) + " (leader)";
}

void validate_mimic_joints(const Model& model, const std::vector<MimicJoint>& mimic) {
  // Union-find over the dofs: a row joining two dofs already connected closes a cycle.
  std::vector<int> root(static_cast<size_t>(model.nv));
  std::iota(root.begin(), root.end(), 0);
  auto find = [&root](int d) {
    while (root[static_cast<size_t>(d)] != d) d = root[static_cast<size_t>(d)];
    return d;
  };
  for (const MimicJoint& m : mimic) {
    const std::string what = describe(model, m);
    for (const int dof : {m.dof_a, m.dof_b}) {
      if (dof < 0 || dof >= model.nv)
        throw std::invalid_argument(what + ": dof " + std::to_string(dof) +
                                    " is out of range [0, " + std::to_string(model.nv) + ")");
      const Link& link = model.links[model.dof_link[dof]];
      if (link.joint_type != JointType::revolute && link.joint_type != JointType::prismatic)
        throw std::invalid_argument(what + ": joint '" + link.joint_name + "' is " +
                                    to_string(link.joint_type) +
                                    "; mimic joints couple revolute and prismatic joints only");
    }
    if (m.dof_a == m.dof_b) throw std::invalid_argument(what + ": a joint cannot mimic itself");
    if (!std::isfinite(m.gear_ratio) || m.gear_ratio == 0.0)
      throw std::invalid_argument(what + ": gear_ratio = " + format_double(m.gear_ratio) +
                                  " must be finite and nonzero");
    if (!std::isfinite(m.offset))
      throw std::invalid_argument(what + ": offset = " + format_double(m.offset) +
                                  " must be finite");
    if (!std::isfinite(m.natural_frequency))
      throw std::invalid_argument(
          what + ": natural_frequency = " + format_double(m.natural_frequency) + " must be finite");
    if (!std::isfinite(m.damping_ratio))
      throw std::invalid_argument(what + ": damping_ratio = " + format_double(m.damping_ratio) +
                                  " must be finite");
    const int ra = find(m.dof_a), rb = find(m.dof_b);
    if (ra == rb)
      throw std::invalid_argument(what +
                                  ": closes a cycle of mimic joints (the two joints are "
                                  "already coupled through other mimic joints)");
    root[static_cast<size_t>(ra)] = rb;
  }
}

}  // namespace featherdrive
