// A hand-specialised PGS step for the benchmarks' chain: the reference of issue 21's single-step
// target, measured beside Simulation::step (docs/benchmarks.md, "The single step and its
// prototype"). The same math as Simulation for this one case (a fixed base, revolute joints about
// coordinate axes, force drives alone, compat none), with everything the general step must
// decide at run time fixed: no branches on joint types or row kinds, every link's sweep constants
// in one 256-byte record, the sweeps' velocity change and impulse carried in registers, the
// 6-vectors and the columns of 6 x 6 matrices in aligned pairs of doubles (SSE2, the portable
// build's instruction set).
#pragma once

#include <vector>

#include "featherdrive/sim/simulation.hpp"

namespace featherdrive::bench {

namespace proto {
using Pair = double __attribute__((vector_size(16)));  // GCC's and Clang's vector extension
struct V6 {                                            // a 6-vector as three pairs
  Pair p[3];
};
}  // namespace proto

class ChainPrototype {
 public:
  /// sim's model, drives, state and PGS options. Throws std::invalid_argument unless its model is
  /// such a chain (link 0 fixed at the origin, link i + 1 the child of link i) with diagonal link
  /// inertias, every dof has a force drive, and nothing else acts (limits, friction, applied
  /// forces, velocity limits, link settings).
  explicit ChainPrototype(const Simulation& sim);

  void step();
  /// Sets the state (nv each); the drive forces stay those of the last step.
  void set_state(const std::vector<double>& q, const std::vector<double>& qd);

  const std::vector<double>& q() const { return q_; }
  const std::vector<double>& qd() const { return qd_; }
  /// The drive force of the last step per dof (its accumulated impulse / dt).
  std::vector<double> drive_force() const;

 private:
  struct Link {                 // constants
    int A = 0, A1 = 1, A2 = 2;  // the axis and the two it turns
    double sign = 1.0;
    double r[3] = {0, 0, 0};  // joint origin in the parent's frame
    double mass = 0.0;
    double com[3] = {0, 0, 0};
    double moment[3] = {0, 0, 0};  // principal moments, link axes
    double armature = 0.0;
    double drive_a = 0.0;  // h (h kp + kd), eq. (13)
    double drive_b = 0.0;  // h kd v_target, eq. (14)
    double h_kp = 0.0;
    double target = 0.0;
  };
  using V6 = proto::V6;
  struct Body {  // ABA's per-link quantities of a step
    V6 IA[6];    // columns
    V6 c, pA;
    double u, pad;
  };
  struct Hot {  // what the sweeps read of a link: 32 doubles
    V6 S, U, W, G;
    double D_inv, r, base_per_parent_base, base_per_parent_impulse, parent_S;
    double row_T, row_V, row_m;  // lambda = T + m accumulated + V v (eq. 20-22)
  };
  struct Dof {  // what the sweeps write, and the drive's bound
    double accumulated, impulse, entry_change, max_impulse;
  };

  void sweep();

  int n_ = 0;
  double dt_ = 0.0;
  int position_iterations_ = 0, velocity_iterations_ = 0;
  double gravity_[3] = {0, 0, 0};
  std::vector<Link> links_;
  std::vector<Body> bodies_;
  std::vector<Hot> hot_;  // n + 1: a zero record after the last
  std::vector<Dof> dofs_;
  std::vector<double> q_, qd_;
};

}  // namespace featherdrive::bench
