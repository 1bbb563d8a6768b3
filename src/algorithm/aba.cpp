// The articulated-body algorithm in frame 0 (world axes, origin at the root link's origin;
// docs/math/unit_response.md, "Frame 0"): every link's subspace and inertia are brought into that
// frame once, after which a child hands its articulated inertia and bias force to its parent by
// plain addition. 1-dof joints (S a 6-vector, D a number) take a path of their own.
#include "featherdrive/algorithm/aba.hpp"

#include <Eigen/Cholesky>

#include "featherdrive/algorithm/kinematics.hpp"

namespace featherdrive {
namespace {

// The spatial inertia in frame 0 of a link with orientation R at p (relative to the frame origin):
// [Ic + m c x c x^T, m c x; m c x^T, m 1] with c its centre of mass and Ic its inertia about it,
// both in frame 0. Ic = R Ic_link R^T is formed on its six distinct entries.
void inertia_in_frame0(const Data::LinkConstants& link, bool diagonal, const Mat3& R,
                       const Vec3& p, Mat6& I) {
  const double m = link.mass;
  const Vec3 c = p + R * link.com;
  Mat3 RI;  // R Ic_link, or R's columns scaled by the principal moments
  if (diagonal) RI = R * link.inertia_com.diagonal().asDiagonal();
  else RI.noalias() = R * link.inertia_com;
  const double cc = c.squaredNorm();
  for (int r = 0; r < 3; ++r)
    for (int k = r; k < 3; ++k) {
      double a = RI(r, 0) * R(k, 0) + RI(r, 1) * R(k, 1) + RI(r, 2) * R(k, 2) - m * c[r] * c[k];
      if (r == k) a += m * cc;
      I(r, k) = a;
      I(k, r) = a;
    }
  const Vec3 mc = m * c;
  I.topRightCorner<3, 3>() << 0.0, -mc.z(), mc.y(), mc.z(), 0.0, -mc.x(), -mc.y(), mc.x(), 0.0;
  I.bottomLeftCorner<3, 3>() = I.topRightCorner<3, 3>().transpose();
  I.bottomRightCorner<3, 3>() = m * Mat3::Identity();
}

// A motion vector of a link frame (orientation R, origin p) in frame 0.
Vec6 motion_to_frame0(const Mat3& R, const Vec3& p, const Vec6& s) {
  Vec6 out;
  out.head<3>().noalias() = R * s.head<3>();
  out.tail<3>().noalias() = R * s.tail<3>();
  out.tail<3>() += p.cross(out.head<3>());
  return out;
}

// Link i in frame 0 from the kinematics: its S_i and its inertia as the start of IA_i.
void prepare_link(const Model& model, Data& data, int i) {
  const Data::LinkInfo& link = data.info[i];
  const Data::LinkConstants& k = data.constants[i];
  const Mat3& R = data.world_rotation[i];
  const Vec3 p = data.world_position[i] - data.frame_origin;
  inertia_in_frame0(k, link.inertia_diagonal, R, p, data.articulated_inertia[i]);
  if (link.nv == 1) {
    Vec6& S = data.one_dof[i].S;
    if (link.type == JointType::revolute) {
      S.head<3>().noalias() = R * k.axis;
      S.tail<3>() = p.cross(S.head<3>());
    } else {
      S.head<3>().setZero();
      S.tail<3>().noalias() = R * k.axis;
    }
  } else {
    const Mat6N& S_link = model.links[i].motion_subspace;
    for (int c = 0; c < link.nv; ++c)
      data.motion_subspace[i].col(c) = motion_to_frame0(R, p, S_link.col(c));
  }
}

// U, D^-1 of a joint with several dofs.
void joint_inertia(const Model& model, int v_index, const Mat6N& S, const Mat6& IA, Mat6N& U,
                   MatNN& D_inv) {
  U.noalias() = IA * S;
  MatNN D = S.transpose() * U;
  D.diagonal() += model.armature.segment(v_index, S.cols());
  D_inv = D.llt().solve(MatNN::Identity(S.cols(), S.cols()));
}

}  // namespace

void articulated_inertias(const Model& model, Data& data) {
  data.frame_origin = data.world_position[0];
  for (int i = 0; i < model.num_links(); ++i) prepare_link(model, data, i);
  for (int i = model.num_links() - 1; i >= 0; --i) {
    const Data::LinkInfo& link = data.info[i];
    const Mat6& IA = data.articulated_inertia[i];
    if (link.nv == 1) {
      Data::OneDof& J = data.one_dof[i];
      J.U.noalias() = IA * J.S;
      J.D_inv = 1.0 / (J.S.dot(J.U) + model.armature[link.v_index]);
      if (link.parent < 0) continue;
      Mat6& IA_parent = data.articulated_inertia[link.parent];
      IA_parent += IA;
      IA_parent.noalias() -= (J.D_inv * J.U) * J.U.transpose();
      continue;
    }
    if (link.nv > 0)
      joint_inertia(model, link.v_index, data.motion_subspace[i], IA, data.U[i], data.D_inv[i]);
    if (link.parent < 0) continue;
    Mat6& IA_parent = data.articulated_inertia[link.parent];
    IA_parent += IA;
    if (link.nv > 0) IA_parent.noalias() -= data.U[i] * data.D_inv[i] * data.U[i].transpose();
  }
}

const VecX& aba_from_kinematics(const Model& model, Data& data, const VecX& v, const VecX& tau,
                                const std::vector<Vec6>* external_force) {
  const int n = model.num_links();
  data.frame_origin = data.world_position[0];
  // Pass 1: S_i and I_i in frame 0, velocities, velocity-product accelerations, bias forces.
  for (int i = 0; i < n; ++i) {
    prepare_link(model, data, i);
    const Data::LinkInfo& link = data.info[i];
    Vec6 vJ;
    if (link.nv == 1) vJ = data.one_dof[i].S * v[link.v_index];
    else if (link.nv > 0) vJ.noalias() = data.motion_subspace[i] * v.segment(link.v_index, link.nv);
    else vJ.setZero();
    Vec6 vi = vJ;
    if (link.parent >= 0) vi += data.velocity0[link.parent];
    data.velocity0[i] = vi;
    data.bias_acceleration0[i] = cross_motion(vi, vJ);
    const Vec6 h = data.articulated_inertia[i] * vi;
    data.articulated_bias[i] = cross_force(vi, h);
    if (external_force) data.articulated_bias[i] -= (*external_force)[static_cast<size_t>(i)];
  }
  // Pass 2: articulated inertias and bias forces, leaves to root.
  for (int i = n - 1; i >= 0; --i) {
    const Data::LinkInfo& link = data.info[i];
    const Mat6& IA = data.articulated_inertia[i];
    const Vec6& pA = data.articulated_bias[i];
    const Vec6& c = data.bias_acceleration0[i];
    if (link.nv == 1) {
      Data::OneDof& J = data.one_dof[i];
      J.U.noalias() = IA * J.S;
      J.D_inv = 1.0 / (J.S.dot(J.U) + model.armature[link.v_index]);
      const double u = tau[link.v_index] - J.S.dot(pA);
      data.u[link.v_index] = u;
      if (link.parent < 0) continue;
      // Ia = IA - U D^-1 U^T; pa = pA + Ia c + U D^-1 u = pA + IA c + U D^-1 (u - U.c)
      const Vec6 UD = J.D_inv * J.U;
      Vec6& pA_parent = data.articulated_bias[link.parent];
      pA_parent += pA;
      pA_parent.noalias() += IA * c;
      pA_parent += (u - J.U.dot(c)) * UD;
      Mat6& IA_parent = data.articulated_inertia[link.parent];
      IA_parent += IA;
      IA_parent.noalias() -= UD * J.U.transpose();
      continue;
    }
    auto u = data.u.segment(link.v_index, link.nv);
    if (link.nv > 0) {
      const Mat6N& S = data.motion_subspace[i];
      joint_inertia(model, link.v_index, S, IA, data.U[i], data.D_inv[i]);
      u = tau.segment(link.v_index, link.nv) - S.transpose() * pA;
    }
    if (link.parent < 0) continue;
    Mat6 Ia = IA;
    Vec6 pa = pA;
    if (link.nv > 0) {
      const Mat6N UD = data.U[i] * data.D_inv[i];
      Ia.noalias() -= UD * data.U[i].transpose();
      pa.noalias() += UD * u;
    }
    pa.noalias() += Ia * c;
    data.articulated_inertia[link.parent] += Ia;
    data.articulated_bias[link.parent] += pa;
  }
  // Pass 3: accelerations, root to leaves; gravity as an upward acceleration of the world.
  Vec6 a_world = Vec6::Zero();
  a_world.tail<3>() = -model.gravity;
  for (int i = 0; i < n; ++i) {
    const Data::LinkInfo& link = data.info[i];
    Vec6 a = (link.parent >= 0 ? data.acceleration0[link.parent] : a_world) +
             data.bias_acceleration0[i];
    if (link.nv == 1) {
      const Data::OneDof& J = data.one_dof[i];
      const double qdd = J.D_inv * (data.u[link.v_index] - J.U.dot(a));
      data.qdd[link.v_index] = qdd;
      a += qdd * J.S;
    } else if (link.nv > 0) {
      auto qdd = data.qdd.segment(link.v_index, link.nv);
      qdd = data.D_inv[i] * (data.u.segment(link.v_index, link.nv) - data.U[i].transpose() * a);
      a.noalias() += data.motion_subspace[i] * qdd;
    }
    data.acceleration0[i] = a;
  }
  return data.qdd;
}

const VecX& aba(const Model& model, Data& data, const VecX& q, const VecX& v, const VecX& tau) {
  forward_kinematics(model, data, q, v);
  return aba_from_kinematics(model, data, v, tau);
}

}  // namespace featherdrive
