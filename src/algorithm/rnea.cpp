#include "featherdrive/algorithm/rnea.hpp"

#include "featherdrive/algorithm/kinematics.hpp"

namespace featherdrive {
namespace {

// RNEA with v and a optional (null: zero), so that the bias and gravity terms need no zero
// vector of the caller's.
const VecX& rnea_impl(const Model& model, Data& data, const VecX& q, const VecX* v,
                      const VecX* a) {
  if (v) {
    forward_kinematics(model, data, q, *v);
  } else {
    forward_kinematics(model, data, q);
    for (int i = 0; i < model.num_links(); ++i) {
      data.velocity[i].setZero();
      data.bias_acceleration[i].setZero();
    }
  }
  Vec6 a_world = Vec6::Zero();
  a_world.tail<3>() = -model.gravity;  // gravity as an upward acceleration of the world
  for (int i = 0; i < model.num_links(); ++i) {
    const Link& link = model.links[i];
    const Vec6& a_parent = link.parent >= 0 ? data.acceleration[link.parent] : a_world;
    Vec6 ai = data.parent_transform[i].apply_motion(a_parent);
    if (a) ai.noalias() += link.motion_subspace * a->segment(link.v_index, link.nv);
    ai += data.bias_acceleration[i];  // in rnea's original order: the same bits
    data.acceleration[i] = ai;
    const Vec6& vi = data.velocity[i];
    data.force[i] = link.inertia * ai + cross_force(vi, link.inertia * vi);
  }
  for (int i = model.num_links() - 1; i >= 0; --i) {
    const Link& link = model.links[i];
    auto tau_i = data.tau.segment(link.v_index, link.nv);
    tau_i.noalias() = link.motion_subspace.transpose() * data.force[i];
    if (a)
      tau_i += model.armature.segment(link.v_index, link.nv)
                   .cwiseProduct(a->segment(link.v_index, link.nv));
    if (link.parent >= 0)
      data.force[link.parent] += data.parent_transform[i].transpose_apply_force(data.force[i]);
  }
  return data.tau;
}

}  // namespace

const VecX& rnea(const Model& model, Data& data, const VecX& q, const VecX& v, const VecX& a) {
  return rnea_impl(model, data, q, &v, &a);
}

const VecX& nonlinear_effects(const Model& model, Data& data, const VecX& q, const VecX& v) {
  return rnea_impl(model, data, q, &v, nullptr);
}

const VecX& generalized_gravity(const Model& model, Data& data, const VecX& q) {
  return rnea_impl(model, data, q, nullptr, nullptr);
}

}  // namespace featherdrive
