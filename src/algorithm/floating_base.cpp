// The floating root's world pose and velocity (docs/conventions.md, "Floating"): the root link's
// world pose is the joint frame's (R_T = E_T^T, r_T) composed with (R(Q), p), and its body-frame
// twist is the world one rotated into the link, w_b = R_w^T w, v_b = R_w^T v.
#include "featherdrive/algorithm/floating_base.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include "featherdrive/core/format.hpp"

namespace featherdrive {
namespace {

void check_model(const Model& model, const VecX& q, const VecX& qd, const char* what) {
  if (!model.floating_base())
    throw std::invalid_argument(std::string(what) + ": the model has no floating root");
  if (q.size() != model.nq || qd.size() != model.nv)
    throw std::invalid_argument(std::string(what) + ": q and qd must have " +
                                std::to_string(model.nq) + " and " + std::to_string(model.nv) +
                                " entries, got " + std::to_string(q.size()) + " and " +
                                std::to_string(qd.size()));
}

void check_finite(const Vec3& v, const char* name) {
  for (int i = 0; i < 3; ++i)
    if (!std::isfinite(v[i]))
      throw std::invalid_argument(std::string("base ") + name + "[" + std::to_string(i) +
                                  "] = " + format_double(v[i]) + " is not finite");
}

}  // namespace

void set_base_state(const Model& model, const BaseState& base, VecX& q, VecX& qd) {
  check_model(model, q, qd, "set_base_state");
  check_finite(base.position, "position");
  check_finite(base.linear_velocity, "linear_velocity");
  check_finite(base.angular_velocity, "angular_velocity");
  const Eigen::Vector4d wxyz(base.orientation.w(), base.orientation.x(), base.orientation.y(),
                             base.orientation.z());
  const double norm = wxyz.norm();
  if (!(norm > 1e-150 && std::isfinite(norm)))
    throw std::invalid_argument("base orientation (w, x, y, z) = (" + format_double(wxyz[0]) +
                                ", " + format_double(wxyz[1]) + ", " + format_double(wxyz[2]) +
                                ", " + format_double(wxyz[3]) +
                                ") has no rotation: its norm must be finite and > 0");
  const Mat3 R_world = Quat(wxyz[0] / norm, wxyz[1] / norm, wxyz[2] / norm, wxyz[3] / norm)
                           .toRotationMatrix();
  const Link& root = model.links[0];
  const Transform& X = root.tree_transform;  // world -> the root's joint frame
  const Quat Q(X.E * R_world);
  q.segment<3>(root.q_index) = X.E * (base.position - X.r);
  q.segment<4>(root.q_index + 3) << Q.w(), Q.x(), Q.y(), Q.z();
  qd.segment<3>(root.v_index) = R_world.transpose() * base.angular_velocity;
  qd.segment<3>(root.v_index + 3) = R_world.transpose() * base.linear_velocity;
}

BaseState base_state(const Model& model, const VecX& q, const VecX& qd) {
  check_model(model, q, qd, "base_state");
  const Link& root = model.links[0];
  const Transform& X = root.tree_transform;
  const auto w = q.segment<4>(root.q_index + 3);
  const Mat3 R_world = X.E.transpose() * Quat(w[0], w[1], w[2], w[3]).normalized().toRotationMatrix();
  BaseState base;
  base.position = X.r + X.E.transpose() * q.segment<3>(root.q_index);
  base.orientation = Quat(R_world);
  base.angular_velocity = R_world * qd.segment<3>(root.v_index);
  base.linear_velocity = R_world * qd.segment<3>(root.v_index + 3);
  return base;
}

}  // namespace featherdrive
