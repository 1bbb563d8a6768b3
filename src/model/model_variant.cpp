#include "featherdrive/model/model_variant.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "featherdrive/core/format.hpp"
#include "featherdrive/model/model_builder.hpp"

namespace featherdrive {
namespace {

template <class M>
bool same_bits(const M& a, const M& b) {
  return std::memcmp(a.data(), b.data(), sizeof(double) * static_cast<size_t>(a.size())) == 0;
}

}  // namespace

std::string topology_difference(const Model& a, const Model& b) {
  if (a.nq != b.nq || a.nv != b.nv || a.num_links() != b.num_links())
    return "nq " + std::to_string(a.nq) + ", nv " + std::to_string(a.nv) + ", " +
           std::to_string(a.num_links()) + " links vs nq " + std::to_string(b.nq) + ", nv " +
           std::to_string(b.nv) + ", " + std::to_string(b.num_links()) + " links";
  for (int i = 0; i < a.num_links(); ++i) {
    const Link& x = a.links[static_cast<size_t>(i)];
    const Link& y = b.links[static_cast<size_t>(i)];
    const std::string who = "link " + std::to_string(i) + " ('" + x.name + "'): ";
    if (x.name != y.name) return who + "name '" + x.name + "' vs '" + y.name + "'";
    if (x.joint_name != y.joint_name)
      return who + "joint name '" + x.joint_name + "' vs '" + y.joint_name + "'";
    if (x.parent != y.parent)
      return who + "parent " + std::to_string(x.parent) + " vs " + std::to_string(y.parent);
    if (x.joint_type != y.joint_type)
      return who + "joint type " + to_string(x.joint_type) + " vs " + to_string(y.joint_type);
    if (!same_bits(x.axis, y.axis))
      return who + "joint axis " + format_vec3(x.axis) + " vs " + format_vec3(y.axis);
    if (!same_bits(x.tree_transform.E, y.tree_transform.E) ||
        !same_bits(x.tree_transform.r, y.tree_transform.r))
      return who + "joint origin (tree transform) differs, at " + format_vec3(x.tree_transform.r) +
             " vs " + format_vec3(y.tree_transform.r);
    if (x.q_index != y.q_index || x.v_index != y.v_index)
      return who + "q/v index differs";
  }
  return "";
}

Model with_link_inertial(const Model& model, int link, double mass, const Vec3& com,
                         const Mat3& inertia_com) {
  if (link < 0 || link >= model.num_links())
    throw std::invalid_argument("link index " + std::to_string(link) + " is out of range [0, " +
                                std::to_string(model.num_links()) + ")");
  bool can_move = false;
  for (int i = link; i >= 0 && !can_move; i = model.links[static_cast<size_t>(i)].parent)
    can_move = model.links[static_cast<size_t>(i)].nv > 0;
  Model out = model;
  Link& target = out.links[static_cast<size_t>(link)];
  set_link_inertial(target, mass, com, inertia_com, can_move);
  double total_mass = 0.0, inertia_sum = 0.0;
  for (const Link& l : out.links) {
    total_mass += l.mass;
    inertia_sum += l.inertia.cwiseAbs().sum();
  }
  if (!std::isfinite(total_mass) || !std::isfinite(inertia_sum))
    throw ModelError("model: link '" + target.name + "': mass = " + format_double(mass) +
                     ": the model's total mass or inertia overflows");
  return out;
}

Model with_shapes(const Model& model,
                  const std::vector<std::pair<std::string, CollisionShape>>& shapes) {
  Model out = model;
  for (const auto& [name, given] : shapes) {
    CollisionShape shape = given;
    const std::string who = shape_label(shape, out.shapes.size(), name);
    check_shape(who, shape);
    NamedFrame frame;
    try {
      frame = model.frame(name);  // a link, or a merged link's frame on its link
    } catch (const std::invalid_argument& e) {
      throw ModelError("model: " + who + ": " + e.what());
    }
    shape.link = frame.link;
    shape.position = frame.position + frame.rotation * shape.position;
    shape.rotation = frame.rotation * shape.rotation;
    out.shapes.push_back(std::move(shape));
  }
  std::stable_sort(out.shapes.begin(), out.shapes.end(),
                   [](const CollisionShape& a, const CollisionShape& b) {
                     return a.link < b.link;  // the model's own first within a link
                   });
  return out;
}

Model with_armature(const Model& model, const VecX& armature) {
  if (armature.size() != model.nv)
    throw ModelError("model: armature has " + std::to_string(armature.size()) +
                     " values, expected nv = " + std::to_string(model.nv));
  for (int d = 0; d < model.nv; ++d)
    if (!std::isfinite(armature[d]) || armature[d] < 0.0)
      throw ModelError("model: joint '" +
                       model.links[static_cast<size_t>(model.dof_link[static_cast<size_t>(d)])]
                           .joint_name +
                       "': armature = " + format_double(armature[d]) +
                       " must be finite and >= 0 (dof " + std::to_string(d) + ")");
  Model out = model;
  out.armature = armature;
  return out;
}

}  // namespace featherdrive
