#include "featherdrive/algorithm/center_of_mass.hpp"

namespace featherdrive {

Vec3 center_of_mass_velocity(const Model& model, const Data& data) {
  Vec3 p = Vec3::Zero();  // linear momentum
  double m = 0.0;
  for (int i = 0; i < model.num_links(); ++i) {
    const Link& l = model.links[i];
    const Vec6& v = data.velocity[i];
    p += l.mass * (data.world_rotation[i] * (v.tail<3>() + v.head<3>().cross(l.com)));
    m += l.mass;
  }
  return m > 0.0 ? Vec3(p / m) : Vec3::Zero();
}

void center_of_mass_jacobian(const Model& model, Data& data, MatX& J) {
  if (J.rows() != 3 || J.cols() != model.nv) J.resize(3, model.nv);
  const int n = model.num_links();
  // Subtree masses and first moments sum_k m_k c_k (world), leaves first.
  for (int i = 0; i < n; ++i) {
    const Link& l = model.links[i];
    data.subtree_mass[i] = l.mass;
    data.subtree_moment[i] = l.mass * (data.world_position[i] + data.world_rotation[i] * l.com);
  }
  for (int i = n - 1; i > 0; --i) {
    const int p = model.links[i].parent;
    data.subtree_mass[p] += data.subtree_mass[i];
    data.subtree_moment[p] += data.subtree_moment[i];
  }
  double total = 0.0;
  for (int i = 0; i < n; ++i)
    if (model.links[i].parent < 0) total += data.subtree_mass[i];
  J.setZero();
  if (total <= 0.0) return;
  // A dof of joint j moves its subtree only: column (m_s v + w x (h_s - m_s p_j)) / m, with
  // [w; v] its motion subspace column in world axes at p_j, m_s and h_s the subtree's mass and
  // first moment.
  for (int j = 0; j < n; ++j) {
    const Link& l = model.links[j];
    const Mat3& R = data.world_rotation[j];
    const Vec3 h = data.subtree_moment[j] - data.subtree_mass[j] * data.world_position[j];
    for (int c = 0; c < l.nv; ++c) {
      const Vec3 w = R * l.motion_subspace.col(c).head<3>();
      const Vec3 v = R * l.motion_subspace.col(c).tail<3>();
      J.col(l.v_index + c) = (data.subtree_mass[j] * v + w.cross(h)) / total;
    }
  }
}

}  // namespace featherdrive
