// The walk of a Gauss-Seidel sweep over an articulation's links, written once for Simulation
// (gauss_seidel.hpp, doubles) and Batch's lanes (sim/simd_lane_step.hpp, packs): the order in
// which links are entered, left and finished, which links are left as a run of only children,
// and when a link's velocity change is corrected (docs/math/implicit_drives.md, "Propagating
// impulses"). What happens at one link is the side's, with sweep_law's operations.
//
// An Entering side supplies num_links(), link(i) (a record with parent and chain_up), enter(i)
// (link i's joint rows then its contact rows, docs/math/contact.md C15, and those of the links it
// enters with it: i becomes the last one entered), leave(k, stop, correct) (leave_links with its
// Leaving, built in there from a few arguments, so that its pointers stay in registers),
// finish_after() (the links finished after the sweep, root first, as a range) and finish(i).
// A Leaving supplies link(k), leave_run(k, stop) (leaves the run from k while in_run holds;
// returns the link where it ends) and leave_link(k, stop, correct) (k hands its subtree's
// impulse to its parent, starting the parent's when k is its first child, records the parent's
// when a sibling follows, and corrects the parent's velocity change when correct and the parent
// is stop: sweep_law's hand_over, record_after and correct_parent on the side's storage; the
// side tests correct where it costs least).
// Include-free: the lanes' AVX2 and AVX-512 units take in no inline function of the library.
#pragma once

namespace featherdrive::sweep_walk {

/// Link k is left in a run of only children (Leaving::leave_run): it is finished when left (one
/// dof, no later subtree) and its parent's only child, and, where the side carries the parent's
/// S^T pA through the run in a scalar (kOneDofParent: Simulation), its parent has one dof.
template <bool kOneDofParent>
constexpr bool chain_up(bool finish_on_leave, int parent, bool parent_one_dof, bool first_child,
                        bool last_child) {
  return finish_on_leave && parent >= 0 && first_child && last_child &&
         (!kOneDofParent || parent_one_dof);
}

/// A run goes on through link l unless its parent is stop (whose velocity change the walk may
/// correct, and where leaving ends).
template <class Link>
[[gnu::always_inline]] inline bool in_run(const Link& l, int stop) {
  return l.chain_up && l.parent != stop;
}

/// Leaves the finished links from k up to stop (not included; -1 for all). When a sibling of the
/// last one is entered next (correct), stop's velocity change is corrected by its whole-
/// articulation response to the impulse handed to it; no other link's velocity change is read
/// again in the sweep.
template <class Leaving, class... Args>
void leave_links(int k, int stop, bool correct, Args... args) {
  Leaving s{args...};
  while (k != stop) {
    if (in_run(s.link(k), stop)) {
      k = s.leave_run(k, stop);
      continue;
    }
    const int p = s.link(k).parent;
    s.leave_link(k, stop, correct);
    if (p < 0) return;  // the root hands nothing on
    k = p;
  }
}

/// One sweep: the links entered in storage order (depth-first preorder), the finished ones left
/// before a link whose parent is not the one entered last, then everything left, and the joints
/// not finished when left finished.
template <class Entering>
[[gnu::always_inline]] inline void sweep(Entering& s) {
  const int n = s.num_links();
  int previous = -1;
  for (int i = 0; i < n; ++i) {
    const int parent = s.link(i).parent;
    if (previous != parent) s.leave(previous, parent, true);
    s.enter(i);
    previous = i;
  }
  s.leave(previous, -1, false);
  for (const int i : s.finish_after()) s.finish(i);
}

}  // namespace featherdrive::sweep_walk
