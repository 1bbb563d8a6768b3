// One Gauss-Seidel sweep over the dof rows of an articulation, depth first from the root (PhysX's
// order: a link's dofs, then its children in model order). Every row sees the exact current joint
// velocity, every earlier impulse of the sweep included, yet the sweep costs O(n): an impulse's
// effect on the root side is deferred and folded in when its subtree is left
// (docs/math/implicit_drives.md, "Propagating impulses"). Spatial quantities are those of frame 0
// (data.hpp), so nothing is transformed from link to link.
#pragma once

#include <utility>
#include <vector>

#include "featherdrive/algorithm/data.hpp"
#include "featherdrive/solver/sweep_law.hpp"

namespace featherdrive {

/// Scratch of a sweep, sized once per model.
struct SweepWorkspace {
  explicit SweepWorkspace(const Model& model);
  std::vector<Vec6> link_velocity_change;  ///< Delta v_i of the sweep when entering, frame 0
  /// pA_i: impulse handed up by finished children. Written first by the first child to leave,
  /// so it needs no clearing; a leaf's stays zero.
  std::vector<Vec6> subtree_impulse;
  std::vector<Vec6> parent_impulse_after;  ///< pA_parent right after link i handed its impulse
  std::vector<Vec6> later_velocity_change; ///< E_i: change of link i from later subtrees' impulses
  VecX joint_impulse;                      ///< impulse applied at each dof in this sweep (nv)
  VecX entry_velocity_change;              ///< each dof's velocity change when it was entered (nv)
  std::vector<char> has_rows;              ///< per dof: does the sweep solve a row here
  /// What the sweep's loops read of a link besides its spatial quantities, in one record (with
  /// them in separate arrays, each address was formed and each array's pointer reloaded).
  struct Link {
    int parent = -1;
    int v_index = 0;
    signed char nv = 0;
    bool last_child = true;  ///< no sibling after it
    /// It is its parent's first child (it hands the parent's pA its first value).
    bool first_child = false;
    /// It has one dof and link i + 1 is its child with one dof (a run of a chain).
    bool chain_next = false;
    bool parent_one_dof = false;  ///< its parent has one dof
    /// One dof and no later subtree, so its joint's velocity is final when it is left
    /// (detail::leave_links); the others, in model order, are finished after the sweep.
    bool finish_on_leave = false;
    /// One dof, finished on leave, and its one-dof parent's only child: leaving it is the
    /// tight loop of detail::leave_links.
    bool chain_up = false;
    /// It has contact rows (docs/math/contact.md, C15): solved right after its joint's rows, their
    /// impulse starts its pA, so its first child adds to pA instead of setting it.
    bool contacts = false;
  };
  std::vector<Link> links;
  std::vector<int> finish_after;
  /// Marks the links that have contact rows (num_links flags) and sets the flags that depend on
  /// it; all false restores the sweep without contacts.
  void set_contact_links(const std::vector<char>& has_contacts);
  bool any_contacts = false;
  std::vector<bool> first_child_free_, chain_next_free_;  ///< the flags without contacts
  Vec6 zero = Vec6::Zero();                ///< the world's velocity change
};

namespace detail {

// stop's velocity change corrected by its whole-articulation response to the impulse pa one of
// its children handed it (out of line: branching only).
[[gnu::noinline]] inline void correct_velocity_change(const Data& data, SweepWorkspace& ws, int p,
                                                      const Vec6& pa) {
  ws.link_velocity_change[p].noalias() -= data.response[p] * pa;
}

// S of a joint of N dofs as sweep_law reads it: a spherical joint's dense, a floating root's
// diag(R, R) from its rotation (the root's origin is frame 0's).
template <int N>
inline auto sweep_subspace(const Data& data, int i) {
  if constexpr (N == 6)
    return multi_dof_law::RotationPair<double, true>{data.world_rotation[i].data()};
  else
    return multi_dof_law::DenseSubspace<double, N>{data.motion_subspace[i].data()};
}

// A floating root whose dofs take no rows: entered as nothing (its velocity change stays the
// world's), finished by sweep_law::finish_rowless_root (eq. SW11), as the lanes' root.
template <class Link>
inline bool rowless_root(const SweepWorkspace& ws, const Link& link) {
  if (link.nv != 6 || link.parent >= 0) return false;
  for (int d = 0; d < 6; ++d)
    if (ws.has_rows[static_cast<size_t>(link.v_index + d)]) return false;
  return true;
}

// Link i with N dofs entered: its rows in turn, each at the velocity the impulses before it
// leave, then its velocity change and its link's (sweep_law, eq. SW6-SW8). Inline: out of line,
// the sweep's loop spilled two pointers in the one-dof links' run (chain256: 0.2 % more).
template <int N, class RowSolver>
[[gnu::always_inline]] inline void enter_multi_dof_link(const Data& data, SweepWorkspace& ws, int i,
                                                        const Vec6& dvp, double* qd,
                                                        RowSolver& solve_row) {
  const int v0 = data.info[i].v_index;
  const double* D_inv = data.D_inv[i].data();
  const double* inverse_mass = data.inverse_mass_block[i].data();
  double base[N], impulse[N];
  sweep_law::base_n<N>(D_inv, data.U[i].data(), dvp.data(), base);
  for (int a = 0; a < N; ++a) impulse[a] = 0.0;
  for (int a = 0; a < N; ++a) {
    if (!ws.has_rows[static_cast<size_t>(v0 + a)]) continue;
    impulse[a] += solve_row(
        v0 + a, sweep_law::row_velocity<N>(qd[v0 + a], base[a], inverse_mass, a, impulse));
  }
  for (int a = 0; a < N; ++a) ws.joint_impulse[v0 + a] = impulse[a];
  sweep_law::after_rows_n<N>(
      impulse, D_inv, data.parent_coupling[i].data(), data.U[i].data(), sweep_subspace<N>(data, i),
      dvp.data(), ws.entry_velocity_change.data() + v0, ws.link_velocity_change[i].data());
}

// Link k, with 0 or several dofs, hands pa = pA + U D^-1 (impulse - S^T pA) to its parent
// (sweep_law, eq. SW9).
template <int N>
inline void hand_over(const Data& data, const SweepWorkspace& ws, int k, Vec6& pa) {
  sweep_law::hand_over_n<N>(ws.joint_impulse.data() + data.info[k].v_index,
                            sweep_subspace<N>(data, k), data.U[k].data(), data.D_inv[k].data(),
                            ws.subtree_impulse[k].data(), pa.data());
}
[[gnu::noinline]] inline void leave_multi_dof_link(const Data& data, SweepWorkspace& ws, int k,
                                                   int stop, bool correct_stop) {
  const Data::LinkInfo& link = data.info[k];
  const int p = link.parent;
  if (p < 0) return;  // the root hands nothing on
  Vec6 pa;
  if (link.nv == 3)
    hand_over<3>(data, ws, k, pa);
  else if (link.nv == 6)
    hand_over<6>(data, ws, k, pa);
  else
    pa = ws.subtree_impulse[k];
  Vec6& pA_parent = ws.subtree_impulse[p];
  if (ws.links[k].first_child) pA_parent = pa;
  else pA_parent += pa;
  if (!link.last_child) ws.parent_impulse_after[k] = pA_parent;
  if (p == stop && correct_stop) correct_velocity_change(data, ws, p, pa);
}

// Leaves the finished links from k up to `stop` (not included; -1 for all): each hands its
// subtree's impulse pa = pA + U D^-1 (impulse - S^T pA) to its parent. When a sibling of the last
// one is entered next (correct_stop), stop's velocity change is corrected by its
// whole-articulation response to that impulse; no other link's velocity change is read again in
// the sweep. Along a run of 1-dof links, S_p^T pA_p of the next one is formed from scalars so that
// the 6-vector products stay off the chain of dependencies. Raw pointers are taken once: Eigen's
// vector stores may alias anything, which would make the compiler reload every std::vector's
// data pointer after each of them.
inline void leave_links(const Data& data, SweepWorkspace& ws, double* qd, int k, int stop,
                        bool correct_stop) {
  const SweepWorkspace::Link* const links = ws.links.data();
  const Data::OneDof* const one_dof = data.one_dof.data();
  Vec6* const subtree_impulse = ws.subtree_impulse.data();
  const double* const joint_impulse = ws.joint_impulse.data();
  const double* const entry_velocity_change = ws.entry_velocity_change.data();
  bool have_x = false;
  double x = 0.0;  // S_k^T pA_k when have_x
  while (k != stop) {
    const SweepWorkspace::Link& link = links[k];
    const int p = link.parent;
    if (link.chain_up && p != stop) {
      // A run of only children, as below with first = last = true and every flag known: pA
      // stays in registers and is stored once, for the link where the run ends (no link of the
      // run reads its own again).
      Vec6 pA = subtree_impulse[k];
      if (!have_x) x = sweep_law::dot6<double>(one_dof[k].S, pA);
      for (;;) {
        const Data::OneDof& J = one_dof[k];
        const int d = links[k].v_index;
        const int up = links[k].parent;
        const double beta = sweep_law::leave_beta(J.D_inv, joint_impulse[d], x);
        qd[d] = sweep_law::finished_velocity(qd[d], entry_velocity_change[d], J.G, pA);
        x = sweep_law::parent_S_pA(one_dof[up].S, pA, beta, J.parent_S);
        pA = pA + beta * J.U;
        k = up;
        if (!links[k].chain_up || links[k].parent == stop) break;
      }
      subtree_impulse[k] = pA;
      have_x = true;
      continue;
    }
    if (link.nv != 1) {
      leave_multi_dof_link(data, ws, k, stop, correct_stop);
      if (p < 0) return;
      have_x = false;
      k = p;
      continue;
    }
    const Data::OneDof& J = one_dof[k];
    const Vec6& pA = subtree_impulse[k];
    if (!have_x) x = sweep_law::dot6<double>(J.S, pA);
    const int d = link.v_index;
    const double beta = sweep_law::leave_beta(J.D_inv, joint_impulse[d], x);
    // Its velocity change: what it had when entered, plus what its subtree's impulses do to it.
    if (link.finish_on_leave)
      qd[d] = sweep_law::finished_velocity(qd[d], entry_velocity_change[d], J.G, pA);
    if (p < 0) return;
    // S_p^T of the parent's pA after this hand-over (pA_p so far + pA + beta U).
    have_x = link.parent_one_dof && p != stop;
    const bool first = link.first_child;
    Vec6& pA_parent = subtree_impulse[p];
    if (have_x) {
      const Vec6& S_p = one_dof[p].S;
      x = sweep_law::parent_S_pA(S_p, pA, beta, J.parent_S);
      if (!first) x += sweep_law::dot6<double>(S_p, pA_parent);
    }
    if (first) pA_parent = pA + beta * J.U;
    else pA_parent += pA + beta * J.U;
    if (!link.last_child) ws.parent_impulse_after[k] = pA_parent;
    if (p == stop && correct_stop) correct_velocity_change(data, ws, p, pA + beta * J.U);
    k = p;
  }
}

// The end of a sweep for link i with N dofs: its velocity change from its subtree (sweep_law,
// eq. SW10) and from later subtrees (SW5).
template <int N, class ParentLater>
void finish_multi_dof_link(const Data& data, SweepWorkspace& ws, int i, VecX& qd,
                           const ParentLater& parent_later) {
  const Data::LinkInfo& link = data.info[i];
  const int v0 = link.v_index;
  const auto S = sweep_subspace<N>(data, i);
  const double* D_inv = data.D_inv[i].data();
  double dqd[N];
  sweep_law::finished_n<N>(ws.entry_velocity_change.data() + v0, S, data.parent_coupling[i].data(),
                           data.inverse_mass_block[i].data(), D_inv, ws.subtree_impulse[i].data(),
                           dqd);
  if (link.later) {
    const Vec6 E_hat = parent_later();
    sweep_law::later_n<N>(D_inv, data.U[i].data(), S, E_hat.data(), dqd,
                          ws.later_velocity_change[i].data());
  }
  for (int a = 0; a < N; ++a) qd[v0 + a] += dqd[a];
}

// The end of a sweep for link i with 0 or several dofs, or with a later subtree: its joint's
// velocity change adds -G^T pA and what the later subtrees do (E).
[[gnu::noinline]] inline void finish_link(const Data& data, SweepWorkspace& ws, int i, VecX& qd) {
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
    double dqd = ws.entry_velocity_change[d] - sweep_law::dot6<double>(J.G, pA);
    if (link.later) {
      const Vec6 E_hat = parent_later();
      const double later = sweep_law::later(J.D_inv, J.U, E_hat);
      dqd += later;
      ws.later_velocity_change[i] = E_hat + later * J.S;
    }
    qd[d] += dqd;
    return;
  }
  if (link.nv == 0) {
    if (link.later) ws.later_velocity_change[i] = parent_later();
    return;
  }
  if (rowless_root(ws, link)) {  // no later subtree: the root
    sweep_law::finish_rowless_root<6>(sweep_subspace<6>(data, i), data.D_inv[i].data(), pA.data(),
                                      qd.data() + link.v_index);
    return;
  }
  if (link.nv == 3)
    finish_multi_dof_link<3>(data, ws, i, qd, parent_later);
  else
    finish_multi_dof_link<6>(data, ws, i, qd, parent_later);
}

}  // namespace detail

/// One sweep. qd (nv) holds the exact joint velocities on entry and on exit. For every dof with
/// ws.has_rows set, solve_row(dof, current_qd) returns the impulse to apply there. For every link
/// marked with contacts, solve_contacts(link, dv) is called right after the link's joint rows
/// with dv its velocity change of the sweep (frame 0, exact then); it solves the link's contact
/// rows, adds their velocity change to dv and returns the spatial impulse they applied (frame 0):
/// the sweep carries it to the rest of the articulation as an external impulse on the link.
template <class RowSolver, class ContactSolver>
void gauss_seidel_sweep(const Model& model, const Data& data, SweepWorkspace& ws, VecX& qd,
                        RowSolver&& solve_row, ContactSolver&& solve_contacts) {
  const int n = model.num_links();
  const SweepWorkspace::Link* const links = ws.links.data();
  const Data::OneDof* const one_dof = data.one_dof.data();
  Vec6* const velocity_change = ws.link_velocity_change.data();
  double* const joint_impulse = ws.joint_impulse.data();
  double* const entry_velocity_change = ws.entry_velocity_change.data();
  const char* const has_rows = ws.has_rows.data();
  double* const v = qd.data();
  int previous = -1;
  for (int i = 0; i < n; ++i) {
    const SweepWorkspace::Link& link = links[i];
    if (previous != link.parent) detail::leave_links(data, ws, v, previous, link.parent, true);
    previous = i;
    // Delta v of the parent, exact now.
    const Vec6& from_parent = link.parent >= 0 ? velocity_change[link.parent] : ws.zero;
    if (link.nv == 1) {
      // A run of 1-dof links, each the child of the one before. A joint's velocity change from
      // outside its subtree is base = -D^-1 U^T Delta v_p; its own impulse adds (M^-1)_ii times
      // it. The link then moves by Delta v_p - W D^-1 impulse + S (base + (M^-1)_ii impulse).
      // The next link's base, -D_c^-1 (U_c^T Delta v_p - h U_c^T W + dqd U_c^T S) with
      // h = D^-1 impulse, is affine in the impulse.
      const Vec6* dv_parent = &from_parent;
      double base = sweep_law::base(one_dof[i].D_inv, one_dof[i].U, from_parent);
      for (;;) {
        const Data::OneDof& J = one_dof[i];
        const int d = links[i].v_index;
        const bool next = links[i].chain_next;
        // next base = ahead + impulse * per_impulse, both formed before the impulse is known:
        // the chain of dependencies from one row to the next is one multiply-add
        // (docs/math/implicit_drives.md, eq. GS1-GS2).
        double ahead = 0.0, per_impulse = 0.0;
        if (next) {
          const Data::OneDof& C = one_dof[i + 1];
          ahead = sweep_law::ahead(C.D_inv, C.U, *dv_parent, base, C.base_per_parent_base);
          per_impulse = C.base_per_parent_impulse;
        }
        double impulse = 0.0;
        if (has_rows[d]) impulse = solve_row(d, v[d] + base);
        joint_impulse[d] = impulse;
        Vec6& dv = velocity_change[i];
        entry_velocity_change[d] =
            sweep_law::after_rows(base, impulse, J.inverse_mass, J.D_inv, *dv_parent, J.W, J.S, dv);
        if (!next) {  // a link with contacts ends its run (set_contact_links)
          if (links[i].contacts) ws.subtree_impulse[i] = -solve_contacts(i, dv);
          break;
        }
        base = sweep_law::chained_base(ahead, impulse, per_impulse);
        dv_parent = &dv;
        previous = ++i;
      }
      continue;
    }
    if (link.nv == 0) {
      velocity_change[i] = from_parent;
      if (link.contacts) ws.subtree_impulse[i] = -solve_contacts(i, velocity_change[i]);
      continue;
    }
    if (detail::rowless_root(ws, link))
      velocity_change[i] = from_parent;
    else if (link.nv == 3)
      detail::enter_multi_dof_link<3>(data, ws, i, from_parent, v, solve_row);
    else
      detail::enter_multi_dof_link<6>(data, ws, i, from_parent, v, solve_row);
    if (link.contacts) ws.subtree_impulse[i] = -solve_contacts(i, velocity_change[i]);
  }
  detail::leave_links(data, ws, v, previous, -1, false);
  // The joints not finished when left: several dofs, or a later subtree whose impulses also move
  // them (detail::finish_link), root first.
  for (const int i : ws.finish_after) detail::finish_link(data, ws, i, qd);
}

/// The sweep without contact rows.
template <class RowSolver>
void gauss_seidel_sweep(const Model& model, const Data& data, SweepWorkspace& ws, VecX& qd,
                        RowSolver&& solve_row) {
  gauss_seidel_sweep(model, data, ws, qd, std::forward<RowSolver>(solve_row),
                     [](int, Vec6&) { return Vec6(Vec6::Zero()); });
}

}  // namespace featherdrive
