// One Gauss-Seidel sweep over the dof rows of an articulation, depth first from the root (PhysX's
// order: a link's dofs, then its children in model order). Every row sees the exact current joint
// velocity, every earlier impulse of the sweep included, yet the sweep costs O(n): an impulse's
// effect on the root side is deferred and folded in when its subtree is left
// (docs/math/implicit_drives.md, "Propagating impulses"). Spatial quantities are those of frame 0
// (data.hpp), so nothing is transformed from link to link.
#pragma once

#include <vector>

#include "featherdrive/algorithm/data.hpp"

namespace featherdrive {

/// Scratch of a sweep, sized once per model.
struct SweepWorkspace {
  explicit SweepWorkspace(const Model& model);
  std::vector<Vec6> link_velocity_change;  ///< Delta v_i of the sweep when entering, frame 0
  std::vector<Vec6> subtree_impulse;       ///< pA_i: impulse handed up by finished children
  std::vector<Vec6> parent_impulse_after;  ///< pA_parent right after link i handed its impulse
  std::vector<Vec6> later_velocity_change; ///< E_i: change of link i from later subtrees' impulses
  VecX joint_impulse;                      ///< impulse applied at each dof in this sweep (nv)
  VecX entry_velocity_change;              ///< each dof's velocity change when it was entered (nv)
  std::vector<char> has_rows;              ///< per dof: does the sweep solve a row here
};

namespace detail {

// Leaves the finished links from k up to `stop` (not included; -1 for all): each hands its
// subtree's impulse pa = pA + U D^-1 (impulse - S^T pA) to its parent. When a sibling of the last
// one is entered next (correct_stop), stop's velocity change is corrected by its
// whole-articulation response to that impulse; no other link's velocity change is read again in
// the sweep. Along a run of 1-dof links, S_p^T pA_p of the next one is formed from scalars so that
// the 6-vector products stay off the chain of dependencies.
inline void leave_links(const Data& data, SweepWorkspace& ws, int k, int stop, bool correct_stop) {
  bool have_x = false;
  double x = 0.0;  // S_k^T pA_k when have_x
  while (k != stop) {
    const Data::LinkInfo& link = data.info[k];
    const int p = link.parent;
    Vec6 pa = ws.subtree_impulse[k];
    if (link.nv == 1) {
      const Data::OneDof& J = data.one_dof[k];
      if (!have_x) x = J.S.dot(pa);
      const double beta = J.D_inv * (ws.joint_impulse[link.v_index] - x);
      have_x = p >= 0 && p != stop && data.info[p].nv == 1;
      if (have_x) x = data.one_dof[p].S.dot(ws.subtree_impulse[p] + pa) + beta * J.parent_S;
      pa += beta * J.U;
    } else {
      have_x = false;
      if (link.nv > 0) {
        const VecN t = ws.joint_impulse.segment(link.v_index, link.nv) -
                       data.motion_subspace[k].transpose() * pa;
        pa.noalias() += data.U[k] * (data.D_inv[k] * t);
      }
    }
    if (p < 0) return;
    Vec6& pA_parent = ws.subtree_impulse[p];
    pA_parent += pa;
    if (!link.last_child) ws.parent_impulse_after[k] = pA_parent;
    if (p == stop && correct_stop)
      ws.link_velocity_change[p].noalias() -= data.response[p] * pa;
    k = p;
  }
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
  // The base of link i when it is entered right after its 1-dof parent, from scalars.
  bool have_base = false;
  double next_base = 0.0;
  for (int i = 0; i < n; ++i) {
    const Data::LinkInfo& link = data.info[i];
    if (previous != link.parent) {
      detail::leave_links(data, ws, previous, link.parent, true);
      have_base = false;
    }
    previous = i;
    // Delta v of the parent, exact now.
    const Vec6 from_parent = link.parent >= 0 ? ws.link_velocity_change[link.parent] : Vec6::Zero();
    if (link.nv == 1) {
      // The joint's velocity change from outside its subtree is base = -D^-1 U^T Delta v_p; its own
      // impulse adds (M^-1)_ii times it. The link then moves by
      // Delta v_p - W D^-1 impulse + S (base + (M^-1)_ii impulse).
      const Data::OneDof& J = data.one_dof[i];
      const int d = link.v_index;
      const double base = have_base ? next_base : -J.D_inv * J.U.dot(from_parent);
      // If the next link is a 1-dof child, U_c^T Delta v_p now, the rest after the impulse.
      have_base = i + 1 < n && data.info[i + 1].parent == i && data.info[i + 1].nv == 1;
      const double ahead = have_base ? data.one_dof[i + 1].U.dot(from_parent) : 0.0;
      double impulse = 0.0;
      if (ws.has_rows[d]) {
        impulse = solve_row(d, qd[d] + base);
        ws.joint_impulse[d] = impulse;
      }
      const double dqd = base + J.inverse_mass * impulse;
      const double h = J.D_inv * impulse;
      ws.entry_velocity_change[d] = dqd;
      if (have_base) {
        const Data::OneDof& C = data.one_dof[i + 1];
        next_base = -C.D_inv * (ahead - h * C.parent_W + dqd * C.parent_S);
      }
      Vec6 dv = from_parent;
      dv -= h * J.W;
      dv += dqd * J.S;
      ws.link_velocity_change[i] = dv;
      continue;
    }
    have_base = false;
    if (link.nv == 0) {
      ws.link_velocity_change[i] = from_parent;
      continue;
    }
    const int nv = link.nv;
    const int v0 = link.v_index;
    const Mat6N& U = data.U[i];
    const MatNN& D_inv = data.D_inv[i];
    const VecN base = -(D_inv * (U.transpose() * from_parent));
    auto impulse = ws.joint_impulse.segment(v0, nv);
    for (int d = 0; d < nv; ++d) {
      if (!ws.has_rows[v0 + d]) continue;
      const double current = qd[v0 + d] + base[d] + data.inverse_mass_block[i].row(d).dot(impulse);
      impulse[d] += solve_row(v0 + d, current);
    }
    const Vec6 parent_now = from_parent - data.parent_coupling[i] * (D_inv * impulse);
    const VecN dqd = D_inv * (impulse - U.transpose() * parent_now);
    ws.entry_velocity_change.segment(v0, nv) = dqd;
    ws.link_velocity_change[i] = parent_now + data.motion_subspace[i] * dqd;
  }
  detail::leave_links(data, ws, previous, -1, false);
  // Every joint's velocity change is what it had when entered, plus what its subtree's impulses
  // do to it (-G^T pA, local), plus what subtrees entered after its own do to it (E, zero unless
  // it or an ancestor has a later sibling).
  for (int i = 0; i < n; ++i) {
    const Data::LinkInfo& link = data.info[i];
    const Vec6& pA = ws.subtree_impulse[i];
    // The velocity change of the parent from the impulses entered after this link's subtree.
    auto parent_later = [&]() -> Vec6 {
      Vec6 E_hat = data.info[link.parent].later ? ws.later_velocity_change[link.parent] : Vec6::Zero();
      if (!link.last_child)
        E_hat.noalias() -= data.response[link.parent] *
                           (ws.subtree_impulse[link.parent] - ws.parent_impulse_after[i]);
      return E_hat;
    };
    if (link.nv == 1) {
      const Data::OneDof& J = data.one_dof[i];
      const int d = link.v_index;
      double dqd = ws.entry_velocity_change[d] - J.G.dot(pA);
      if (link.later) {
        const Vec6 E_hat = parent_later();
        const double later = -J.D_inv * J.U.dot(E_hat);
        dqd += later;
        ws.later_velocity_change[i] = E_hat + later * J.S;
      }
      qd[d] += dqd;
      continue;
    }
    if (link.nv == 0) {
      if (link.later) ws.later_velocity_change[i] = parent_later();
      continue;
    }
    const int v0 = link.v_index, nv = link.nv;
    const Mat6N& S = data.motion_subspace[i];
    const MatNN& D_inv = data.D_inv[i];
    VecN dqd = ws.entry_velocity_change.segment(v0, nv) -
               data.inverse_mass_block[i] * (S.transpose() * pA) +
               D_inv * (data.parent_coupling[i].transpose() * pA);
    if (link.later) {
      const Vec6 E_hat = parent_later();
      const VecN later = -(D_inv * (data.U[i].transpose() * E_hat));
      dqd += later;
      ws.later_velocity_change[i] = E_hat + S * later;
    }
    qd.segment(v0, nv) += dqd;
  }
}

}  // namespace featherdrive
