#include "featherdrive/algorithm/aba.hpp"

#include <Eigen/Cholesky>

#include "featherdrive/algorithm/kinematics.hpp"

namespace featherdrive {
namespace {

// U = IA S, D^-1 = (S^T U + armature)^-1 for one link.
void joint_inertia(const Model& model, const Link& link, const Mat6& IA, Mat6N& U, MatNN& D_inv) {
  if (link.nv == 0) return;
  U.noalias() = IA * link.motion_subspace;
  MatNN D = link.motion_subspace.transpose() * U;
  D.diagonal() += model.armature.segment(link.v_index, link.nv);
  if (link.nv == 1) {
    D_inv(0, 0) = 1.0 / D(0, 0);
  } else {
    D_inv = D.llt().solve(MatNN::Identity(link.nv, link.nv));
  }
}

}  // namespace

void articulated_inertias(const Model& model, Data& data) {
  for (int i = 0; i < model.num_links(); ++i) data.articulated_inertia[i] = model.links[i].inertia;
  for (int i = model.num_links() - 1; i >= 0; --i) {
    const Link& link = model.links[i];
    const Mat6& IA = data.articulated_inertia[i];
    joint_inertia(model, link, IA, data.U[i], data.D_inv[i]);
    if (link.parent < 0) continue;
    Mat6 Ia = IA;
    if (link.nv > 0) Ia.noalias() -= data.U[i] * data.D_inv[i] * data.U[i].transpose();
    data.articulated_inertia[link.parent] += data.parent_transform[i].transpose_inertia(Ia);
  }
}

const VecX& aba_from_kinematics(const Model& model, Data& data, const VecX& v, const VecX& tau) {
  (void)v;  // the velocities entered through data.velocity and data.bias_acceleration
  const int n = model.num_links();
  for (int i = 0; i < n; ++i) {
    const Link& link = model.links[i];
    const Vec6& vi = data.velocity[i];
    data.articulated_inertia[i] = link.inertia;
    data.articulated_bias[i] = cross_force(vi, link.inertia * vi);
  }
  for (int i = n - 1; i >= 0; --i) {
    const Link& link = model.links[i];
    const Mat6& IA = data.articulated_inertia[i];
    const Vec6& pA = data.articulated_bias[i];
    joint_inertia(model, link, IA, data.U[i], data.D_inv[i]);
    auto u = data.u.segment(link.v_index, link.nv);
    if (link.nv > 0) u = tau.segment(link.v_index, link.nv) - link.motion_subspace.transpose() * pA;
    if (link.parent < 0) continue;
    Mat6 Ia = IA;
    Vec6 pa = pA;
    if (link.nv > 0) {
      const Mat6N UD = data.U[i] * data.D_inv[i];
      Ia.noalias() -= UD * data.U[i].transpose();
      pa.noalias() += UD * u;
    }
    pa.noalias() += Ia * data.bias_acceleration[i];
    const Transform& X = data.parent_transform[i];
    data.articulated_inertia[link.parent] += X.transpose_inertia(Ia);
    data.articulated_bias[link.parent] += X.transpose_apply_force(pa);
  }
  Vec6 a_world = Vec6::Zero();
  a_world.tail<3>() = -model.gravity;
  for (int i = 0; i < n; ++i) {
    const Link& link = model.links[i];
    const Vec6& a_parent = link.parent >= 0 ? data.acceleration[link.parent] : a_world;
    Vec6 a = data.parent_transform[i].apply_motion(a_parent) + data.bias_acceleration[i];
    if (link.nv > 0) {
      auto qdd = data.qdd.segment(link.v_index, link.nv);
      qdd = data.D_inv[i] * (data.u.segment(link.v_index, link.nv) - data.U[i].transpose() * a);
      a.noalias() += link.motion_subspace * qdd;
    }
    data.acceleration[i] = a;
  }
  return data.qdd;
}

const VecX& aba(const Model& model, Data& data, const VecX& q, const VecX& v, const VecX& tau) {
  forward_kinematics(model, data, q, v);
  return aba_from_kinematics(model, data, v, tau);
}

}  // namespace featherdrive
