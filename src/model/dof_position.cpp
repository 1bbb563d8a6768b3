#include "featherdrive/model/dof_position.hpp"

#include <stdexcept>
#include <string>

#include "featherdrive/constraint/spherical_axes.hpp"

namespace featherdrive {
namespace {

const Link& position_link(const Model& model, int dof) {
  if (dof < 0 || dof >= model.nv)
    throw std::invalid_argument("dof " + std::to_string(dof) + " out of range (the model has " +
                                std::to_string(model.nv) + (model.nv == 1 ? " dof)" : " dofs)"));
  const Link& link = model.links[static_cast<size_t>(model.dof_link[static_cast<size_t>(dof)])];
  if (link.nv != 1 && link.joint_type != JointType::spherical)
    throw std::invalid_argument("dof " + std::to_string(dof) + " ('" +
                                model.dof_names[static_cast<size_t>(dof)] +
                                "') is a floating root's: its position is the root's 7 q entries");
  return link;
}

}  // namespace

bool has_dof_position(const Model& model, int dof) {
  if (dof < 0 || dof >= model.nv) return false;
  const Link& link = model.links[static_cast<size_t>(model.dof_link[static_cast<size_t>(dof)])];
  return link.nv == 1 || link.joint_type == JointType::spherical;
}

double dof_position(const Model& model, const double* q, int dof) {
  const Link& link = position_link(model, dof);
  const double* x = q + link.q_index;
  if (link.nv == 1) return x[0];
  return spherical_joint_positions(Quat(x[0], x[1], x[2], x[3]))[dof - link.v_index];
}

void set_dof_position(const Model& model, double* q, int dof, double value) {
  const Link& link = position_link(model, dof);
  double* x = q + link.q_index;
  if (link.nv == 1) {
    x[0] = value;
    return;
  }
  Vec3 theta = spherical_joint_positions(Quat(x[0], x[1], x[2], x[3]));
  theta[dof - link.v_index] = value;
  const double angle = theta.norm();
  const Quat Q = angle > 0.0 ? Quat(Eigen::AngleAxisd(angle, theta / angle)) : Quat::Identity();
  x[0] = Q.w();
  x[1] = Q.x();
  x[2] = Q.y();
  x[3] = Q.z();
}

}  // namespace featherdrive
