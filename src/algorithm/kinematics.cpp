#include "featherdrive/algorithm/kinematics.hpp"


#include "featherdrive/algorithm/joint_motion.hpp"
#include "featherdrive/spatial/joint_transform_law.hpp"
#include "featherdrive/spatial/sincos.hpp"

namespace featherdrive {
namespace {

// R(a, q)^T: the transpose of the rotation by q about the unit axis a (eq. JT-1).
Mat3 rotation_transpose(const Vec3& a, double q) {
  double s, c;
  sincos_inline(q, s, c);
  Mat3 J;
  joint_transform_law::axis_rotation(a.x(), a.y(), a.z(), s, c, J);
  return J.transpose();
}

// A joint's unit axis in the axes P of its joint frame (eq. JT-8).
template <class M>
Vec3 joint_axis_in(const M& P, const Data::LinkInfo& link, const Vec3& axis) {
  Vec3 a;
  joint_transform_law::joint_axis(P, link.unit_axis, link.axis_sign, axis, a);
  return a;
}

using joint_transform_law::next_axis;
using joint_transform_law::previous_axis;

// X_i = X_J(q) X_T, written into X, with the common joints written out. For a revolute joint
// about a coordinate axis, (c, s) receive the cosine and sine of its angle (axis sign included).
void parent_transform_of(const Model& model, const Data& data, int i, const double* q,
                         Transform& X, double& c, double& s) {
  const Data::LinkInfo& info = data.info[i];
  const Data::LinkConstants& k = data.constants[i];
  const Transform& T = k.tree_transform;
  switch (info.type) {
    case JointType::fixed: X = T; return;
    case JointType::revolute:
      X.r = T.r;
      if (info.unit_axis >= 0) {
        // R(+-e_k, q)^T X_T: rows k1 and k2 of E_T mix, row k stays.
        const double angle = info.axis_sign * q[0];
        sincos_inline(angle, s, c);
        const int a = info.unit_axis, a1 = next_axis(a), a2 = previous_axis(a);
        if (info.tree_rotation_identity) {
          X.E.setZero();
          X.E(a, a) = 1.0;
          X.E(a1, a1) = c;
          X.E(a1, a2) = s;
          X.E(a2, a1) = -s;
          X.E(a2, a2) = c;
        } else {
          joint_transform_law::turn_rows(T.E, a, s, c, X.E);
        }
        return;
      }
      if (info.tree_rotation_identity) X.E = rotation_transpose(k.axis, q[0]);
      else X.E.noalias() = rotation_transpose(k.axis, q[0]) * T.E;
      return;
    case JointType::prismatic:
      // r_T + a_p x, a_p = E_T^T a the axis in the parent's coordinates: the world position's
      // law (eq. JT-8, JT-9) on the joint frame's axes in the parent, E_T^T.
      X.E = T.E;
      X.r = T.r;
      joint_transform_law::slide(joint_axis_in(T.E.transpose(), info, k.axis), q[0], X.r);
      return;
    default: X = joint_transform(model.links[i], q) * T; return;
  }
}

const Mat3 kIdentity3 = Mat3::Identity();  // the world's pose, the root's parent
const Vec3 kZero3 = Vec3::Zero();

// Link i's X_i, world rotation and world position (its parent's are done; the world's for the
// root): any joint.
void position_link(const Model& model, Data& data, int i, const VecX& q) {
  const Data::LinkInfo& link = data.info[i];
  Transform& X = data.parent_transform[i];
  double c = 1.0, s = 0.0;
  parent_transform_of(model, data, i, q.data() + link.q_index, X, c, s);
  const bool has_parent = link.parent >= 0;
  const Mat3& Rp = has_parent ? data.world_rotation[link.parent] : kIdentity3;
  const Vec3& pp = has_parent ? data.world_position[link.parent] : kZero3;
  Mat3& R = data.world_rotation[i];
  Vec3& p = data.world_position[i];
  // p = p_p + R_p r (eq. JT-7); a prismatic joint's slide is added along its world axis.
  const bool prismatic = link.type == JointType::prismatic;
  joint_transform_law::link_position(pp, Rp, prismatic ? data.constants[i].tree_transform.r : X.r,
                                     p);
  if (link.type == JointType::revolute && link.unit_axis >= 0) {
    // R = Rp X_T^T R(e_k, q): columns k1 and k2 mix. Rp X_T^T is Rp when X_T does not rotate.
    Mat3 B;
    if (!link.tree_rotation_identity)
      B.noalias() = Rp * data.constants[i].tree_transform.E.transpose();
    const Mat3& P = link.tree_rotation_identity ? Rp : B;
    joint_transform_law::turn_columns(P, link.unit_axis, s, c, R);
    return;
  }
  const bool fixed_rotation = link.type == JointType::fixed || prismatic;
  if (link.tree_rotation_identity && fixed_rotation) R = Rp;
  else if (fixed_rotation) joint_transform_law::joint_frame(Rp, X.E, R);  // X.E = E_T (eq. JT-5)
  else R.noalias() = Rp * X.E.transpose();
  if (!prismatic) return;
  // p += (R_p E_T^T a) q (eq. JT-8, JT-9), R_p E_T^T being R.
  joint_transform_law::slide(joint_axis_in(R, link, data.constants[i].axis), q[link.q_index], p);
}

// The common case (LinkInfo::coordinate_revolute) about e_A, inline: X_i = [R(e_A, q)^T, r_T],
// R_i = R_p R(e_A, q), p_i = p_p + R_p r_T. A is a template argument so that every index is a
// constant.
// Without kTransform, X_i is not written (world_poses).
template <int A, bool kTransform = true>
void position_coordinate_revolute(Data& data, int i, const VecX& q) {
  constexpr int A1 = A == 2 ? 0 : A + 1, A2 = A == 0 ? 2 : A - 1;
  const Data::LinkInfo& link = data.info[i];
  // First, so that nothing computed before it has to survive the call.
  const double angle = link.axis_sign * q[link.q_index];
  double c, s;
  sincos_inline(angle, s, c);
  const Vec3 r = data.constants[i].tree_transform.r;
  const Mat3& Rp = data.world_rotation[link.parent];
  Vec3 p;
  joint_transform_law::link_position(data.world_position[link.parent], Rp, r, p);
  joint_transform_law::turn_columns(Rp, A, s, c, data.world_rotation[i]);
  data.world_position[i] = p;
  if (!kTransform) return;
  Transform& X = data.parent_transform[i];
  X.E(A, A) = 1.0;
  X.E(A, A1) = 0.0;
  X.E(A, A2) = 0.0;
  X.E(A1, A) = 0.0;
  X.E(A2, A) = 0.0;
  X.E(A1, A1) = c;
  X.E(A1, A2) = s;
  X.E(A2, A1) = -s;
  X.E(A2, A2) = c;
  X.r = r;
}

// X v for a coordinate revolute joint's X_i = [R(e_A, q)^T, r]: E mixes two coordinates.
template <int A>
Vec6 coordinate_apply_motion(const Transform& X, const Vec6& v) {
  constexpr int A1 = A == 2 ? 0 : A + 1, A2 = A == 0 ? 2 : A - 1;
  const double c = X.E(A1, A1), s = X.E(A1, A2);
  const Vec3 w = v.head<3>(), u = v.tail<3>() - X.r.cross(w);
  Vec6 out;
  out[A] = w[A];
  out[A1] = c * w[A1] + s * w[A2];
  out[A2] = c * w[A2] - s * w[A1];
  out[3 + A] = u[A];
  out[3 + A1] = c * u[A1] + s * u[A2];
  out[3 + A2] = c * u[A2] - s * u[A1];
  return out;
}

// X_i v_parent, the parent's velocity in link i's frame.
Vec6 velocity_from_parent(const Data& data, int i) {
  const Data::LinkInfo& link = data.info[i];
  const Transform& X = data.parent_transform[i];
  const Vec6& vp = data.velocity[link.parent];
  if (!link.coordinate_revolute) return X.apply_motion(vp);
  if (link.unit_axis == 0) return coordinate_apply_motion<0>(X, vp);
  if (link.unit_axis == 1) return coordinate_apply_motion<1>(X, vp);
  return coordinate_apply_motion<2>(X, vp);
}

// Either of the above.
template <bool kTransform = true>
inline void position_any(const Model& model, Data& data, int i, const VecX& q) {
  const Data::LinkInfo& link = data.info[i];
  if (!link.coordinate_revolute) position_link(model, data, i, q);
  else if (link.unit_axis == 0) position_coordinate_revolute<0, kTransform>(data, i, q);
  else if (link.unit_axis == 1) position_coordinate_revolute<1, kTransform>(data, i, q);
  else position_coordinate_revolute<2, kTransform>(data, i, q);
}

}  // namespace

void world_poses(const Model& model, Data& data, const VecX& q) {
  const int n = model.num_links();
  for (int i = 0; i < n; ++i) position_any<false>(model, data, i, q);
}

void forward_kinematics(const Model& model, Data& data, const VecX& q) {
  const int n = model.num_links();
  for (int i = 0; i < n; ++i) position_any(model, data, i, q);
}

void forward_kinematics(const Model& model, Data& data, const VecX& q, const VecX& v) {
  const int n = model.num_links();
  for (int i = 0; i < n; ++i) {
    position_any(model, data, i, q);
    const Data::LinkInfo& link = data.info[i];
    const Vec3& axis = data.constants[i].axis;
    Vec6 vi = link.parent >= 0 ? velocity_from_parent(data, i) : Vec6::Zero();
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
