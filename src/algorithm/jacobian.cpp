#include "featherdrive/algorithm/jacobian.hpp"

namespace featherdrive {
namespace {

// A motion vector m given in link j's frame, re-expressed with world axes at the world point P:
// [R_j m_w; R_j m_v + R_j m_w x (P - p_j)] (Featherstone 2008, eq. 2.21 with E = R_j^T).
Vec6 world_aligned_at(const Data& data, int j, const Vec6& m, const Vec3& P) {
  Vec6 out;
  const Mat3& R = data.world_rotation[j];
  out.head<3>() = R * m.head<3>();
  out.tail<3>() = R * m.tail<3>() + out.head<3>().cross(P - data.world_position[j]);
  return out;
}

// Rotates a world-aligned spatial vector into link axes.
void to_local(const Mat3& R, Vec6& m) {
  m.head<3>() = R.transpose() * m.head<3>().eval();
  m.tail<3>() = R.transpose() * m.tail<3>().eval();
}

}  // namespace

void frame_jacobian(const Model& model, const Data& data, int link, const Vec3& point,
                    ReferenceFrame reference, MatX& J) {
  check_link_index(model, link);
  if (J.rows() != 6 || J.cols() != model.nv) J.resize(6, model.nv);
  J.setZero();
  const Vec3 P = data.world_position[link] + data.world_rotation[link] * point;
  const Mat3& R = data.world_rotation[link];
  for (int j = link; j >= 0; j = model.links[j].parent) {
    const Link& lj = model.links[j];
    for (int c = 0; c < lj.nv; ++c) {
      Vec6 col = world_aligned_at(data, j, lj.motion_subspace.col(c), P);
      if (reference == ReferenceFrame::local) to_local(R, col);
      J.col(lj.v_index + c) = col;
    }
  }
}

Vec6 jacobian_dot_times_v(const Model& model, const Data& data, int link, const Vec3& point,
                          ReferenceFrame reference) {
  check_link_index(model, link);
  // The spatial acceleration at qdd = 0 in one fixed frame is the sum of every ancestor's
  // velocity-product term c_j = v_j x (S_j qd_j) (Featherstone 2008, eq. 7.36 with qdd = 0),
  // each stored in its link's frame; the sum does not depend on the order.
  const Vec3 P = data.world_position[link] + data.world_rotation[link] * point;
  Vec6 a = Vec6::Zero();
  for (int j = link; j >= 0; j = model.links[j].parent)
    a += world_aligned_at(data, j, data.bias_acceleration[j], P);
  if (reference == ReferenceFrame::local) {
    to_local(data.world_rotation[link], a);
    return a;
  }
  // Classical: the point's acceleration is the spatial one plus omega x (point velocity).
  const Vec6 v = frame_velocity(model, data, link, point, ReferenceFrame::world_aligned);
  a.tail<3>() += v.head<3>().cross(v.tail<3>());
  return a;
}

}  // namespace featherdrive
