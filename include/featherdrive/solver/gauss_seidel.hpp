// One Gauss-Seidel sweep over the dof rows of an articulation, depth first from the root (PhysX's
// order: a link's dofs, then its children in model order). Every row sees the exact current joint
// velocity, every earlier impulse of the sweep included, yet the sweep costs O(n): an impulse's
// effect on the root side is deferred and folded in when its subtree is left
// (docs/math/implicit_drives.md, "Propagating impulses").
#pragma once

#include <vector>

#include "featherdrive/algorithm/data.hpp"

namespace featherdrive {

/// Scratch of a sweep, sized once per model.
struct SweepWorkspace {
  explicit SweepWorkspace(const Model& model);
  std::vector<Vec6> link_velocity_change;  ///< Delta v_i of the sweep, link frame
  std::vector<Vec6> subtree_impulse;       ///< pA_i: impulse handed up by finished children
  VecX joint_impulse;                      ///< impulse applied at each dof in this sweep (nv)
  std::vector<char> has_rows;              ///< per dof: does the sweep solve a row here
};

namespace detail {

// Leaves link k: hands its subtree's impulse to the parent and corrects the parent's velocity
// change by the parent's whole-articulation response to it.
inline void leave_link(const Model& model, const Data& data, SweepWorkspace& ws, int k) {
  const Link& link = model.links[k];
  Vec6 pa = ws.subtree_impulse[k];
  if (link.nv > 0) {
    const VecN t = ws.joint_impulse.segment(link.v_index, link.nv) -
                   link.motion_subspace.transpose() * pa;
    pa.noalias() += data.U[k] * (data.D_inv[k] * t);
  }
  if (link.parent < 0) return;
  const Vec6 f = data.parent_transform[k].transpose_apply_force(pa);
  ws.subtree_impulse[link.parent] += f;
  ws.link_velocity_change[link.parent].noalias() -= data.response[link.parent] * f;
}

}  // namespace detail

/// One sweep. qd (nv) holds the exact joint velocities on entry and on exit. For every dof with
/// ws.has_rows set, solve_row(dof, current_qd) returns the impulse to apply there.
template <class RowSolver>
void gauss_seidel_sweep(const Model& model, const Data& data, SweepWorkspace& ws, VecX& qd,
                        RowSolver&& solve_row) {
  const int n = model.num_links();
  ws.joint_impulse.setZero();
  for (int i = 0; i < n; ++i) ws.subtree_impulse[i].setZero();
  int previous = -1;
  for (int i = 0; i < n; ++i) {
    const Link& link = model.links[i];
    for (int k = previous; k != link.parent; k = model.links[k].parent)
      detail::leave_link(model, data, ws, k);
    previous = i;
    Vec6 from_parent = Vec6::Zero();  // X_i Delta v_parent, exact now
    if (link.parent >= 0)
      from_parent = data.parent_transform[i].apply_motion(ws.link_velocity_change[link.parent]);
    if (link.nv == 0) {
      ws.link_velocity_change[i] = from_parent;
      continue;
    }
    const int nv = link.nv;
    const int v0 = link.v_index;
    const VecN base = -(data.D_inv[i] * (data.U[i].transpose() * from_parent));
    auto impulse = ws.joint_impulse.segment(v0, nv);
    for (int d = 0; d < nv; ++d) {
      if (!ws.has_rows[v0 + d]) continue;
      const double current = qd[v0 + d] + base[d] + data.inverse_mass_block[i].row(d).dot(impulse);
      impulse[d] += solve_row(v0 + d, current);
    }
    const Vec6 parent_now = from_parent - data.parent_coupling[i] * (data.D_inv[i] * impulse);
    const VecN dqd = data.D_inv[i] * (impulse - data.U[i].transpose() * parent_now);
    ws.link_velocity_change[i] = parent_now + link.motion_subspace * dqd;
  }
  for (int k = previous; k >= 0; k = model.links[k].parent) detail::leave_link(model, data, ws, k);
  // Fold the sweep's impulses into every joint velocity: Delta qd = M^-1 impulse (ABA pass 3).
  for (int i = 0; i < n; ++i) {
    const Link& link = model.links[i];
    Vec6 a = Vec6::Zero();
    if (link.parent >= 0)
      a = data.parent_transform[i].apply_motion(ws.link_velocity_change[link.parent]);
    if (link.nv > 0) {
      const VecN t = ws.joint_impulse.segment(link.v_index, link.nv) -
                     link.motion_subspace.transpose() * ws.subtree_impulse[i];
      const VecN dqd = data.D_inv[i] * (t - data.U[i].transpose() * a);
      qd.segment(link.v_index, link.nv) += dqd;
      a.noalias() += link.motion_subspace * dqd;
    }
    ws.link_velocity_change[i] = a;
  }
}

}  // namespace featherdrive
