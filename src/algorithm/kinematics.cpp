#include "featherdrive/algorithm/kinematics.hpp"


#include "featherdrive/algorithm/joint_motion.hpp"
#include "featherdrive/spatial/joint_transform_law.hpp"
#include "featherdrive/spatial/sincos.hpp"

namespace featherdrive {
namespace {

// A joint's unit axis in the axes P of its joint frame (eq. JT-8).
template <class M>
Vec3 joint_axis_in(const M& P, const Data::LinkInfo& link, const Vec3& axis) {
  Vec3 a;
  joint_transform_law::joint_axis(P, link.unit_axis, link.axis_sign, axis, a);
  return a;
}

using joint_transform_law::next_axis;
using joint_transform_law::previous_axis;

// X_i = X_J(q) X_T, written into X. For a revolute joint about a coordinate axis, (c, s) receive
// the cosine and sine of its angle (axis sign included); for one about another axis, a spherical
// joint and a floating root, J receives the joint's rotation R_J (eq. JT-1, Q-5), and X_i's
// rotation is R_J^T E_T.
void parent_transform_of(const Data& data, int i, const double* q, Transform& X, double& c,
                         double& s, Mat3& J) {
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
      sincos_inline(q[0], s, c);
      joint_transform_law::axis_rotation(k.axis.x(), k.axis.y(), k.axis.z(), s, c, J);
      break;
    case JointType::prismatic:
      // r_T + a_p x, a_p = E_T^T a the axis in the parent's coordinates: the world position's
      // law (eq. JT-8, JT-9) on the joint frame's axes in the parent, E_T^T.
      X.E = T.E;
      X.r = T.r;
      joint_transform_law::slide(joint_axis_in(T.E.transpose(), info, k.axis), q[0], X.r);
      return;
    case JointType::spherical:
      J = quaternion_rotation(q);
      X.r = T.r;
      break;
    case JointType::floating:
      J = quaternion_rotation(q + 3);
      X.r = T.r + T.E.transpose() * Vec3(q[0], q[1], q[2]);
      break;
  }
  if (info.tree_rotation_identity) X.E = J.transpose();
  else X.E.noalias() = J.transpose() * T.E;
}

const Mat3 kIdentity3 = Mat3::Identity();  // the world's pose, the root's parent
const Vec3 kZero3 = Vec3::Zero();

// Link i's X_i, world rotation and position in frame 0 (its parent's are done in Rw, pf; the
// world's pose for the root): any joint, in the lanes' operations (LaneStep::link_pose). The
// root's frame 0 position is 0 (JT-12); its world one goes into *root.
void position_link(const Data& data, int i, const VecX& q, Transform& X, Mat3* Rw, Vec3* pf,
                   Vec3* root) {
  const Data::LinkInfo& link = data.info[i];
  const Data::LinkConstants& k = data.constants[i];
  double c = 1.0, s = 0.0;
  Mat3 J;
  parent_transform_of(data, i, q.data() + link.q_index, X, c, s, J);
  const bool has_parent = link.parent >= 0;
  const Mat3& Rp = has_parent ? Rw[link.parent] : kIdentity3;
  const Vec3& pp = has_parent ? pf[link.parent] : kZero3;
  Mat3& R = Rw[i];
  if (!has_parent) pf[i].setZero();
  Vec3& p = has_parent ? pf[i] : *root;
  // p = p_p + R_p r_T (eq. JT-7); a floating root's r is X_i's, r_T + E_T^T q.
  const bool floating = link.type == JointType::floating;
  joint_transform_law::link_position(pp, Rp, floating ? X.r : k.tree_transform.r, p);
  // The joint frame's axes P = R_p E_T^T (eq. JT-5), R_p itself where X_T does not rotate.
  Mat3 B;
  if (!link.tree_rotation_identity) joint_transform_law::joint_frame(Rp, k.tree_transform.E, B);
  const Mat3& P = link.tree_rotation_identity ? Rp : B;
  switch (link.type) {
    case JointType::fixed: R = P; return;
    case JointType::prismatic:
      // p += (P a) q (eq. JT-8, JT-9).
      R = P;
      joint_transform_law::slide(joint_axis_in(P, link, k.axis), q[link.q_index], p);
      return;
    case JointType::revolute:
      // R = P R(e_k, q): columns k1 and k2 mix (eq. JT-3).
      if (link.unit_axis >= 0)
        return joint_transform_law::turn_columns(P, link.unit_axis, s, c, R);
      [[fallthrough]];
    default: joint_transform_law::compose(P, J, R); return;  // R = P R_J (eq. JT-6)
  }
}

// The common case (LinkInfo::coordinate_revolute) about e_A, inline: X_i = [R(e_A, q)^T, r_T],
// R_i = R_p R(e_A, q), p_i = p_p + R_p r_T (frame 0's, in pf). A is a template argument so that
// every index is a constant.
// Without kTransform, X_i is not written (world_poses).
template <int A, bool kTransform = true>
void position_coordinate_revolute(const Data& data, int i, const VecX& q, Transform& X, Mat3* Rw,
                                  Vec3* pf) {
  constexpr int A1 = A == 2 ? 0 : A + 1, A2 = A == 0 ? 2 : A - 1;
  const Data::LinkInfo& link = data.info[i];
  // First, so that nothing computed before it has to survive the call.
  const double angle = link.axis_sign * q[link.q_index];
  double c, s;
  sincos_inline(angle, s, c);
  const Vec3 r = data.constants[i].tree_transform.r;
  const Mat3& Rp = Rw[link.parent];
  Vec3 p;
  joint_transform_law::link_position(pf[link.parent], Rp, r, p);
  joint_transform_law::turn_columns(Rp, A, s, c, Rw[i]);
  pf[i] = p;
  if (!kTransform) return;
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

// Either of the above, into the rotations Rw and frame 0's positions pf (the root's world position
// into *root), X_i into X. Forced inline: out of line world_poses's loop takes 8 % more
// instructions (chain256).
template <bool kTransform = true>
[[gnu::always_inline]] inline void position_any(const Data& data, int i, const VecX& q,
                                                Transform& X, Mat3* Rw, Vec3* pf, Vec3* root) {
  const Data::LinkInfo& link = data.info[i];
  if (!link.coordinate_revolute) position_link(data, i, q, X, Rw, pf, root);
  else if (link.unit_axis == 0) position_coordinate_revolute<0, kTransform>(data, i, q, X, Rw, pf);
  else if (link.unit_axis == 1) position_coordinate_revolute<1, kTransform>(data, i, q, X, Rw, pf);
  else position_coordinate_revolute<2, kTransform>(data, i, q, X, Rw, pf);
}

// Into data's own poses and X_i: frame 0's position p, then the world's p + p_0 with p_0 the
// root's origin (docs/math/joint_transform.md, JT-12), as the lanes' contacts form it.
template <bool kTransform = true>
[[gnu::always_inline]] inline void position_any(Data& data, int i, const VecX& q) {
  Vec3* const pw = data.world_position.data();
  Vec3* const pf = data.frame_position.data();
  position_any<kTransform>(data, i, q, data.parent_transform[i], data.world_rotation.data(), pf,
                           pw);
  if (i > 0) pw[i] = pf[i] + pw[0];
}

}  // namespace

void world_poses(const Model& model, Data& data, const VecX& q) {
  const int n = model.num_links();
  for (int i = 0; i < n; ++i) position_any<false>(data, i, q);
}

void world_poses(const Data& data, const VecX& q, Mat3* R, Vec3* p) {
  const int n = static_cast<int>(data.info.size());
  Transform X;  // X_i, not kept
  Vec3 root;    // the root's origin in the world
  for (int i = 0; i < n; ++i) position_any<false>(data, i, q, X, R, p, &root);
  for (int i = 0; i < n; ++i) p[i] = p[i] + root;  // frame 0's to the world's (JT-12)
}

void forward_kinematics(const Model& model, Data& data, const VecX& q) {
  const int n = model.num_links();
  for (int i = 0; i < n; ++i) position_any(data, i, q);
}

void forward_kinematics(const Model& model, Data& data, const VecX& q, const VecX& v) {
  const int n = model.num_links();
  for (int i = 0; i < n; ++i) {
    position_any(data, i, q);
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
