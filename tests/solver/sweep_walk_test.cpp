// sweep_walk's order of entering, leaving and finishing on a hand-made tree, against the order
// docs/math/implicit_drives.md ("Propagating impulses") gives, worked out by hand below.
#include "featherdrive/solver/sweep_walk.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace featherdrive {
namespace {

struct ToyLink {
  int parent = -1;
  bool chain_up = false;
};

// Records what the walk asks of a side. A run is left as the sides leave it: up while in_run.
struct ToyLeaving {
  const std::vector<ToyLink>* links;
  std::string* log;
  const ToyLink& link(int k) const { return (*links)[k]; }
  int leave_run(int k, int stop) const {
    int end = k;
    while (sweep_walk::in_run(link(end), stop)) end = link(end).parent;
    *log += "R" + std::to_string(k) + "-" + std::to_string(end) + " ";
    return end;
  }
  void leave_link(int k, int stop, bool correct) const {
    const bool fix = correct && link(k).parent == stop;
    *log += "L" + std::to_string(k) + (fix ? "* " : " ");
  }
};

struct ToyEntering {
  std::vector<ToyLink> links;
  int joined_from = -1, joined_to = -1;  // entered together, as the scalar side's chain runs
  std::vector<int> finished_after;
  std::string log;
  int num_links() const { return static_cast<int>(links.size()); }
  const ToyLink& link(int i) const { return links[i]; }
  void enter(int& i) {
    if (i == joined_from) {
      log += "E" + std::to_string(i) + "-" + std::to_string(joined_to) + " ";
      i = joined_to;
      return;
    }
    log += "E" + std::to_string(i) + " ";
  }
  void leave(int k, int stop, bool correct) {
    sweep_walk::leave_links<ToyLeaving>(k, stop, correct, &links, &log);
  }
  const std::vector<int>& finish_after() const { return finished_after; }
  void finish(int i) { log += "F" + std::to_string(i) + " "; }
};

// 0 -> 1 -> 2 -> 3 and 0 -> 4 -> 5 in preorder; 2, 3 and 5 are left in runs.
ToyEntering toy_tree() {
  ToyEntering t;
  t.links = {{-1, false}, {0, false}, {1, true}, {2, true}, {0, false}, {4, true}};
  t.finished_after = {0, 1};
  return t;
}

// Entering 4 (parent 0) leaves 3's run up to 1, then 1 alone with 0's velocity change corrected
// (4 follows); the end leaves 5's run, 4 and the root without corrections, then finishes.
constexpr const char* kExpected = "E0 E1 E2 E3 R3-1 L1* E4 E5 R5-4 L4 L0 F0 F1 ";

TEST(SweepWalk, EntersLeavesAndFinishesInTheDocumentedOrder) {
  ToyEntering t = toy_tree();
  sweep_walk::sweep(t);
  EXPECT_EQ(t.log, kExpected);
}

// A run never takes in a link whose parent is where leaving stops: that link hands its impulse
// alone, with the correction.
TEST(SweepWalk, RunStopsBelowTheStopLink) {
  ToyEntering t = toy_tree();
  t.links[1].chain_up = true;
  sweep_walk::sweep(t);
  EXPECT_EQ(t.log, "E0 E1 E2 E3 R3-1 L1* E4 E5 R5-4 L4 L0 F0 F1 ");
}

// Links a side enters together (the scalar side's runs of one-dof links) are one step of the walk.
TEST(SweepWalk, LinksEnteredTogether) {
  ToyEntering t = toy_tree();
  t.joined_from = 1, t.joined_to = 3;
  sweep_walk::sweep(t);
  EXPECT_EQ(t.log, "E0 E1-3 R3-1 L1* E4 E5 R5-4 L4 L0 F0 F1 ");
}

// The runs: Simulation's need a parent of one dof (its S^T pA is carried in a scalar), the
// lanes' do not; neither takes a link with a later subtree (not finished on leave), a root or a
// link with a sibling.
TEST(SweepWalk, ChainUp) {
  EXPECT_TRUE(sweep_walk::chain_up<true>(true, 0, true, true, true));
  EXPECT_FALSE(sweep_walk::chain_up<true>(true, 0, false, true, true));
  EXPECT_TRUE(sweep_walk::chain_up<false>(true, 0, false, true, true));
  EXPECT_FALSE(sweep_walk::chain_up<false>(false, 0, true, true, true));
  EXPECT_FALSE(sweep_walk::chain_up<false>(true, -1, false, true, true));
  EXPECT_FALSE(sweep_walk::chain_up<false>(true, 0, true, false, true));
  EXPECT_FALSE(sweep_walk::chain_up<false>(true, 0, true, true, false));
}

}  // namespace
}  // namespace featherdrive
