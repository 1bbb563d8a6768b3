// One Gauss-Seidel sweep over the dof rows of an articulation, depth first from the root (PhysX's
// order: a link's dofs, then its children in model order). Every row sees the exact current joint
// velocity, every earlier impulse of the sweep included, yet the sweep costs O(n): an impulse's
// effect on the root side is deferred and folded in when its subtree is left
// (docs/math/implicit_drives.md, "Propagating impulses"). Spatial quantities are those of frame 0
// (data.hpp), so nothing is transformed from link to link.
#pragma once

#include <type_traits>
#include <utility>
#include <vector>

#include "featherdrive/algorithm/data.hpp"
#include "featherdrive/solver/sweep_law.hpp"
#include "featherdrive/solver/sweep_walk.hpp"

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
    /// (detail::SweepLeaving); the others, in model order, are finished after the sweep.
    bool finish_on_leave = false;
    /// One dof, finished on leave, and its one-dof parent's only child: it is left in a run
    /// (sweep_walk::chain_up), the tight loop of detail::SweepLeaving::leave_run.
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
// its children handed it (sweep_law, eq. SW13; out of line: branching only).
[[gnu::noinline]] inline void correct_velocity_change(const Data& data, SweepWorkspace& ws, int p,
                                                      const Vec6& pa) {
  sweep_law::correct_parent<double>(data.response[p], pa, ws.link_velocity_change[p]);
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
// (sweep_law, eq. SW9; a fixed joint pA whole).
template <int N>
inline void handed_n(const Data& data, const SweepWorkspace& ws, int k, Vec6& pa) {
  sweep_law::hand_over_n<N>(ws.joint_impulse.data() + data.info[k].v_index,
                            sweep_subspace<N>(data, k), data.U[k].data(), data.D_inv[k].data(),
                            ws.subtree_impulse[k].data(), pa.data());
}
[[gnu::noinline]] inline void leave_multi_dof_link(const Data& data, SweepWorkspace& ws, int k,
                                                   bool correct) {
  const Data::LinkInfo& link = data.info[k];
  const int p = link.parent;
  if (p < 0) return;  // the root hands nothing on
  Vec6 pa;
  if (link.nv == 3)
    handed_n<3>(data, ws, k, pa);
  else if (link.nv == 6)
    handed_n<6>(data, ws, k, pa);
  else
    pa = ws.subtree_impulse[k];
  Vec6& pA_parent = ws.subtree_impulse[p];
  sweep_law::hand_over<double>(pa, ws.links[k].first_child, pA_parent);
  if (!link.last_child) sweep_law::record_after<double>(pA_parent, ws.parent_impulse_after[k]);
  if (correct) correct_velocity_change(data, ws, p, pa);
}

// Leaving links for sweep_walk::leave_links: each hands its subtree's impulse
// pa = pA + U D^-1 (impulse - S^T pA) to its parent. Along a run of 1-dof links, S_p^T pA_p of
// the next one is formed from scalars (x) so that the 6-vector products stay off the chain of
// dependencies. Raw pointers are taken once: Eigen's vector stores may alias anything, which
// would make the compiler reload every std::vector's data pointer after each of them.
class SweepLeaving {
 public:
  SweepLeaving(const Data* data, SweepWorkspace* ws, double* qd)
      : data_(*data),
        ws_(*ws),
        qd_(qd),
        links_(ws->links.data()),
        one_dof_(data->one_dof.data()),
        subtree_impulse_(ws->subtree_impulse.data()),
        joint_impulse_(ws->joint_impulse.data()),
        entry_velocity_change_(ws->entry_velocity_change.data()) {}
  const SweepWorkspace::Link& link(int k) const { return links_[k]; }

  // A run of only children, as leave_link with first = last = true and every flag known: pA
  // stays in registers and is stored once, for the link where the run ends (no link of the run
  // reads its own again).
  [[gnu::always_inline]] int leave_run(int k, int stop) {
    Vec6 pA = subtree_impulse_[k];
    if (!have_x_) x_ = sweep_law::dot6<double>(one_dof_[k].S, pA);
    for (;;) {
      const Data::OneDof& J = one_dof_[k];
      const int d = links_[k].v_index;
      const int up = links_[k].parent;
      const double beta = sweep_law::leave_beta(J.D_inv, joint_impulse_[d], x_);
      qd_[d] = sweep_law::finished_velocity(qd_[d], entry_velocity_change_[d], J.G, pA);
      x_ = sweep_law::parent_S_pA(one_dof_[up].S, pA, beta, J.parent_S);
      pA = pA + beta * J.U;
      k = up;
      if (!sweep_walk::in_run(links_[k], stop)) break;
    }
    subtree_impulse_[k] = pA;
    have_x_ = true;
    return k;
  }

  [[gnu::always_inline]] void leave_link(int k, int stop, bool correct) {
    const SweepWorkspace::Link& link = links_[k];
    const int p = link.parent;
    if (link.nv != 1) {
      leave_multi_dof_link(data_, ws_, k, p == stop && correct);
      have_x_ = false;
      return;
    }
    const Data::OneDof& J = one_dof_[k];
    const Vec6& pA = subtree_impulse_[k];
    if (!have_x_) x_ = sweep_law::dot6<double>(J.S, pA);
    const int d = link.v_index;
    const double beta = sweep_law::leave_beta(J.D_inv, joint_impulse_[d], x_);
    // Its velocity change: what it had when entered, plus what its subtree's impulses do to it.
    if (link.finish_on_leave)
      qd_[d] = sweep_law::finished_velocity(qd_[d], entry_velocity_change_[d], J.G, pA);
    if (p < 0) return;
    // S_p^T of the parent's pA after this hand-over (pA_p so far + pA + beta U).
    have_x_ = link.parent_one_dof && p != stop;
    const bool first = link.first_child;
    Vec6& pA_parent = subtree_impulse_[p];
    if (have_x_) {
      const Vec6& S_p = one_dof_[p].S;
      x_ = sweep_law::parent_S_pA(S_p, pA, beta, J.parent_S);
      if (!first) x_ += sweep_law::dot6<double>(S_p, pA_parent);
    }
    const Vec6 pa = sweep_law::handed(pA, beta, J.U);
    sweep_law::hand_over<double>(pa, first, pA_parent);
    if (!link.last_child) sweep_law::record_after<double>(pA_parent, ws_.parent_impulse_after[k]);
    if (p == stop && correct) correct_velocity_change(data_, ws_, p, pa);
  }

 private:
  const Data& data_;
  SweepWorkspace& ws_;
  double* const qd_;
  const SweepWorkspace::Link* const links_;
  const Data::OneDof* const one_dof_;
  Vec6* const subtree_impulse_;
  const double* const joint_impulse_;
  const double* const entry_velocity_change_;
  bool have_x_ = false;
  double x_ = 0.0;  // S_k^T pA_k when have_x_
};

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

// Entering links for sweep_walk::sweep, and its leaving and finishing.
template <class RowSolver, class ContactSolver>
class SweepEntering {
 public:
  SweepEntering(const Model& model, const Data& data, SweepWorkspace& ws, VecX& qd,
                RowSolver& solve_row, ContactSolver& solve_contacts)
      : data_(data),
        ws_(ws),
        qd_(qd),
        solve_row_(solve_row),
        solve_contacts_(solve_contacts),
        n_(model.num_links()),
        links_(ws.links.data()),
        one_dof_(data.one_dof.data()),
        velocity_change_(ws.link_velocity_change.data()),
        joint_impulse_(ws.joint_impulse.data()),
        entry_velocity_change_(ws.entry_velocity_change.data()),
        has_rows_(ws.has_rows.data()),
        v_(qd.data()) {}
  int num_links() const { return n_; }
  const SweepWorkspace::Link& link(int i) const { return links_[i]; }
  void leave(int k, int stop, bool correct) const {
    sweep_walk::leave_links<SweepLeaving>(k, stop, correct, &data_, &ws_, v_);
  }
  const std::vector<int>& finish_after() const { return ws_.finish_after; }
  // The joints not finished when left: several dofs, or a later subtree whose impulses also move
  // them.
  void finish(int i) { finish_link(data_, ws_, i, qd_); }

  // Link i, and after a 1-dof link the run of 1-dof links each the child of the one before.
  [[gnu::always_inline]] void enter(int& i) {
    const SweepWorkspace::Link& link = links_[i];
    // Delta v of the parent, exact now.
    const Vec6& from_parent = link.parent >= 0 ? velocity_change_[link.parent] : ws_.zero;
    if (link.nv == 1) {
      // A joint's velocity change from outside its subtree is base = -D^-1 U^T Delta v_p; its
      // own impulse adds (M^-1)_ii times it. The link then moves by
      // Delta v_p - W D^-1 impulse + S (base + (M^-1)_ii impulse). The next link's base,
      // -D_c^-1 (U_c^T Delta v_p - h U_c^T W + dqd U_c^T S) with h = D^-1 impulse, is affine in
      // the impulse.
      const Vec6* dv_parent = &from_parent;
      double base = sweep_law::base(one_dof_[i].D_inv, one_dof_[i].U, from_parent);
      for (;;) {
        const Data::OneDof& J = one_dof_[i];
        const int d = links_[i].v_index;
        const bool next = links_[i].chain_next;
        // next base = ahead + impulse * per_impulse, both formed before the impulse is known:
        // the chain of dependencies from one row to the next is one multiply-add
        // (docs/math/implicit_drives.md, eq. GS1-GS2).
        double ahead = 0.0, per_impulse = 0.0;
        if (next) {
          const Data::OneDof& C = one_dof_[i + 1];
          ahead = sweep_law::ahead(C.D_inv, C.U, *dv_parent, base, C.base_per_parent_base);
          per_impulse = C.base_per_parent_impulse;
        }
        double impulse = 0.0;
        if (has_rows_[d]) impulse = solve_row_(d, v_[d] + base);
        joint_impulse_[d] = impulse;
        Vec6& dv = velocity_change_[i];
        entry_velocity_change_[d] =
            sweep_law::after_rows(base, impulse, J.inverse_mass, J.D_inv, *dv_parent, J.W, J.S, dv);
        if (!next) {  // a link with contacts ends its run (set_contact_links)
          if (links_[i].contacts) contacts(i);
          return;
        }
        base = sweep_law::chained_base(ahead, impulse, per_impulse);
        dv_parent = &dv;
        ++i;
      }
    }
    if (link.nv == 0 || rowless_root(ws_, link))
      velocity_change_[i] = from_parent;
    else if (link.nv == 3)
      enter_multi_dof_link<3>(data_, ws_, i, from_parent, v_, solve_row_);
    else
      enter_multi_dof_link<6>(data_, ws_, i, from_parent, v_, solve_row_);
    if (link.contacts) contacts(i);
  }

 private:
  // Link i's contact rows, right after its joint's (docs/math/contact.md, C15).
  void contacts(int i) { ws_.subtree_impulse[i] = -solve_contacts_(i, velocity_change_[i]); }

  const Data& data_;
  SweepWorkspace& ws_;
  VecX& qd_;
  RowSolver& solve_row_;
  ContactSolver& solve_contacts_;
  const int n_;
  const SweepWorkspace::Link* const links_;
  const Data::OneDof* const one_dof_;
  Vec6* const velocity_change_;
  double* const joint_impulse_;
  double* const entry_velocity_change_;
  const char* const has_rows_;
  double* const v_;
};

}  // namespace detail

/// One sweep (sweep_walk::sweep). qd (nv) holds the exact joint velocities on entry and on exit.
/// For every dof with ws.has_rows set, solve_row(dof, current_qd) returns the impulse to apply
/// there. For every link marked with contacts, solve_contacts(link, dv) is called right after the
/// link's joint rows with dv its velocity change of the sweep (frame 0, exact then); it solves the
/// link's contact rows, adds their velocity change to dv and returns the spatial impulse they
/// applied (frame 0): the sweep carries it to the rest of the articulation as an external impulse
/// on the link.
template <class RowSolver, class ContactSolver>
void gauss_seidel_sweep(const Model& model, const Data& data, SweepWorkspace& ws, VecX& qd,
                        RowSolver&& solve_row, ContactSolver&& solve_contacts) {
  detail::SweepEntering<std::remove_reference_t<RowSolver>, std::remove_reference_t<ContactSolver>>
      side(model, data, ws, qd, solve_row, solve_contacts);
  sweep_walk::sweep(side);
}

/// The sweep without contact rows.
template <class RowSolver>
void gauss_seidel_sweep(const Model& model, const Data& data, SweepWorkspace& ws, VecX& qd,
                        RowSolver&& solve_row) {
  gauss_seidel_sweep(model, data, ws, qd, std::forward<RowSolver>(solve_row),
                     [](int, Vec6&) { return Vec6(Vec6::Zero()); });
}

}  // namespace featherdrive
