#include "featherdrive/algorithm/kinematics.hpp"

#include <cmath>

#include "featherdrive/algorithm/joint_motion.hpp"

namespace featherdrive {
namespace {

// R(a, q)^T: the transpose of the rotation by q about the unit axis a (Rodrigues).
Mat3 rotation_transpose(const Vec3& a, double q) {
  const double s = std::sin(q), c = std::cos(q), t = 1.0 - c;
  const double xy = t * a.x() * a.y(), xz = t * a.x() * a.z(), yz = t * a.y() * a.z();
  const double sx = s * a.x(), sy = s * a.y(), sz = s * a.z();
  Mat3 E;
  E << t * a.x() * a.x() + c, xy + sz, xz - sy,  //
      xy - sz, t * a.y() * a.y() + c, yz + sx,   //
      xz + sy, yz - sx, t * a.z() * a.z() + c;
  return E;
}

// X_i = X_J(q) X_T, written into X, with the common joints written out.
void parent_transform_of(const Model& model, const Data& data, int i, const double* q,
                         Transform& X) {
  const Data::LinkInfo& info = data.info[i];
  const Data::LinkConstants& k = data.constants[i];
  const Transform& T = k.tree_transform;
  switch (info.type) {
    case JointType::fixed: X = T; return;
    case JointType::revolute:
      if (info.tree_rotation_identity) X.E = rotation_transpose(k.axis, q[0]);
      else X.E.noalias() = rotation_transpose(k.axis, q[0]) * T.E;
      X.r = T.r;
      return;
    case JointType::prismatic:
      X.E = T.E;
      if (info.tree_rotation_identity) X.r = T.r + k.axis * q[0];
      else X.r = T.r + T.E.transpose() * (k.axis * q[0]);
      return;
    default: X = joint_transform(model.links[i], q) * T; return;
  }
}

// Link i's X_i, world rotation and world position (its parent's are done).
void position_link(const Model& model, Data& data, int i, const VecX& q) {
  const Data::LinkInfo& link = data.info[i];
  Transform& X = data.parent_transform[i];
  parent_transform_of(model, data, i, q.data() + link.q_index, X);
  if (link.parent < 0) {
    data.world_rotation[i] = X.E.transpose();
    data.world_position[i] = X.r;
  } else {
    const Mat3& Rp = data.world_rotation[link.parent];
    data.world_rotation[i].noalias() = Rp * X.E.transpose();
    data.world_position[i] = data.world_position[link.parent];
    data.world_position[i].noalias() += Rp * X.r;
  }
}

}  // namespace

void forward_kinematics(const Model& model, Data& data, const VecX& q) {
  for (int i = 0; i < model.num_links(); ++i) position_link(model, data, i, q);
}

void forward_kinematics(const Model& model, Data& data, const VecX& q, const VecX& v) {
  const int n = model.num_links();
  for (int i = 0; i < n; ++i) {
    position_link(model, data, i, q);
    const Data::LinkInfo& link = data.info[i];
    const Vec3& axis = data.constants[i].axis;
    Vec6 vi = link.parent >= 0 ? data.parent_transform[i].apply_motion(data.velocity[link.parent])
                               : Vec6::Zero();
    Vec6& c = data.bias_acceleration[i];
    switch (link.type) {
      case JointType::fixed: c.setZero(); break;
      case JointType::revolute: {  // vJ = [qd a; 0], c = v x vJ = qd [w x a; v x a]
        const Vec3 a = v[link.v_index] * axis;
        vi.head<3>() += a;
        c.head<3>() = vi.head<3>().cross(a);
        c.tail<3>() = vi.tail<3>().cross(a);
        break;
      }
      case JointType::prismatic: {  // vJ = [0; qd a], c = [0; w x qd a]
        const Vec3 a = v[link.v_index] * axis;
        vi.tail<3>() += a;
        c.head<3>().setZero();
        c.tail<3>() = vi.head<3>().cross(a);
        break;
      }
      default: {
        const Vec6 vJ = model.links[i].motion_subspace * v.segment(link.v_index, link.nv);
        vi += vJ;
        c = cross_motion(vi, vJ);
        break;
      }
    }
    data.velocity[i] = vi;
  }
}

}  // namespace featherdrive
