// Batch's lane step on one block of W lanes, one environment per lane, written once for any
// xsimd architecture A, or One (a plain double: one lane), and instantiated by
// simd_lane_step_<isa>.cpp and simd_lane_step_one.cpp (each compiled for its instruction set,
// with -ffp-contract=off). It is Simulation's step (step.cpp, aba.cpp,
// inverse_mass_diagonal.cpp, gauss_seidel.hpp, dof_rows.cpp) for links of 0 or 1 dof on a fixed
// or floating base, with every branch on lane data turned into a select, so every lane runs the
// same operations: only + - * /, sqrt (correctly rounded) and exact selects and comparisons, never
// the library's math functions or fma, whose results differ between instruction sets.
// docs/simd_batch.md.
// Everything here has internal linkage: the units compiled with -mavx2 and -mavx512f must not lend
// an inline function to the rest of the library.
#pragma once

#include <array>
#include <cmath>
#include <tuple>
#include <type_traits>
#include <utility>

#include <xsimd/xsimd.hpp>

#include "featherdrive/algorithm/articulated_law.hpp"
#include "featherdrive/algorithm/link_motion_law.hpp"
#include "featherdrive/algorithm/multi_dof_law.hpp"
#include "featherdrive/algorithm/response_law.hpp"
#include "featherdrive/constraint/actuator_row.hpp"
#include "featherdrive/constraint/drive.hpp"
#include "featherdrive/constraint/mimic_law.hpp"
#include "featherdrive/constraint/row_laws.hpp"
#include "featherdrive/constraint/row_sequence.hpp"
#include "featherdrive/constraint/row_setup.hpp"
#include "featherdrive/sim/integration_law.hpp"
#include "featherdrive/sim/link_bias_law.hpp"
#include "featherdrive/sim/link_laws.hpp"
#include "featherdrive/sim/momentum_law.hpp"
#include "featherdrive/sim/revolute_wrap_law.hpp"
#include "featherdrive/solver/sweep_law.hpp"
#include "featherdrive/solver/sweep_walk.hpp"
#include "featherdrive/spatial/joint_transform_law.hpp"
#include "featherdrive/spatial/quaternion_law.hpp"
#include "featherdrive/spatial/sincos.hpp"
#include "simd_plan.hpp"

namespace featherdrive::simd {
namespace {

// A symmetric 6 x 6 matrix [A, B; B^T, C] is stored as A's six distinct entries (00, 11, 22, 01,
// 02, 12), B's nine (row-major), C's six: entry (a, b) at kSym[a][b] (link_law's packed layout).
constexpr const auto& kSym = link_law::kPacked;

// Architecture A's vector of doubles and its mask as the lane step uses them: an xsimd
// architecture's batch, or One's plain double (one lane, simd_lane_step_one.cpp). The step
// calls xsimd only through these and the lane_* overloads below, so that it compiles for both.
template <class A>
struct LaneVector {
  using B = xsimd::batch<double, A>;
  using M = xsimd::batch_bool<double, A>;
  static constexpr std::size_t size = B::size;
  static B load_aligned(const double* p) { return B::load_aligned(p); }
  static B load_unaligned(const double* p) { return B::load_unaligned(p); }
  static void store_aligned(const B& x, double* p) { x.store_aligned(p); }
};
template <class A>
xsimd::batch<double, A> lane_select(const xsimd::batch_bool<double, A>& c,
                                    const xsimd::batch<double, A>& x,
                                    const xsimd::batch<double, A>& y) {
  return xsimd::select(c, x, y);
}
template <class A>
xsimd::batch<double, A> lane_sqrt(const xsimd::batch<double, A>& x) {
  return xsimd::sqrt(x);
}
template <class A>
bool lane_any(const xsimd::batch_bool<double, A>& c) {
  return xsimd::any(c);
}
template <class A>
bool lane_all(const xsimd::batch_bool<double, A>& c) {
  return xsimd::all(c);
}

// One lane: a double and a bool, whose operations (+ - * /, sqrt, comparisons) are the same
// IEEE operations as a vector's lane by lane, so it gives the lanes' bits.
struct One {};
template <>
struct LaneVector<One> {
  using B = double;
  using M = bool;
  static constexpr std::size_t size = 1;
  static B load_aligned(const double* p) { return *p; }
  static B load_unaligned(const double* p) { return *p; }
  static void store_aligned(B x, double* p) { *p = x; }
};
inline double lane_select(bool c, double x, double y) { return c ? x : y; }
using featherdrive::select;  // a plain double's (core/select.hpp), beside the packs' below
inline double lane_sqrt(double x) { return std::sqrt(x); }
inline bool lane_any(bool c) { return c; }
inline bool lane_all(bool c) { return c; }

// K vectors of architecture A as one vector of K W lanes: K independent chains of
// dependencies per operation, so a sweep's link-to-link latency is paid once for K W lanes.
// Every operation acts lane by lane, as on one vector.
template <class A, int K>
struct PackMask {
  typename LaneVector<A>::M m[K];
};

template <class A, int K>
struct Pack {
  using L = LaneVector<A>;
  using B = typename L::B;
  static constexpr std::size_t size = L::size * K;
  B b[K];
  Pack() = default;
  Pack(double x) {  // NOLINT: broadcast, as xsimd's batch
    for (int k = 0; k < K; ++k) b[k] = B(x);
  }
  static Pack load_aligned(const double* p) {
    Pack out;
    for (int k = 0; k < K; ++k) out.b[k] = L::load_aligned(p + k * L::size);
    return out;
  }
  void store_aligned(double* p) const {
    for (int k = 0; k < K; ++k) L::store_aligned(b[k], p + k * L::size);
  }
};

#define FEATHERDRIVE_PACK_BINARY(OP, R, F)                        \
  template <class A, int K>                                       \
  R<A, K> operator OP(const Pack<A, K>& x, const Pack<A, K>& y) { \
    R<A, K> out;                                                  \
    for (int k = 0; k < K; ++k) out.F[k] = x.b[k] OP y.b[k];      \
    return out;                                                   \
  }
FEATHERDRIVE_PACK_BINARY(+, Pack, b)
FEATHERDRIVE_PACK_BINARY(-, Pack, b)
FEATHERDRIVE_PACK_BINARY(*, Pack, b)
FEATHERDRIVE_PACK_BINARY(/, Pack, b)
FEATHERDRIVE_PACK_BINARY(==, PackMask, m)
FEATHERDRIVE_PACK_BINARY(!=, PackMask, m)
FEATHERDRIVE_PACK_BINARY(<, PackMask, m)
FEATHERDRIVE_PACK_BINARY(>, PackMask, m)
FEATHERDRIVE_PACK_BINARY(>=, PackMask, m)
#undef FEATHERDRIVE_PACK_BINARY

template <class A, int K>
Pack<A, K> operator-(const Pack<A, K>& x) {
  Pack<A, K> out;
  for (int k = 0; k < K; ++k) out.b[k] = -x.b[k];
  return out;
}
template <class A, int K>
PackMask<A, K> operator|(const PackMask<A, K>& x, const PackMask<A, K>& y) {
  PackMask<A, K> out;
  for (int k = 0; k < K; ++k) out.m[k] = x.m[k] | y.m[k];
  return out;
}
template <class A, int K>
PackMask<A, K> operator&(const PackMask<A, K>& x, const PackMask<A, K>& y) {
  PackMask<A, K> out;
  for (int k = 0; k < K; ++k) out.m[k] = x.m[k] & y.m[k];
  return out;
}
template <class A, int K>
PackMask<A, K> operator!(const PackMask<A, K>& x) {
  PackMask<A, K> out;
  for (int k = 0; k < K; ++k) out.m[k] = !x.m[k];
  return out;
}
template <class A, int K>
Pack<A, K> select(const PackMask<A, K>& c, const Pack<A, K>& x, const Pack<A, K>& y) {
  Pack<A, K> out;
  for (int k = 0; k < K; ++k) out.b[k] = lane_select(c.m[k], x.b[k], y.b[k]);
  return out;
}
// Correctly rounded lane by lane, as std::sqrt (the laws over the number type find it by
// argument-dependent lookup: sim/link_laws.hpp).
template <class A, int K>
Pack<A, K> sqrt(const Pack<A, K>& x) {
  Pack<A, K> out;
  for (int k = 0; k < K; ++k) out.b[k] = lane_sqrt(x.b[k]);
  return out;
}
template <class A, int K>
bool any(const PackMask<A, K>& c) {
  for (int k = 0; k < K; ++k)
    if (lane_any(c.m[k])) return true;
  return false;
}
template <class A, int K>
bool all(const PackMask<A, K>& c) {
  for (int k = 0; k < K; ++k)
    if (!lane_all(c.m[k])) return false;
  return true;
}

template <class A, int K>
class LaneStep {
 public:
  using V = Pack<A, K>;
  using M = PackMask<A, K>;
  using B = typename LaneVector<A>::B;
  static constexpr int kW = static_cast<int>(V::size);
  static constexpr int kVector = static_cast<int>(LaneVector<A>::size);

  LaneStep(const Plan& p, const Block& b, double* scratch)
      : p_(p), b_(b), l_(p.layout), s_(reinterpret_cast<V*>(scratch)),
        forces_{p.layout.df, p.layout.lf, p.layout.ff, p.layout.vf},
        old_forces_{p.layout.old_df, p.layout.old_lf, p.layout.old_ff, p.layout.old_vf} {
    for (int k = 0; k < K; ++k) {
      const int e = b.env0 + k * kVector;
      parameters_[k] = b.parameters + (e / kGroup) * p.entries * kGroup + e % kGroup;
    }
  }

  void run(int steps);

 private:
  // Scratch and parameters.
  V* at(int base) { return s_ + base; }
  // Entry k of the lanes' parameters: vector j of the pack, or the whole pack.
  B parameter(int k, int j) const {
    return LaneVector<A>::load_unaligned(parameters_[j] + k * kGroup);
  }
  V parameter(int k) const {
    V out;
    for (int j = 0; j < K; ++j) out.b[j] = parameter(k, j);
    return out;
  }
  V dof_parameter(int d, int f) const { return parameter(d * kDofParameters + f); }
  // Vector j only: the link's parameters are read one vector at a time (gathered into packs
  // first, they went through the stack).
  B link_parameter(int i, int f, int j) const {
    return parameter(p_.nv * kDofParameters + i * kLinkParameters + f, j);
  }
  V link_parameter_pack(int i, int f) const {
    return parameter(p_.nv * kDofParameters + i * kLinkParameters + f);
  }
  V* row(int d) { return sa_.row + Layout::kRowFields * d; }
  static constexpr double kActuator = 1.0, kMotorClip = 2.0, kTableClip = 4.0;
  static bool has_bit(double flags, double bit) {
    return (static_cast<int>(flags) & static_cast<int>(bit)) != 0;
  }
  // Per dof: some lane has friction, some a limit, every lane a drive, some a velocity limit,
  // some a wrapped position, some an envelope, some transmitted friction, and [7] the implicit
  // actuators' kinds (bits: kActuator some lane has one, kMotorClip a dc_motor, kTableClip a
  // remotized_pd), [8] the row kinds some lane has (bit k: RowKinds' kind k).
  double* any_row(int d) { return sa_.flags + 16 * d; }
  // any_row's entries the sweeps set (prepare_sweeps): [9] every lane has friction, [10] some
  // lane's limit may act whatever its velocity (row_law::limit_held; 1 in TGS, whose dx changes),
  // [11] its rows are a lone drive's (Entering::enter).
  static constexpr int kAllFriction = 9, kLimitHeld = 10, kDriveAlone = 11;
  int env_of_lane(int l) const { return b_.env0 + (l < b_.valid ? l : b_.valid - 1); }
  // The state arrays' row of environment e (Block::rows).
  long row_of(int e) const { return b_.rows ? b_.rows[e] : e; }
  // Gravity's component r, per lane (EnvParameter).
  int gravity_entry(int r) const {
    return p_.nv * kDofParameters + p_.num_links * kLinkParameters +
           p_.num_mimic * kMimicParameters + gravity_x + r;
  }
  void scatter(V x, double* rows, int stride, int k) const;
  // Entries 0 .. n - 1 of every lane's row (stride apart) into the packs out[0 .. n - 1], and
  // back (the lanes still stepping): lane by lane, each row's address formed once.
  void gather_rows(const double* rows, int stride, int n, V* out) const;
  void scatter_rows(const V* in, double* rows, int stride, int n) const;

  // The stages of a step.
  void step();
  void scale_to_velocity_limits();
  void kinematics_and_bias();
  template <bool kStart = true>
  void link_pose(int i);
  void link_velocity_and_bias(int i);
  void articulated_pass();
  void forward_pass();
  void link_acceleration(int i, const V* g, const V& dt);
  void link_response(int i);
  void transmitted_force(int i);
  void link_damping(int i, int j, const B* R, const B* RI, const B* cg, const B& m, const B* v,
                    B* F) const;
  void link_cfm(int i);
  void setup_row_constants(double h);
  void setup_link_rows(int i);
  void setup_dof_row(int i, int d, const V& r, const V& x0, const V& x0_drive);
  struct LaneDof;
  V solve_row(int d, V v, const V& dx);
  template <class L, bool kLoneDrive = false>
  struct LaneRows;
  row_sequence::Phase row_phase() const {
    return {p_.tgs, velocity_iteration_, time_to_step_end_,
            {h_, recip_h_, p_.limit_erp, velocity_iteration_}};
  }
  V clip_actuator(int d, const V* rw, const V& lambda, const V& accumulated, const V& v,
                  const V& r, const V& dx);
  template <bool kGiven, class L>
  void enter_link(const L& lane, int i, const V* dvp, V* dv);
  // A one-dof link's arrays as leaving reads and writes them, found once for all its vectors (a
  // store through a pack may alias the plan: what is found after one is found again).
  struct LeftLink {
    const V *D_inv, *jimp, *S, *pA, *U, *G, *entry;
    V *qd, *pA_parent;
    bool finish;
  };
  LeftLink left_link(int k);
  template <class L>
  void leave_chain_link(const L& lane, const LeftLink& l, bool to_parent, V& beta);
  void sweep();
  void prepare_sweeps();
  void find_held_limits();
  // f(d) for every dof of a one-dof or spherical joint (a floating root's rows are zero).
  template <class F>
  void for_each_joint_row_dof(const F& f) const {
    for (int i = 0; i < p_.num_links; ++i) {
      const LinkConstants& k = sa_.links[i];
      if (k.type != 1 && k.type != 2 && k.type != 4) continue;
      for (int d = k.v_index; d < k.v_index + (k.type == 4 ? 3 : 1); ++d) f(d);
    }
  }
  template <bool kGiven>
  void sweep_links();
  // The sides of sweep_walk (the walk over the links, shared with Simulation's sweep).
  template <bool kGiven>
  struct Entering;
  struct Leaving;
  void setup_mimic();
  void link_bias();
  void track_prismatic(double h);
  void clamp_prismatic();
  V row_bias(int d) { return at(l_.row_bias)[d]; }
  // Link i's centre of mass in world axes at the pose (R, pos).
  void link_com(int i, const V* R, const V* pos, V* out) const {
    V com[3];
    for (int r = 0; r < 3; ++r) com[r] = link_parameter_pack(i, com_x + r);
    for (int r = 0; r < 3; ++r)
      out[r] = pos[r] + (R[3 * r] * com[0] + R[3 * r + 1] * com[1] + R[3 * r + 2] * com[2]);
  }
  void solve_mimic();
  V mimic_parameter(int j, int f) const {
    return parameter(p_.nv * kDofParameters + p_.num_links * kLinkParameters +
                     j * kMimicParameters + f);
  }
  void leave_link(int k, bool fix);
  [[gnu::noinline]] void correct_parent(int p, const V* pa);
  int leave_chain_run(int k, int stop);
  void finish_link(int i);
  void finish_run(int i, const V* E);
  // A floating root, link 0 (docs/simd_batch.md, "Floating bases").
  template <bool kStart>
  void root_pose(V* R);
  void root_articulated();
  void root_acceleration(V* a, const V& dt);
  void root_response();
  void root_finish();
  void integrate_root(double h);
  void integrate_balls_physx(double h);
  // Spherical joints (docs/simd_batch.md, "Spherical joints"): three dofs, S, U, W 6 x 3.
  void ball_pose(int i, const V* P, V* R, const V* pos, bool start);
  void ball_articulated(int i);
  void ball_acceleration(int i, V* a, const V& dt);
  void ball_response(int i);
  void ball_rows(int i);
  template <bool kGiven>
  void enter_ball(int i, const V* dvp, V* dv);
  void leave_ball(int k, V* pa);
  void finish_ball(int i, const V* E);
  void end_classical_root();
  // compat physx on a floating root (physx_departures.md, section 2).
  void physx_start();
  void physx_free_momentum();
  void integrate_root_physx(double h);
  void root_origin(const V* q, V* p);
  void physx_end_momentum();
  void world_velocity(const V* R, const V* pos, const V* com, const V* qd, const V* w0,
                      const V* v0);
  void inertia_com(int i, V* Ic) const;  // link i's about its centre of mass, its axes
  void world_inertia(int i, const V* Ri, V* I) const;  // (R Ic) R^T of link i at rotation Ri
  // momentum_law's view of the links in the pose (R, com, frame 0's origin) with the velocities
  // vel_w, vel_v, plus the link bias where asked.
  struct PoseLinks {
    const LaneStep& step;
    const V* R;
    const V* c;
    bool bias_w = false, bias_v = false;
    V mass(int i) const { return step.link_parameter_pack(i, LinkParameter::mass); }
    const V* com(int i) const { return c + 3 * i; }
    void world_inertia(int i, V* I) const { step.world_inertia(i, R + 9 * i, I); }
    void world_inertia_times(int i, const V* w, V* Iw) const {
      V Ic[9];
      step.inertia_com(i, Ic);
      momentum_law::world_inertia_times(joint_transform_law::rows(R + 9 * i),
                                        joint_transform_law::rows(Ic), w, Iw);
    }
    void velocity(int i, V* w, V* v) const {
      const V* s = step.s_;
      const Layout& l = step.l_;
      for (int r = 0; r < 3; ++r) {
        w[r] = bias_w ? s[l.vel_w + 3 * i + r] + s[l.bias_w + 3 * i + r] : s[l.vel_w + 3 * i + r];
        v[r] = bias_v ? s[l.vel_v + 3 * i + r] + s[l.bias_v + 3 * i + r] : s[l.vel_v + 3 * i + r];
      }
    }
  };
  // Quaternions (w x y z) by spatial/quaternion_law.hpp, as Simulation's.
  static void rotate(const V* q, const V* v, V* out) { quaternion_law::rotate(q, v, out); }
  static void unit_quaternion(const V* q, V* out) { quaternion_law::unit(q, out); }
  static void quaternion_product(const V* a, const V* b, V* out) {
    quaternion_law::product(a, b, out);
  }
  static void quaternion_rotation(const V* q, V* R) { quaternion_law::rotation(q, R); }
  static V sqrt_of(const V& x) {  // correctly rounded: the same bits at every width
    V out;
    for (int k = 0; k < K; ++k) out.b[k] = lane_sqrt(x.b[k]);
    return out;
  }
  static bool one_dof(const LinkConstants& k) { return k.type == 1 || k.type == 2; }
  // Ground contacts (docs/simd_batch.md, "Contacts"): each live lane's own rows, out of line.
  void contact_velocities();
  void contact_bias();
  template <bool kGiven>
  void contact_link(int i);
  void track_contacts(double h);
  double* scratch() const { return reinterpret_cast<double*>(s_); }
  void integrate(double h, bool track);
  void wrap_positions();
  void finish_step();

  static void sincos(V x, V& s, V& c);
  // A row-major 3 x 3 matrix of constants (double[9]) read as packs, for joint_transform_law.
  struct Broadcast {
    const double* m;
    V operator()(int r, int c) const { return V(m[3 * r + c]); }
  };
  struct BroadcastTransposed {  // the transpose of Broadcast's matrix
    const double* m;
    V operator()(int r, int c) const { return V(m[3 * c + r]); }
  };
  static V dot6(const V* a, const V* b) { return dot6(WholePack{}, a, b); }
  static void sym_times(const V* m, const V* x, V* y);  // y = M x, M symmetric 6 x 6
  // y = M x for vector j of the packs of M (x, y: that vector's entries, kept in registers).
  [[gnu::always_inline]] static void sym_times(const V* m, int j, const B* x, B* y) {
    for (int r = 0; r < 6; ++r) {
      B sum = m[kSym[r][0]].b[j] * x[0];
      for (int k = 1; k < 6; ++k) sum = sum + m[kSym[r][k]].b[j] * x[k];
      y[r] = sum;
    }
  }
  // Vector j of the packs of a row-major 3 x 3 (a rotation), read where it is stored.
  struct VectorRows {
    const V* m;
    int j;
    [[gnu::always_inline]] B operator()(int r, int c) const { return m[3 * r + c].b[j]; }
  };
  // f(axis) with a unit axis 0, 1 or 2 as a constant (std::integral_constant), else as it is.
  template <class F>
  [[gnu::always_inline]] static void with_unit_axis(int axis, const F& f) {
    switch (axis) {
      case 0: f(std::integral_constant<int, 0>{}); return;
      case 1: f(std::integral_constant<int, 1>{}); return;
      case 2: f(std::integral_constant<int, 2>{}); return;
      default: f(axis);
    }
  }
  // Vector j of the packs of a symmetric 6 x 6 (kSym), as articulated_law reads it.
  struct SymmetricVector {
    const V* m;
    int j;
    [[gnu::always_inline]] B operator()(int a, int b) const { return m[kSym[a][b]].b[j]; }
  };
  // Whole packs of a symmetric 6 x 6 (kSym), as multi_dof_law and response_law read it and
  // multi_dof_law accumulates it (the upper triangle).
  struct SymmetricPack {
    const V* m;
    [[gnu::always_inline]] V operator()(int a, int b) const { return m[kSym[a][b]]; }
  };
  struct SymmetricPackSum {
    V* m;
    template <class F>
    [[gnu::always_inline]] void accumulate(const F& f) const {
      for (int a = 0; a < 6; ++a)
        for (int b = a; b < 6; ++b) m[kSym[a][b]] = m[kSym[a][b]] + f(a, b);
    }
  };
  struct PackSqrt {
    V operator()(const V& x) const { return sqrt_of(x); }
  };
  // Vector j of the packs of a symmetric 6 x 6 (kSym), as articulated_law accumulates it: the
  // upper triangle row by row, entry (a, b) for b >= a, each stored as it is summed (formed
  // first and stored together, the sums spilled: 7 % more instructions in articulated_pass).
  struct SymmetricSum {
    V* m;
    int j;
    template <class F>
    [[gnu::always_inline]] void accumulate(const F& f) const {
      for (int a = 0; a < 6; ++a)
        for (int b = a; b < 6; ++b) {
          const int k = kSym[a][b];
          m[k].b[j] = m[k].b[j] + f(a, b);
        }
    }
  };
  // Vector j of the packs of a symmetric 6 x 6 (kSym), as response_law writes it: the upper
  // triangle row by row, each entry stored as it is formed (formed first and stored together,
  // they spill: 2 % more instructions in a Batch step with SSE2).
  struct SymmetricAssign {
    V* m;
    int j;
    template <class F>
    [[gnu::always_inline]] void assign(const F& f) const {
      for (int a = 0; a < 6; ++a)
        for (int b = a; b < 6; ++b) m[kSym[a][b]].b[j] = f(a, b);
    }
  };
  // Whole packs of a symmetric 6 x 6 (kSym), as response_law's multi-dof law writes it (the upper
  // triangle row by row; it reads through SymmetricPack).
  struct SymmetricPacksAssign {
    V* m;
    template <class F>
    [[gnu::always_inline]] void assign(const F& f) const {
      for (int a = 0; a < 6; ++a)
        for (int b = a; b < 6; ++b) m[kSym[a][b]] = f(a, b);
    }
  };
  // An N x N of packs stored row by row (D^-1).
  template <int N>
  struct RowMajorPacks {
    const V* m;
    [[gnu::always_inline]] const V& operator()(int a, int b) const { return m[N * a + b]; }
  };
  // a^T b summed left to right. The sweep's one-dof operations sum in sweep_law's order (SW0,
  // the scalar step's) instead.
  template <class T>
  [[gnu::always_inline]] static T sum6(const T& p0, const T& p1, const T& p2, const T& p3,
                                       const T& p4, const T& p5) {
    return p0 + p1 + p2 + p3 + p4 + p5;
  }
  [[gnu::always_inline]] static B dot6(const B* a, const B* b) {
    return sum6(a[0] * b[0], a[1] * b[1], a[2] * b[2], a[3] * b[3], a[4] * b[4], a[5] * b[5]);
  }
  // Entries 0-5 of vector j of the packs at p.
  [[gnu::always_inline]] static void take6(const V* p, int j, B* out) {
    for (int r = 0; r < 6; ++r) out[r] = p[r].b[j];
  }
  // Which lanes a piece of a sweep acts on at a time: the whole pack, or one of its K vectors.
  // With 16 vector registers (SSE2, AVX2) a pack of four spills; one vector at a time, link by
  // link, stays in registers while the K vectors' chains still overlap. With AVX-512's 32 the
  // whole pack measured faster (docs/simd_batch.md).
  struct WholePack {
    V& operator()(V& x) const { return x; }
    const V& operator()(const V& x) const { return x; }
  };
  struct OneVector {
    int j;
    B& operator()(V& x) const { return x.b[j]; }
    const B& operator()(const V& x) const { return x.b[j]; }
  };
  static constexpr bool kVectorByVector = kVector < 8;
  // f over the block's lanes, in arrays of one or two `OneVector`s where kVectorByVector (two:
  // their chains of dependences overlap), else over the whole pack (`WholePack`).
  template <class F>
  [[gnu::always_inline]] static void by_vector_pairs(F&& f) {
    if constexpr (kVectorByVector && K == 1) {  // One
      f(std::array<OneVector, 1>{OneVector{0}});
    } else if constexpr (kVectorByVector) {
      static_assert(K % 2 == 0);
      for (int j = 0; j < K; j += 2) f(std::array<OneVector, 2>{OneVector{j}, OneVector{j + 1}});
    } else {
      f(std::array<WholePack, 1>{});
    }
  }
  // Six entries at p as `lane` reads them, for sweep_law: p[r] of the pack, or of one vector.
  template <class P, class L>
  struct Six {
    P* p;
    L lane;
    [[gnu::always_inline]] decltype(auto) operator[](int r) const { return lane(p[r]); }
  };
  // Six entries written and never read.
  template <class T>
  struct Sink {
    T x;
    [[gnu::always_inline]] T& operator[](int) { return x; }
  };
  template <class P, class L>
  [[gnu::always_inline]] static Six<P, L> six(const L& lane, P* p) {
    return {p, lane};
  }
  template <class L>
  static auto dot6(const L& lane, const V* a, const V* b) {
    return sum6(lane(a[0]) * lane(b[0]), lane(a[1]) * lane(b[1]), lane(a[2]) * lane(b[2]),
                lane(a[3]) * lane(b[3]), lane(a[4]) * lane(b[4]), lane(a[5]) * lane(b[5]));
  }
  template <class T>  // V or B
  static void cross(const T* a, const T* b, T* out) {
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
  }
  static V select_zero(const M& m, const V& x) { return select(m, x, V(0.0)); }
  static M none() { return V(0.0) != V(0.0); }  // (xsimd 8's batch_bool(bool) reads past a bool)

  const Plan& p_;
  const Block& b_;
  const Layout& l_;
  V* const s_;
  const double* parameters_[K];  // per vector of the pack
  // The rows' forces of the step (df, lf, ff, vf) and of the one before, which a lane that stops
  // keeps: two rooms of the scratch that trade places each step, as a step writes every force
  // without reading it (copied instead, they cost 2 % of a step's instructions).
  struct Forces {
    int df, lf, ff, vf;
  };
  Forces forces_, old_forces_;
  // Where in the step a sweep runs (RowPhase).
  double h_ = 0.0, recip_h_ = 0.0, time_to_step_end_ = 0.0;
  double h_solve_ = 0.0;  // the step of one solve, for the rows' set-up
  bool velocity_iteration_ = false;
  M stopped_ = none();
  M rowless_ = none();   // lanes with no row at all: a sweep leaves their velocities alone
  M undriven_ = none();  // lanes with a limit or friction row: what a TGS velocity iteration solves
  M grounded_ = none();  // lanes whose environment's ground contacts run (Plan::contacts)
  M colliding_ = none();  // lanes whose environment's self contacts run (Plan::contacts)
  bool live_[kW] = {};   // per lane: its contact rows run this step (ground or self, not stopped)
  bool self_live_[kW] = {};  // per live lane: its self-contact rows run
  Stop contact_stop_[kW] = {};  // per live lane: its first non-finite contact force
  LaneContactPhase contact_phase_;  // the sweep's
  // The sweep's arrays (and the rows'), found once: at() finds them again after every store
  // through a pack (it may alias the plan).
  struct SweepArrays {
    V *dv, *subtree, *after, *later, *S, *U, *W, *G, *D_inv, *inverse_mass, *qd, *jimp, *entry,
        *chain_pS, *chain_pi, *chain_base, *Lambda, *zero, *given, *row_bias, *row;
    double* flags;
    const LinkConstants* links;
  };
  const SweepArrays sa_{s_ + l_.dv,       s_ + l_.subtree,    s_ + l_.after,    s_ + l_.later,
                        s_ + l_.S,        s_ + l_.U,          s_ + l_.W,        s_ + l_.G,
                        s_ + l_.D_inv,    s_ + l_.inverse_mass, s_ + l_.qd,     s_ + l_.jimp,
                        s_ + l_.entry,    s_ + l_.chain_pS,   s_ + l_.chain_pi, s_ + l_.chain_base,
                        s_ + l_.Lambda,   s_ + l_.zero,       s_ + l_.given,    s_ + l_.row_bias,
                        s_ + l_.row,      reinterpret_cast<double*>(s_ + l_.flags),
                        p_.links};
};

template <class A, int K>
void LaneStep<A, K>::scatter(V x, double* rows, int stride, int k) const {
  alignas(64) double t[kW];
  x.store_aligned(t);
  for (int l = 0; l < b_.valid; ++l) rows[row_of(b_.env0 + l) * stride + k] = t[l];
}

template <class A, int K>
void LaneStep<A, K>::gather_rows(const double* rows, int stride, int n, V* out) const {
  double* o = reinterpret_cast<double*>(out);  // pack k's lane l at o[k kW + l]
  for (int l = 0; l < kW; ++l) {
    const double* row = rows + row_of(env_of_lane(l)) * stride;
    for (int k = 0; k < n; ++k) o[k * kW + l] = row[k];
  }
}

template <class A, int K>
void LaneStep<A, K>::scatter_rows(const V* in, double* rows, int stride, int n) const {
  const double* x = reinterpret_cast<const double*>(in);
  for (int l = 0; l < b_.valid; ++l) {
    double* row = rows + row_of(b_.env0 + l) * stride;
    for (int k = 0; k < n; ++k) row[k] = x[k * kW + l];
  }
}

// sin and cos from + - * / only, the kinematics' own (sincos_law, docs/math/sincos.md): within
// 2 ulp of glibc's for |x| <= 1e5.
template <class A, int K>
void LaneStep<A, K>::sincos(V x, V& s, V& c) {
  sincos_law::sincos(x, s, c);
}

template <class A, int K>
void LaneStep<A, K>::sym_times(const V* m, const V* x, V* y) {
  // One vector of the pack at a time: its six entries of x stay in registers for all six rows,
  // where a whole pack of four would be reloaded for each (6 % fewer instructions a step).
  for (int j = 0; j < K; ++j) {
    B xj[6], yj[6];
    take6(x, j, xj);
    sym_times(m, j, xj, yj);
    for (int r = 0; r < 6; ++r) y[r].b[j] = yj[r];
  }
}

// Pass 1 of the step's ABA, root to leaves, link by link: pose, S_i, rigid-body inertia,
// velocity, c_i and bias force, one link's results read by the next while still in cache.
template <class A, int K>
void LaneStep<A, K>::kinematics_and_bias() {
  for (int i = 0; i < p_.num_links; ++i) {
    link_pose(i);
    link_velocity_and_bias(i);
  }
}

// Link i's pose (world axes; position relative to the root link's origin, frame 0's origin) and
// S_i, its parent's being done; without kStart the pose alone, kept apart (now_R, now_pos) for
// compat physx's tracking of a sub-step.
template <class A, int K>
template <bool kStart>
[[gnu::always_inline]] inline void LaneStep<A, K>::link_pose(int i) {
  const LinkConstants& k = p_.links[i];
  const int R_base = kStart ? l_.R : l_.now_R, pos_base = kStart ? l_.pos : l_.now_pos;
  V* R = at(R_base + 9 * i);
  V* pos = at(pos_base + 3 * i);
  if (k.type == 3) {  // frame 0's origin is the root's own
    for (int r = 0; r < 3; ++r) pos[r] = V(0.0);
    root_pose<kStart>(R);
    return;
  }
  // The joint frame's axes R_parent E^T: the parent's own rotation, read in place, where the
  // joint frame does not rotate (a copy of nine packs cost a fifth of this pass with AVX2).
  V frame[9];
  const V* P = frame;
  if (k.parent < 0) {
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) frame[3 * r + c] = V(k.E[3 * c + r]);
    for (int r = 0; r < 3; ++r) pos[r] = V(0.0);
  } else {
    const V* Rp = at(R_base + 9 * k.parent);
    const V* pp = at(pos_base + 3 * k.parent);
    // p = p_p + R_p r_T (spatial/joint_transform_law.hpp, as kinematics.cpp).
    const V r_T[3] = {V(k.r[0]), V(k.r[1]), V(k.r[2])};
    joint_transform_law::link_position(pp, joint_transform_law::rows(Rp), r_T, pos);
    if (k.tree_rotation_identity) {
      P = Rp;
    } else {
      joint_transform_law::joint_frame(joint_transform_law::rows(Rp), Broadcast{k.E},
                                       joint_transform_law::rows(frame));
    }
  }
  if (k.type == 4) {
    ball_pose(i, P, R, pos, kStart);
    return;
  }
  // The joint's unit axis as a constant where it is one (x, y or z): the laws' entries then sit at
  // fixed places (worked out per entry at run time, they cost a third of this pass with AVX2).
  V aw[3];  // the joint axis in world axes
  with_unit_axis(k.unit_axis, [&](auto axis) {
    joint_transform_law::joint_axis(joint_transform_law::rows(P), axis, V(k.axis_sign), k.axis, aw);
    const V x = k.type != 0 ? at(l_.q)[k.q_index] : V(0.0);
    if (k.type == 1) {
      V s, c;
      sincos(V(k.axis_sign) * x, s, c);
      // R = P R(a, angle) (spatial/joint_transform_law.hpp, as kinematics.cpp).
      if (axis >= 0) {
        joint_transform_law::turn_columns(joint_transform_law::rows(P), axis, s, c,
                                          joint_transform_law::rows(R));
      } else {
        V J[9];
        joint_transform_law::axis_rotation(V(k.axis[0]), V(k.axis[1]), V(k.axis[2]), s, c,
                                           joint_transform_law::rows(J));
        joint_transform_law::compose(joint_transform_law::rows(P), joint_transform_law::rows(J),
                                     joint_transform_law::rows(R));
      }
    } else {
      for (int e = 0; e < 9; ++e) R[e] = P[e];
      if (k.type == 2 && k.parent >= 0) joint_transform_law::slide(aw, x, pos);
    }
  });
  if (k.type == 0 || !kStart) return;
  // S_i = [a_w; pos x a_w] or [0; a_w] (joint_transform_law, as aba.cpp).
  joint_transform_law::one_dof_subspace(aw, pos, k.type == 1, at(l_.S + 6 * i));
}

// Link i's rigid-body inertia in frame 0, velocity, velocity-product acceleration c_i and bias
// force v x* I v (link_motion_law, as aba.cpp); one vector of the pack at a time, so that its
// centre of mass and velocity stay in registers (sym_times).
template <class A, int K>
[[gnu::always_inline]] inline void LaneStep<A, K>::link_velocity_and_bias(int i) {
  const LinkConstants& k = p_.links[i];
  const V* Rv = at(l_.R + 9 * i);
  const V* posv = at(l_.pos + 3 * i);
  V* Iv = at(l_.IA + 21 * i);
  V* vv = at(l_.vel + 6 * i);
  V* cv = at(l_.c + 6 * i);
  V* pAv = at(l_.pA + 6 * i);
  const V* vp = k.parent >= 0 ? at(l_.vel + 6 * k.parent) : nullptr;
  const V* Sv = one_dof(k) ? at(l_.S + 6 * i) : nullptr;
  const V* qdv = k.type != 0 ? &at(l_.qd)[k.v_index] : nullptr;
  const V* R0 = k.type == 3 ? at(l_.root_R) : nullptr;  // a floating root's S: diag(R0, R0)
  for (int j = 0; j < K; ++j) {
    B pos[3], com[3];
    for (int r = 0; r < 3; ++r) pos[r] = posv[r].b[j], com[r] = link_parameter(i, com_x + r, j);
    const B m = link_parameter(i, mass, j);
    // The body's inertia in frame 0 (link_motion_law, eq. P1-1, P1-2); A's entries at kSym. R
    // read where it is stored, and B and C stored before A is formed, so that R's entries are
    // read again there (kept from before, they spilled).
    const VectorRows Rm{Rv, j};
    B cg[3], mc[3];
    link_motion_law::centre_of_mass(Rm, pos, com, m, cg, mc);
    if (p_.any_transmission_friction || p_.any_cfm)  // the poses' room goes to the response
      for (int r = 0; r < 3; ++r) at(l_.cg + 3 * i)[r].b[j] = cg[r];
    // B = [mc]x, C = m 1.
    const B zero(0.0);
    Iv[6].b[j] = zero, Iv[7].b[j] = -mc[2], Iv[8].b[j] = mc[1];
    Iv[9].b[j] = mc[2], Iv[10].b[j] = zero, Iv[11].b[j] = -mc[0];
    Iv[12].b[j] = -mc[1], Iv[13].b[j] = mc[0], Iv[14].b[j] = zero;
    Iv[15].b[j] = m, Iv[16].b[j] = m, Iv[17].b[j] = m;
    Iv[18].b[j] = zero, Iv[19].b[j] = zero, Iv[20].b[j] = zero;
    B RI[9];  // R Ic
    const auto RIm = joint_transform_law::rows(RI);
    const B xx = link_parameter(i, inertia_xx, j), yy = link_parameter(i, inertia_yy, j),
            zz = link_parameter(i, inertia_zz, j);
    if (k.diagonal_inertia) {
      link_motion_law::rotate_principal(Rm, xx, yy, zz, RIm);
    } else {
      const B xy = link_parameter(i, inertia_xy, j), xz = link_parameter(i, inertia_xz, j),
              yz = link_parameter(i, inertia_yz, j);
      B Ic[9] = {xx, xy, xz, xy, yy, yz, xz, yz, zz};
      link_motion_law::rotate_full(Rm, joint_transform_law::rows(Ic), RIm);
    }
    B Ia[6];
    link_motion_law::rotational_block(Rm, RIm, cg, mc, Ia);
    for (int e = 0; e < 6; ++e) Iv[e].b[j] = Ia[e];

    B J[6] = {zero, zero, zero, zero, zero, zero};  // S qd
    if (Sv) {
      const B qd = qdv->b[j];
      for (int r = 0; r < 6; ++r) J[r] = qd * Sv[r].b[j];
    } else if (k.type == 4) {  // S qd, S = ball_S's three columns (multi_dof_law, eq. AP14)
      const V* S3 = at(l_.ball_S + 18 * i);
      B S3j[18], qd[3];
      for (int e = 0; e < 18; ++e) S3j[e] = S3[e].b[j];
      for (int r = 0; r < 3; ++r) qd[r] = qdv[r].b[j];
      multi_dof_law::joint_motion(multi_dof_law::DenseSubspace<B, 3>{S3j}, qd, J);
    } else if (R0) {
      B R0j[9], qd[6];
      for (int e = 0; e < 9; ++e) R0j[e] = R0[e].b[j];
      for (int r = 0; r < 6; ++r) qd[r] = qdv[r].b[j];
      multi_dof_law::joint_motion(multi_dof_law::RotationPair<B>{R0j}, qd, J);
    }
    // v, c and the bias force (link_motion_law, eq. P1-3 to P1-5).
    B v[6], c[6], pA[6];
    if (vp) {
      B vpj[6];
      take6(vp, j, vpj);
      link_motion_law::velocity(vpj, J, v);
    } else {
      link_motion_law::velocity<B>(nullptr, J, v);
    }
    for (int r = 0; r < 6; ++r) vv[r].b[j] = v[r];
    link_motion_law::velocity_product(v, J, c);
    for (int r = 0; r < 6; ++r) cv[r].b[j] = c[r];
    link_motion_law::bias_force(v, six(OneVector{j}, static_cast<const V*>(Iv)), mc, m, pA);
    for (int r = 0; r < 6; ++r) pAv[r].b[j] = pA[r];
    if (p_.any_link_damping) {  // an external force: the bias less it
      B R[9], F[6];
      for (int e = 0; e < 9; ++e) R[e] = Rv[e].b[j];
      link_damping(i, j, R, RI, cg, m, v, F);
      for (int r = 0; r < 6; ++r) pAv[r].b[j] = pAv[r].b[j] - F[r];
      if (p_.physx_floating)  // part of the momentum targets (physx_start)
        for (int r = 0; r < 6; ++r) at(l_.link_force + 6 * i)[r].b[j] = F[r];
    }
  }
}

// ABA pass 2: articulated inertias and bias forces, leaves to root.
template <class A, int K>
void LaneStep<A, K>::articulated_pass() {
  for (int i = p_.num_links - 1; i >= 0; --i) {
    const LinkConstants& k = p_.links[i];
    const V* IA = at(l_.IA + 21 * i);
    const V* pA = at(l_.pA + 6 * i);
    if (k.type == 3) {
      root_articulated();
      continue;
    }
    if (k.type == 4) {
      ball_articulated(i);
      continue;
    }
    if (k.type == 0) {
      if (k.parent < 0) continue;
      V* IAp = at(l_.IA + 21 * k.parent);
      V* pAp = at(l_.pA + 6 * k.parent);
      for (int e = 0; e < 21; ++e) IAp[e] = IAp[e] + IA[e];
      for (int r = 0; r < 6; ++r) pAp[r] = pAp[r] + pA[r];
      continue;
    }
    const V* S = at(l_.S + 6 * i);
    V* U = at(l_.U + 6 * i);
    const V* c = at(l_.c + 6 * i);
    const V armature = dof_parameter(k.v_index, simd::armature);
    V* pAp = k.parent >= 0 ? at(l_.pA + 6 * k.parent) : nullptr;
    V* IAp = k.parent >= 0 ? at(l_.IA + 21 * k.parent) : nullptr;
    // One vector of the pack at a time, so that U, D^-1 and the like stay in registers;
    // articulated_law (docs/math/unit_response.md, eq. AP1-AP4) as Simulation's.
    for (int j = 0; j < K; ++j) {
      const SymmetricVector IAj{IA, j};
      B Sj[6], Uj[6], pAj[6];
      take6(S, j, Sj);
      const B D_inv = articulated_law::joint_inertia(IAj, Sj, armature.b[j], Uj);
      for (int r = 0; r < 6; ++r) U[r].b[j] = Uj[r];
      at(l_.D_inv)[i].b[j] = D_inv;
      take6(pA, j, pAj);
      const B u = articulated_law::joint_force(at(l_.tau)[k.v_index].b[j], Sj, pAj);
      at(l_.u)[k.v_index].b[j] = u;
      if (!pAp) continue;
      // U and pA read again: after the stores above, kept from before they spilled.
      B cj[6], pa[6];
      take6(U, j, Uj);
      take6(pA, j, pAj);
      take6(c, j, cj);
      take6(pAp, j, pa);
      articulated_law::project_bias(IAj, pAj, cj, Uj, D_inv, u, pa);
      const SymmetricSum ia{IAp, j};
      articulated_law::project_inertia(IAj, Uj, D_inv, ia);
      for (int r = 0; r < 6; ++r) pAp[r].b[j] = pa[r];
    }
  }
}

// ABA pass 3, the response and the rows, in one pass root to tip (step.cpp's
// accelerations_and_response and setup_rows): each reads what the one before wrote for the link.
template <class A, int K>
void LaneStep<A, K>::forward_pass() {
  const V g[6] = {V(0.0),
                  V(0.0),
                  V(0.0),
                  -parameter(gravity_entry(0)),
                  -parameter(gravity_entry(1)),
                  -parameter(gravity_entry(2))};
  const V dt(p_.dt);
  for (int i = 0; i < p_.num_links; ++i) {
    link_acceleration(i, g, dt);
    const bool one = one_dof(p_.links[i]);
    if (p_.any_transmission_friction && (one || p_.links[i].type == 4)) transmitted_force(i);
    link_response(i);
    if (p_.any_cfm) link_cfm(i);
    if (one) setup_link_rows(i);
    else if (p_.links[i].type == 4) ball_rows(i);
  }
}

// ABA pass 3 at link i: its acceleration (gravity as an upward acceleration of the world) and
// the free velocity qd += dt qdd.
template <class A, int K>
[[gnu::always_inline]] inline void LaneStep<A, K>::link_acceleration(int i, const V* g,
                                                                     const V& dt) {
  const V* zero = at(l_.zero);
  const LinkConstants& k = p_.links[i];
  const V* ap = k.parent >= 0 ? at(l_.acc + 6 * k.parent) : g;
  const V* c = at(l_.c + 6 * i);
  V* a = at(l_.acc + 6 * i);
  if (!one_dof(k)) {
    V acc[6];  // read whole before it is stored (a might overlap ap or c)
    for (int r = 0; r < 6; ++r) acc[r] = ap[r] + (k.type != 0 ? c[r] : zero[r]);
    for (int r = 0; r < 6; ++r) a[r] = acc[r];
    if (k.type == 3) root_acceleration(a, dt);
    if (k.type == 4) ball_acceleration(i, a, dt);
    return;
  }
  // articulated_law (docs/math/unit_response.md, eq. AP5-AP6) as Simulation's, one vector of the
  // pack at a time: a whole pack's six entries spill (AVX2: 16 registers).
  const V* U = at(l_.U + 6 * i);
  const V* S = at(l_.S + 6 * i);
  const V& D_inv = at(l_.D_inv)[i];
  const V& u = at(l_.u)[k.v_index];
  V& qd = at(l_.qd)[k.v_index];
  for (int j = 0; j < K; ++j) {
    B acc[6], Uj[6], Sj[6];  // acc read whole before it is stored (a might overlap ap or c)
    for (int r = 0; r < 6; ++r) acc[r] = ap[r].b[j] + c[r].b[j];
    take6(U, j, Uj);
    take6(S, j, Sj);
    const B qdd = articulated_law::joint_acceleration(Uj, D_inv.b[j], u.b[j], acc);
    articulated_law::add_joint_motion(qdd, Sj, acc);
    for (int r = 0; r < 6; ++r) a[r].b[j] = acc[r];
    qd.b[j] = qd.b[j] + dt.b[j] * qdd;
  }
}

// PhysX's link damping and link velocity limits on link i, vector j: link_law::damping_force
// (sim/link_laws.hpp, joint_constraints.md J10), as link_damping.cpp, from the start-of-step
// velocity v (frame 0), a force on the free velocity as gravity's.
template <class A, int K>
[[gnu::always_inline]] inline void LaneStep<A, K>::link_damping(int i, int j, const B* R,
                                                                const B* RI, const B* cg,
                                                                const B& m, const B* v,
                                                                B* F) const {
  B v_com[3], local[3], g[3];
  // v_c and omega in the link's axes (link_motion_law, eq. P1-6, P1-7), as link_damping.cpp.
  link_motion_law::point_velocity(v, cg, v_com);
  link_motion_law::in_link_axes(joint_transform_law::rows(R), v, local);
  for (int r = 0; r < 3; ++r) g[r] = parameter(gravity_entry(r), j);
  const link_law::Damping<B> d{link_parameter(i, link_linear_damping, j),
                               link_parameter(i, link_angular_damping, j),
                               link_parameter(i, link_max_linear_velocity, j),
                               link_parameter(i, link_max_angular_velocity, j)};
  link_law::damping_force(d, v, local, v_com, RI, cg, m, g, B(p_.dt), F);
}

// PhysX's constraint force mixing of link i: link_law::cfm (sim/link_laws.hpp,
// joint_constraints.md J8), as link_cfm.cpp; 0 for the fixed root.
template <class A, int K>
void LaneStep<A, K>::link_cfm(int i) {
  V& out = at(l_.cfm)[i];
  if (p_.links[i].parent < 0 && p_.links[i].type != 3) {  // the fixed root
    out = V(0.0);
    return;
  }
  out = link_law::cfm(at(l_.Lambda + 21 * i), at(l_.cg + 3 * i),
                      link_parameter_pack(i, link_cfm_scale));
}

// The bound of link i's transmitted-force friction row (joint_constraints.md J6): |torque| +
// |force| its joint transmits, IA_i a_i + pA_i, by link_law::transmitted_force_magnitude
// (sim/link_laws.hpp, J9), as transmitted_force.cpp. Read before the response takes IA_i's room.
template <class A, int K>
void LaneStep<A, K>::transmitted_force(int i) {
  const V magnitude = link_law::transmitted_force_magnitude(
      at(l_.IA + 21 * i), at(l_.acc + 6 * i), at(l_.pA + 6 * i), at(l_.cg + 3 * i));
  const LinkConstants& k = p_.links[i];
  for (int d = k.v_index; d < k.v_index + (k.type == 4 ? 3 : 1); ++d)
    row(d)[Layout::tf_bound] =
        row_setup::transmission_friction_bound(dof_parameter(d, friction_coefficient), h_solve_,
                                               magnitude);
}

// Link i's whole-articulation response Lambda_i, W_i = Lambda_parent U_i, G_i and (M^-1)_ii
// (inverse_mass_diagonal.cpp), its parent's being done.
template <class A, int K>
[[gnu::always_inline]] inline void LaneStep<A, K>::link_response(int i) {
  const LinkConstants& k = p_.links[i];
  const V* T = k.parent >= 0 ? at(l_.Lambda + 21 * k.parent) : at(l_.zero);
  V* L = at(l_.Lambda + 21 * i);
  if (k.type == 0) {
    for (int e = 0; e < 21; ++e) L[e] = T[e];
    return;
  }
  if (k.type == 3) {
    root_response();
    return;
  }
  if (k.type == 4) {
    ball_response(i);
    return;
  }
  const V* U = at(l_.U + 6 * i);
  const V* S = at(l_.S + 6 * i);
  V* W = at(l_.W + 6 * i);
  V* G = at(l_.G + 6 * i);
  // One vector of the pack at a time (articulated_pass), by response_law
  // (docs/math/unit_response.md, eq. R1-R5).
  for (int j = 0; j < K; ++j) {
    B Uj[6], Wj[6], Gj[6];
    take6(U, j, Uj);
    const B D_inv = at(l_.D_inv)[i].b[j];
    const SymmetricAssign Lj{L, j};
    const B r = response_law::response(SymmetricVector{T, j}, six(OneVector{j}, S), Uj, D_inv, Wj,
                                       Gj, Lj);
    for (int e = 0; e < 6; ++e) W[e].b[j] = Wj[e];
    for (int e = 0; e < 6; ++e) G[e].b[j] = Gj[e];
    at(l_.inverse_mass)[i].b[j] = r;
    if (k.parent_one_dof) {  // the sweep's chain constants (implicit_drives.md, eq. GS1-GS3)
      const int p = k.parent;
      B Sp[6], Wp[6];
      take6(at(l_.S + 6 * p), j, Sp);
      take6(at(l_.W + 6 * p), j, Wp);
      const response_law::Chain<B> c =
          response_law::chain(Uj, D_inv, Sp, Wp, at(l_.D_inv)[p].b[j], at(l_.inverse_mass)[p].b[j]);
      at(l_.chain_pS)[i].b[j] = c.parent_S;
      at(l_.chain_pi)[i].b[j] = c.base_per_parent_impulse;
    }
  }
}

// What of every dof's rows depends only on the lanes' parameters and the (sub)step h: set once a
// call, since parameters change only between calls.
template <class A, int K>
void LaneStep<A, K>::setup_row_constants(double h_step) {
  h_solve_ = h_step;
  M rows_any = none();
  undriven_ = none();
  for (int i = 0; i < p_.num_links; ++i) {
    const LinkConstants& k = p_.links[i];
    if (k.type == 0) continue;
    if (k.type == 3) {  // no rows: the accumulators the outputs read stay 0
      for (int d = k.v_index; d < k.v_index + 6; ++d) {
        V* rw = row(d);
        for (int f = 0; f < Layout::kRowFields; ++f) rw[f] = V(0.0);
        rw[Layout::vmax] = dof_parameter(d, max_velocity);
        double* has = any_row(d);
        for (int f = 0; f < 16; ++f) has[f] = 0.0;
        has[3] = any(rw[Layout::vmax] < V(__builtin_inf())) ? 1.0 : 0.0;
      }
      continue;
    }
    for (int d = k.v_index; d < k.v_index + (k.type == 4 ? 3 : 1); ++d) {
    V* rw = row(d);
    const M drive = dof_parameter(d, has_drive) != V(0.0);
    // An implicit actuator's row is solved as the drive's (implicit_actuators.md, I4).
    const M actuated = dof_parameter(d, implicit_actuator) != V(0.0);
    const M driven = drive | actuated;
    const V lower_limit = dof_parameter(d, lower), upper_limit = dof_parameter(d, upper);
    const V inf(__builtin_inf());
    const M limited = (lower_limit > -inf) | (upper_limit < inf);
    rw[Layout::has_limit] = select_zero(limited, V(1.0));
    const V fs = dof_parameter(d, static_friction), fd = dof_parameter(d, dynamic_friction),
            fv = dof_parameter(d, viscous_friction);
    // JointFriction::active(): any of the three nonzero.
    const M rubbing = !((fs == V(0.0)) & (fd == V(0.0)) & (fv == V(0.0)));
    rw[Layout::has_friction] = select_zero(rubbing, V(1.0));
    LaneDof dof{*this, i, d, rw};
    row_setup::constants<V>(dof, p_.dt);
    rw[Layout::driven] = select_zero(driven, V(1.0));
    rw[Layout::vmax] = dof_parameter(d, max_velocity);
    const M speed_limited = rw[Layout::vmax] < inf;
    // Whether some lane has a friction, limit or velocity limit row, whether every lane has a
    // drive: a sweep skips what no lane has and selects nothing where every lane has it.
    double* has = any_row(d);
    has[0] = any(rubbing) ? 1.0 : 0.0;
    has[1] = any(limited) ? 1.0 : 0.0;
    has[2] = all(driven) ? 1.0 : 0.0;
    has[3] = any(speed_limited) ? 1.0 : 0.0;
    has[4] = any(dof_parameter(d, wrapped) != V(0.0)) ? 1.0 : 0.0;
    // The envelope is the drive's: an implicit actuator's row has none.
    const M enveloped = drive & (V(0.0) < dof_parameter(d, envelope_max_effort));
    rw[Layout::has_envelope] = select_zero(enveloped, V(1.0));
    has[5] = any(enveloped) ? 1.0 : 0.0;
    // Transmitted-force friction only where no static or viscous friction is set (like PhysX).
    const M transmitting = (V(0.0) < dof_parameter(d, friction_coefficient)) & (fs == V(0.0)) &
                           (fv == V(0.0));
    rw[Layout::has_tf] = select_zero(transmitting, V(1.0));
    has[6] = any(transmitting) ? 1.0 : 0.0;
    const V kind = dof_parameter(d, actuator_kind);
    has[7] = (any(actuated) ? kActuator : 0.0) +
             (any(actuated & (kind == V(1.0))) ? kMotorClip : 0.0) +
             (any(actuated & (kind == V(2.0))) ? kTableClip : 0.0);
    undriven_ = undriven_ | transmitting;
    rows_any = rows_any | transmitting;
    // The row kinds (row_kinds.hpp): which lanes have each (LaneEngine::pack_joints decided).
    double kinds = 0.0;
    for (int e = 0; e < RowKinds::size; ++e) {
      const M on = dof_parameter(d, row_kind_on + e) != V(0.0);
      rw[Layout::kind_masks + e] = select_zero(on, V(1.0));
      if (any(on)) kinds += static_cast<double>(1 << e);
      undriven_ = undriven_ | on;  // as the scalar step's any_undriven_rows
      rows_any = rows_any | on;
    }
    has[8] = kinds;
    undriven_ = undriven_ | limited | rubbing | speed_limited;
    rows_any = rows_any | limited | rubbing | driven | speed_limited;
    }
  }
  rowless_ = !rows_any;
}

// The rows of link i's dof for the step (step.cpp's setup_rows, drive.hpp's setup_drive_row):
// what depends on the configuration, and the accumulators.
template <class A, int K>
[[gnu::always_inline]] inline void LaneStep<A, K>::setup_link_rows(int i) {
  const LinkConstants& k = p_.links[i];
  const V x0 = at(l_.q)[k.q_index];
  setup_dof_row(i, k.v_index, at(l_.inverse_mass)[i], x0, x0);
}

// Dof d of link i as row_setup (constraint/row_setup.hpp) reads and writes it: the lanes'
// parameters and its packed row.
template <class A, int K>
struct LaneStep<A, K>::LaneDof {
  LaneStep& s;
  int i, d;
  V* rw;
  V parameter(DofParameter f) const { return s.dof_parameter(d, f); }
  static bool any_of(const M& mask) { return simd::any(mask); }
  // Every dof's drive row runs; undriven lanes keep their impulse (LaneRows, Layout::driven).
  static bool any_driven() { return true; }
  M acceleration_drive() const { return parameter(acceleration) != V(0.0); }
  DriveTermsOf<V> drive_terms() const {
    return {parameter(stiffness),       parameter(damping),   parameter(target_position),
            parameter(target_velocity), parameter(max_force), parameter(max_impulse)};
  }
  bool any_actuated() const { return s.any_row(d)[7] != 0.0; }
  M actuated() const { return parameter(implicit_actuator) != V(0.0); }
  ActuatorTermsOf<V> actuator_terms() const {
    return {parameter(actuator_stiffness), parameter(actuator_damping),
            parameter(actuator_effort_limit), parameter(command_position),
            parameter(command_velocity), parameter(command_effort)};
  }
  bool any_cfm() const { return s.p_.any_cfm; }
  V cfm_child() const { return s.s_[s.l_.cfm + i]; }
  V cfm_parent() const { return s.s_[s.l_.cfm + s.p_.links[i].parent]; }
  V applied_force() const { return s.s_[s.l_.tau + d]; }
  V lower_limit() const { return parameter(lower); }
  V upper_limit() const { return parameter(upper); }
  V static_effort() const { return parameter(static_friction); }
  V dynamic_effort() const { return parameter(dynamic_friction); }
  V viscous() const { return parameter(viscous_friction); }

  void set_drive(const DriveRowOf<V>& row) const {
    rw[Layout::tvb] = row.target_vel_plus_initial_bias;
    rw[Layout::velm] = row.vel_multiplier;
    rw[Layout::impm] = row.impulse_multiplier;
    rw[Layout::biasc] = row.bias_coefficient;
    rw[Layout::tpb] = row.target_pos_bias;
    rw[Layout::maxi] = row.max_impulse;
  }
  V& response() const { return rw[Layout::response]; }
  V& recip() const { return rw[Layout::recip]; }
  V& external() const { return rw[Layout::external]; }
  V& actuator_x0() const { return rw[Layout::x_start]; }
  V& error_low() const { return rw[Layout::err_low]; }
  V& error_high() const { return rw[Layout::err_high]; }
  V& friction_static() const { return rw[Layout::fstat]; }
  V& friction_dynamic() const { return rw[Layout::fdyn]; }
  V& friction_viscous() const { return rw[Layout::fvisc]; }
  V& drive_impulse() const { return rw[Layout::dimp]; }
  V& tf_impulse() const { return rw[Layout::tf_imp]; }
  V& tf_applied() const { return rw[Layout::tf_applied]; }
  V& friction_impulse() const { return rw[Layout::fimp]; }
  V& low() const { return rw[Layout::low]; }
  V& high() const { return rw[Layout::high]; }
  V& velocity_limit() const { return rw[Layout::vlimp]; }
};

// Dof d of link i: unit response r, position x0 (a spherical axis's from its quaternion), and
// x0_drive, the position its drive's error is taken from (target - error for a spherical axis).
// The TGS position change is zeroed here too (the scalar step keeps it outside its rows).
template <class A, int K>
[[gnu::always_inline]] inline void LaneStep<A, K>::setup_dof_row(int i, int d, const V& r,
                                                                 const V& x0, const V& x0_drive) {
  const LaneDof dof{*this, i, d, row(d)};
  row_setup::setup(dof, r, x0, x0_drive, {h_solve_, p_.dt, p_.tgs});
  dof.rw[Layout::delta_x] = V(0.0);
  if (const double kinds = any_row(d)[8]; kinds != 0.0) {
    // Each kind some lane has, on every lane (the solve keeps the others' bits: row_kind.hpp).
    const RowInputs<V> in{r, row_setup::response_with_cfm(dof, r), x0, h_solve_, p_.dt, p_.tgs};
    RowKinds::for_each([&]<class E>(E, int field, int slot) {
      using Kind = typename E::Kind;
      if (!has_bit(kinds, static_cast<double>(1 << E::index))) return;
      std::array<V, Kind::fields.size()> values;
      for (size_t j = 0; j < values.size(); ++j)
        values[j] = dof_parameter(d, row_kind_fields + field + static_cast<int>(j));
      V* row = dof.rw + Layout::kind_slots + slot;
      Kind::setup(row, values, in);
    });
  }
}

// An implicit actuator's clip that depends on the state (actuator_row.hpp, dof_rows.cpp): on
// dc_motor lanes the torque-speed line's (eq. I8-I11), on remotized_pd lanes the table's at the
// iterate's end-of-(sub-)step position (eq. I13), read lane by lane out of line; lambda elsewhere.
template <class A, int K>
auto LaneStep<A, K>::clip_actuator(int d, const V* rw, const V& lambda, const V& accumulated,
                                   const V& v, const V& r, const V& dx) -> V {
  const M actuated = dof_parameter(d, implicit_actuator) != V(0.0);
  const V kind = dof_parameter(d, actuator_kind);
  const V bound = dof_parameter(d, actuator_effort_limit) * V(p_.dt);
  V out = lambda;
  if (has_bit(any_row(d)[7], kMotorClip)) {
    const V clipped = actuator_row::clip_dc_motor(lambda, accumulated, v, r, bound,
                                                  dof_parameter(d, actuator_saturation),
                                                  dof_parameter(d, actuator_velocity_limit), p_.dt);
    out = select(actuated & (kind == V(1.0)), clipped, out);
  }
  if (has_bit(any_row(d)[7], kTableClip)) {
    const M table = actuated & (kind == V(2.0));
    alignas(64) double position[kW], on[kW], limit[kW];
    (rw[Layout::x_start] + dx + V(h_) * v).store_aligned(position);
    select(table, V(1.0), V(0.0)).store_aligned(on);
    for (int l = 0; l < kW; ++l)
      limit[l] = on[l] != 0.0 ? table_effort_limit(*b_.tables, b_.env0 + l, d, position[l]) : 0.0;
    out = select(table, actuator_row::clip_to_table(lambda, bound, V::load_aligned(limit), p_.dt),
                 out);
  }
  return out;
}

// Dof d's rows in the packed layout, as row_sequence::solve reads them, on the lanes lane picks:
// the whole pack, or one vector for a lone drive (kLoneDrive: the sweep checked that no lane has
// another row, an envelope or a clip).
template <class A, int K>
template <class L, bool kLoneDrive>
struct LaneStep<A, K>::LaneRows {
  using Row = row_sequence::Row;
  LaneStep& s;
  int d;
  V* rw;
  L lane;
  double* flags = s.any_row(d);  // found once (a store through a pack may alias the plan)
  using T = std::remove_cvref_t<decltype(std::declval<L>()(std::declval<V&>()))>;
  auto& f(int field) const { return lane(rw[field]); }
  bool any(Row k) const {
    if constexpr (kLoneDrive) return k == Row::drive;
    const double* has = flags;
    switch (k) {
      case Row::transmission_friction: return has[6] != 0.0;
      case Row::drive: return true;  // every dof's row runs; undriven lanes keep theirs (driven)
      case Row::friction: return has[0] != 0.0;
      case Row::limit: return has[1] != 0.0;
      case Row::velocity_limit: return has[3] != 0.0;
    }
    return false;
  }
  bool all(Row k) const {
    return (k == Row::drive && flags[2] != 0.0) ||
           (k == Row::friction && flags[kAllFriction] != 0.0);
  }
  template <class Mask>
  static bool any_of(const Mask& m) {
    if constexpr (std::is_same_v<T, V>) return simd::any(m);
    else return lane_any(m);
  }
  auto has(Row k) const {
    const int field = k == Row::transmission_friction ? Layout::has_tf
                      : k == Row::drive               ? Layout::driven
                      : k == Row::friction            ? Layout::has_friction
                                                      : Layout::has_limit;
    return f(field) != T(0.0);
  }
  T response() const { return f(Layout::response); }
  T recip() const { return f(Layout::recip); }
  T& tf_impulse() const { return f(Layout::tf_imp); }
  T& tf_applied() const { return f(Layout::tf_applied); }
  T tf_bound() const { return f(Layout::tf_bound); }
  DriveRowOf<T> drive() const {
    return {f(Layout::tvb), f(Layout::velm), f(Layout::impm),
            f(Layout::biasc), f(Layout::tpb), f(Layout::maxi)};
  }
  T& drive_impulse() const { return f(Layout::dimp); }
  T clip_drive(T next, const T& accumulated, const T& v, const T& dx) const {
    if constexpr (std::is_same_v<T, V>) {
      const double* has = flags;
      if (has[5] != 0.0) {
        const row_law::EnvelopeOf<V> e{s.dof_parameter(d, envelope_max_effort),
                                       s.dof_parameter(d, envelope_max_velocity),
                                       s.dof_parameter(d, envelope_gradient),
                                       s.dof_parameter(d, envelope_resistance)};
        next = select(rw[Layout::has_envelope] != V(0.0),
                      row_law::envelope(e, next, accumulated, v, rw[Layout::response],
                                        rw[Layout::external], s.p_.dt),
                      next);
      }
      if (has_bit(has[7], kMotorClip) || has_bit(has[7], kTableClip))
        next = s.clip_actuator(d, rw, next, accumulated, v, rw[Layout::response], dx);
    }
    return next;
  }
  T& friction_impulse() const { return f(Layout::fimp); }
  T friction_static() const { return f(Layout::fstat); }
  T friction_dynamic() const { return f(Layout::fdyn); }
  T friction_viscous() const { return f(Layout::fvisc); }
  T& low() const { return f(Layout::low); }
  T& high() const { return f(Layout::high); }
  T error_low() const { return f(Layout::err_low); }
  T error_high() const { return f(Layout::err_high); }
  T max_velocity() const { return f(Layout::vmax); }
  T& velocity_limit() const { return f(Layout::vlimp); }
  // row_law::limit_may_act for some lane, its terms in v alone where no lane's limit is held.
  bool limit_may_act(const T& low, const T& high, const T& v, const T& dx,
                     const row_law::LimitPhase& phase) const {
    double& held = flags[kLimitHeld];
    const bool act =
        held != 0.0
            ? any_of(row_law::limit_may_act(low, high, v, error_low(), error_high(), dx, phase))
            : any_of(row_law::limit_crossing(v, error_low(), error_high(), dx, phase));
    if (act) held = 1.0;  // the law may leave an impulse
    return act;
  }
  bool any_kinds() const {
    if constexpr (kLoneDrive) return false;
    return flags[8] != 0.0;
  }
  bool any_kind(int e) const { return has_bit(flags[8], static_cast<double>(1 << e)); }
  auto has_kind(int e) const { return f(Layout::kind_masks + e) != T(0.0); }
  /// A kind's row as the lanes lane picks see it.
  struct KindSlots {
    const LaneRows& rows;
    int base;
    T& operator[](int k) const { return rows.f(Layout::kind_slots + base + k); }
  };
  KindSlots kind_slots(int offset) const { return {*this, offset}; }
};

// All rows of dof d at joint velocity v, the whole pack (row_sequence.hpp).
template <class A, int K>
[[gnu::always_inline]] inline auto LaneStep<A, K>::solve_row(int d, V v, const V& dx) -> V {
  LaneRows<WholePack> rows{*this, d, row(d), WholePack{}};
  return row_sequence::solve(rows, v, dx, row_phase());
}

// Link k's part of leaving (the lanes lane picks): beta = D^-1 (impulse - S^T pA), its joint's
// velocity finished where it is its last change, and when to_parent, pA_parent = pA + beta U.
template <class A, int K>
auto LaneStep<A, K>::left_link(int k) -> LeftLink {
  const LinkConstants& lk = sa_.links[k];
  const int d = lk.v_index;
  return {sa_.D_inv + k, sa_.jimp + d, sa_.S + 6 * k, sa_.subtree + 6 * k, sa_.U + 6 * k,
          sa_.G + 6 * k, sa_.entry + d, sa_.qd + d, sa_.subtree + 6 * lk.parent,
          lk.finish_on_leave};
}

template <class A, int K>
template <class L>
[[gnu::always_inline]] inline void LaneStep<A, K>::leave_chain_link(const L& lane,
                                                                    const LeftLink& l,
                                                                    bool to_parent, V& beta) {
  auto& b = lane(beta);
  using T = std::remove_cvref_t<decltype(b)>;
  b = sweep_law::leave_beta(lane(*l.D_inv), lane(*l.jimp),
                            sweep_law::dot6<T>(six(lane, l.S), six(lane, l.pA)));
  if (l.finish) {
    auto& qd = lane(*l.qd);
    qd = sweep_law::finished_velocity(qd, lane(*l.entry), six(lane, l.G), six(lane, l.pA));
  }
  if (to_parent)  // the parent's first child (sweep_law, eq. SW12)
    sweep_law::hand_over<T>(sweep_law::handed(six(lane, l.pA), b, six(lane, l.U)), true,
                            six(lane, l.pA_parent));
}

// Leaves the run of only children from k (sweep_walk::in_run; leave_chain_link's operations in
// its order), the subtree impulse carried up in registers, one vector at a time where
// kVectorByVector, and stored once where the run ends: in the link returned.
template <class A, int K>
int LaneStep<A, K>::leave_chain_run(int k, int stop) {
  const LinkConstants* const links = sa_.links;
  int end = k;
  while (sweep_walk::in_run(links[end], stop)) end = links[end].parent;
  // The arrays' starts, found once (a store through a pack may alias the plan).
  const V *const G0 = sa_.G, *const U0 = sa_.U, *const S0 = sa_.S;
  const V *const D_inv0 = sa_.D_inv, *const jimp0 = sa_.jimp, *const pS0 = sa_.chain_pS;
  const V* const entry0 = sa_.entry;
  V* const qd0 = sa_.qd;
  V* const pA0 = sa_.subtree;
  // Two vectors at a time where kVectorByVector: each run is a chain of dependences from link to
  // link, and two of them interleaved keep the core busy while one waits.
  auto leave = [&](const auto& lanes) {
    using Lanes = std::remove_cvref_t<decltype(lanes)>;
    constexpr int N = static_cast<int>(std::tuple_size_v<Lanes>);
    using T = std::remove_cvref_t<decltype(lanes[0](std::declval<V&>()))>;
    const V* pAk = pA0 + 6 * k;
    T pA[N][6], Sp[N];  // Sp: S_i^T pA_i of the link being left
    for (int n = 0; n < N; ++n) {
      for (int r = 0; r < 6; ++r) pA[n][r] = lanes[n](pAk[r]);
      Sp[n] = sweep_law::dot6<T>(six(lanes[n], S0 + 6 * k), pA[n]);
    }
    for (int i = k; i != end; i = links[i].parent) {
      const LinkConstants& l = links[i];
      const int d = l.v_index;
      const V* G = G0 + 6 * i;
      const V* U = U0 + 6 * i;
      const V* S_up = S0 + 6 * l.parent;
      const V *D_inv = D_inv0 + i, *jimp = jimp0 + d, *pS = pS0 + i;
      const V* entry = entry0 + d;
      V* qd_d = qd0 + d;
      const bool up_in_run = l.parent != end;  // then one dof (LinkConstants::chain_up)
      for (int n = 0; n < N; ++n) {
        const auto& lane = lanes[n];
        T* x = pA[n];
        const T b = sweep_law::leave_beta(lane(*D_inv), lane(*jimp), Sp[n]);
        // The parent's S^T pA after the hand-over, from this pA and a scalar (implicit_drives.md,
        // eq. GS3).
        if (up_in_run) Sp[n] = sweep_law::parent_S_pA(six(lane, S_up), x, b, lane(*pS));
        auto& qd = lane(*qd_d);
        qd = sweep_law::finished_velocity(qd, lane(*entry), six(lane, G), x);
        for (int r = 0; r < 6; ++r) x[r] = x[r] + b * lane(U[r]);
      }
    }
    V* pA_end = pA0 + 6 * end;
    for (int n = 0; n < N; ++n)
      for (int r = 0; r < 6; ++r) lanes[n](pA_end[r]) = pA[n][r];
  };
  by_vector_pairs(leave);
  return end;
}

// Link k left alone (sweep_walk::leave_links): it hands its subtree's impulse to its parent, and
// where fix, corrects the parent's velocity change by the parent's response to it.
template <class A, int K>
void LaneStep<A, K>::leave_link(int k, bool fix) {
  const LinkConstants& lk = sa_.links[k];
  const int p = lk.parent;
  const bool first_child = lk.first_child, last_child = lk.last_child;
  // A chain's link hands its impulse straight into the parent's subtree impulse.
  const bool chain = p >= 0 && first_child && !fix;
  const V* pAk = sa_.subtree + 6 * k;
  const V* U = nullptr;  // null for a fixed joint: it passes its subtree's impulse on whole
  V beta;
  V ball_pa[6];  // a spherical joint's hand-over
  if (lk.type == 4) {
    leave_ball(k, ball_pa);
    pAk = ball_pa;
  }
  if (one_dof(lk)) {
    U = sa_.U + 6 * k;
    const LeftLink l = left_link(k);
    if constexpr (kVectorByVector)
      for (int j = 0; j < K; ++j) leave_chain_link(OneVector{j}, l, chain, beta);
    else
      leave_chain_link(WholePack{}, l, chain, beta);
  }
  if (p < 0) return;
  // The hand-over (sweep_law, eq. SW12-SW14): a chain's one-dof link did it in leave_chain_link.
  V* pAp = sa_.subtree + 6 * p;
  if (chain) {
    if (!U) sweep_law::hand_over<V>(pAk, true, pAp);
  } else {
    V pa[6];
    for (int r = 0; r < 6; ++r) pa[r] = U ? sweep_law::handed(pAk, beta, U)[r] : pAk[r];
    sweep_law::hand_over<V>(pa, first_child, pAp);
    if (fix) correct_parent(p, pa);
  }
  if (!last_child) sweep_law::record_after<V>(pAp, sa_.after + 6 * k);
}
// Link p's velocity change less its response to the impulse pa handed it (sweep_law, eq. SW13),
// one vector at a time: its six entries of pa stay in registers. Out of line, as Simulation's
// correct_velocity_change: inlined, it moved the spills of leave_chain_run's loop.
template <class A, int K>
void LaneStep<A, K>::correct_parent(int p, const V* pa) {
  const V* Lambda = sa_.Lambda + 21 * p;
  V* dv = sa_.dv + 6 * p;
  for (int j = 0; j < K; ++j)
    sweep_law::correct_parent<B>(SymmetricVector{Lambda, j}, six(OneVector{j}, pa),
                                 six(OneVector{j}, dv));
}

// A joint not finished when left: its velocity change from its subtree and from later subtrees
// (gauss_seidel.hpp's finish_link).
template <class A, int K>
void LaneStep<A, K>::finish_link(int i) {
  const LinkConstants& lk = sa_.links[i];
  if (lk.type == 3) {
    root_finish();
    return;
  }
  if (lk.type == 0 && !lk.later_read) return;  // its E is read by no one
  V* const later_i = sa_.later + 6 * i;  // found once: a store through a pack may alias l_
  V E[6];
  if (lk.later) {
    const V* Ep = sa_.links[lk.parent].later ? sa_.later + 6 * lk.parent : sa_.zero;
    for (int r = 0; r < 6; ++r) E[r] = Ep[r];
    if (!lk.last_child) {
      V diff[6], t[6];
      const V* pAp = sa_.subtree + 6 * lk.parent;
      const V* after = sa_.after + 6 * i;
      for (int r = 0; r < 6; ++r) diff[r] = pAp[r] - after[r];
      sym_times(sa_.Lambda + 21 * lk.parent, diff, t);
      for (int r = 0; r < 6; ++r) E[r] = E[r] - t[r];
    }
  }
  if (lk.type == 0) {
    if (lk.later)
      for (int r = 0; r < 6; ++r) later_i[r] = E[r];
    return;
  }
  if (lk.type == 4) {
    finish_ball(i, lk.later ? E : nullptr);
    return;
  }
  if (lk.finish_down) {
    finish_run(i, E);
    return;
  }
  const int d = lk.v_index;
  V dqd = sa_.entry[d] - sweep_law::dot6<V>(sa_.G + 6 * i, sa_.subtree + 6 * i);
  if (lk.later) {
    const V* S = sa_.S + 6 * i;
    const V later = sweep_law::later(sa_.D_inv[i], sa_.U + 6 * i, E);
    dqd = dqd + later;
    if (lk.later_read)
      for (int r = 0; r < 6; ++r) later_i[r] = E[r] + later * S[r];
  }
  V& qd = sa_.qd[d];
  qd = qd + dqd;
}

// finish_link's one-dof part down the run of only children from i (LinkConstants::finish_down),
// E being i's: each link's E carried to its child in registers, a vector or two at a time where
// kVectorByVector (as leave_chain_run), stored where the run ends if a child reads it there.
template <class A, int K>
void LaneStep<A, K>::finish_run(int i, const V* E) {
  // The arrays' starts, found once (a store through a pack may alias the plan).
  const LinkConstants* const links = sa_.links;
  const V *const G0 = sa_.G, *const pA0 = sa_.subtree, *const U0 = sa_.U;
  const V *const S0 = sa_.S, *const D_inv0 = sa_.D_inv, *const entry0 = sa_.entry;
  V* const qd0 = sa_.qd;
  V* const later0 = sa_.later;
  auto finish = [&](const auto& lanes) {
    using Lanes = std::remove_cvref_t<decltype(lanes)>;
    constexpr int N = static_cast<int>(std::tuple_size_v<Lanes>);
    using T = std::remove_cvref_t<decltype(lanes[0](std::declval<V&>()))>;
    T e[N][6];
    for (int n = 0; n < N; ++n)
      for (int r = 0; r < 6; ++r) e[n][r] = lanes[n](E[r]);
    for (int l = i;; ++l) {
      const LinkConstants& lk = links[l];
      const int d = lk.v_index;
      const V *G = G0 + 6 * l, *pA = pA0 + 6 * l, *U = U0 + 6 * l, *S = S0 + 6 * l;
      const V *D_inv = D_inv0 + l, *entry = entry0 + d;
      V* qd_d = qd0 + d;
      for (int n = 0; n < N; ++n) {
        const auto& lane = lanes[n];
        T dqd = lane(*entry) - sweep_law::dot6<T>(six(lane, G), six(lane, pA));
        const T later = sweep_law::later(lane(*D_inv), six(lane, U), e[n]);
        dqd = dqd + later;
        for (int r = 0; r < 6; ++r) e[n][r] = e[n][r] + later * lane(S[r]);
        auto& qd = lane(*qd_d);
        qd = qd + dqd;
      }
      if (!lk.finish_down) {
        if (lk.later_read) {
          V* later_l = later0 + 6 * l;
          for (int n = 0; n < N; ++n)
            for (int r = 0; r < 6; ++r) lanes[n](later_l[r]) = e[n][r];
        }
        return;
      }
    }
  };
  by_vector_pairs(finish);
}

// Link i entered (the lanes lane picks): its joint's velocity from outside its subtree, its
// rows (a lone drive's alone when lane is one vector) or, kGiven, the impulse given at its dof,
// its velocity change dv for its children.
template <class A, int K>
template <bool kGiven, class L>
[[gnu::always_inline]] inline void LaneStep<A, K>::enter_link(const L& lane, int i, const V* dvp,
                                                              V* dv) {
  const LinkConstants& k = sa_.links[i];
  const int d = k.v_index;
  const V* U = sa_.U + 6 * i;
  const V* S = sa_.S + 6 * i;
  const V* W = sa_.W + 6 * i;
  V* rw = row(d);
  const bool chain_next = i + 1 < p_.num_links && sa_.links[i + 1].chain_in;
  const auto D_inv = lane(sa_.D_inv[i]);
  using T = std::remove_cv_t<decltype(D_inv)>;
  // A chained link's base was formed by its parent (implicit_drives.md, eq. GS1); the next link's
  // part that does not wait on this link's impulse is formed before the rows (eq. GS2).
  const T base = k.chain_in ? lane(sa_.chain_base[i])
                            : sweep_law::base(D_inv, six(lane, U), six(lane, dvp));
  T ahead{};
  if (chain_next) {
    const T D_next = lane(sa_.D_inv[i + 1]);  // its b^b = -D^-1 U^T S_i, formed as in the pass
    ahead = sweep_law::ahead(D_next, six(lane, sa_.U + 6 * (i + 1)), six(lane, dvp), base,
                             T(-D_next * lane(sa_.chain_pS[i + 1])));
  }
  T impulse;
  if constexpr (kGiven) {
    impulse = lane(sa_.given[d]);
  } else if constexpr (std::is_same_v<T, V>) {
    // compat physx: a prismatic row sees the link bias (PD-2).
    const V v = p_.physx_prismatic ? sa_.qd[d] + base + row_bias(d) : sa_.qd[d] + base;
    impulse = solve_row(d, v, rw[Layout::delta_x]);
  } else {
    T v = lane(sa_.qd[d]) + base;
    if (p_.physx_prismatic) v = v + lane(sa_.row_bias[d]);
    LaneRows<L, true> rows{*this, d, rw, lane};
    impulse = row_sequence::solve(rows, v, lane(rw[Layout::delta_x]), row_phase());
  }
  lane(sa_.jimp[d]) = impulse;
  if (chain_next)
    lane(sa_.chain_base[i + 1]) =
        sweep_law::chained_base(ahead, impulse, T(lane(sa_.chain_pi[i + 1])));
  // dv's entries all read before any is stored: one lane's six then go as pairs (SSE2).
  auto after_rows = [&](auto&& out) {
    return sweep_law::after_rows(base, impulse, T(lane(sa_.inverse_mass[i])), D_inv,
                                 six(lane, dvp), six(lane, W), six(lane, S), out);
  };
  // A childless link's dv is read by no one: formed into a sink, it is not formed at all.
  lane(sa_.entry[d]) =
      k.leaf && !k.contacts ? after_rows(Sink<T>{}) : after_rows(six(lane, dv));
}

// One Gauss-Seidel sweep (gauss_seidel.hpp) with exact joint velocities, O(n): the mimic rows
// first, as PhysX solves them (mimic_solve.hpp), then the dofs' rows.
template <class A, int K>
void LaneStep<A, K>::sweep() {
  if (p_.num_mimic > 0) solve_mimic();
  if (p_.contacts) {  // Stepper::sweep: its phase, the self rows, the links' velocities then
    LaneContactPhase& c = contact_phase_;
    c.dt = p_.dt, c.h = h_, c.tgs = p_.tgs, c.velocity_iteration = velocity_iteration_;
    c.elapsed = velocity_iteration_ ? p_.dt : p_.dt - time_to_step_end_ - h_;
    if (any(colliding_))
      for (int l = 0; l < b_.valid; ++l)
        if (self_live_[l]) contact_self_solve(*b_.contacts, p_, b_.env0 + l, c, scratch(), kW, l);
    contact_velocities();
  }
  V* saved = at(l_.saved);  // rowless lanes keep their velocities (Simulation skips the sweep)
  const bool keep = any(rowless_);
  if (keep)
    for (int d = 0; d < p_.nv; ++d) saved[d] = sa_.qd[d];
  sweep_links<false>();
  if (keep)
    for (int d = 0; d < p_.nv; ++d) sa_.qd[d] = select(rowless_, saved[d], sa_.qd[d]);
}

// What the sweeps read of the rows' constants (setup_row_constants, once a call): whether every
// lane has friction, so that its row selects nothing (row_sequence::solve), and whether the rows
// are a lone drive's, solved a vector at a time (Entering::enter).
template <class A, int K>
void LaneStep<A, K>::prepare_sweeps() {
  for_each_joint_row_dof([&](int d) {
    double* has = any_row(d);
    has[kAllFriction] = all(row(d)[Layout::has_friction] != V(0.0)) ? 1.0 : 0.0;
    has[kLimitHeld] = 1.0;
    const bool alone = has[0] == 0.0 && has[1] == 0.0 && has[3] == 0.0 && has[5] == 0.0 &&
                       has[6] == 0.0 && has[8] == 0.0 && (has[7] == 0.0 || has[7] == kActuator);
    has[kDriveAlone] = alone ? 1.0 : 0.0;
  });
}

// PGS, before a step's first sweep: which dofs' limits may act whatever the velocity. Their
// errors and dx stay as they are through the step, the impulses change only where the limit's
// law runs (LaneRows::limit_may_act marks those).
template <class A, int K>
void LaneStep<A, K>::find_held_limits() {
  for_each_joint_row_dof([&](int d) {
    if (any_row(d)[1] == 0.0) return;
    const V* rw = row(d);
    any_row(d)[kLimitHeld] = any(row_law::limit_held(rw[Layout::low], rw[Layout::high],
                                                     rw[Layout::err_low], rw[Layout::err_high],
                                                     rw[Layout::delta_x]))
                                 ? 1.0
                                 : 0.0;
  });
}

// sweep_walk's sides: links entered, contacts solved, links finished, and leaving.
template <class A, int K>
struct LaneStep<A, K>::Leaving {
  LaneStep* s;
  const LinkConstants& link(int k) const { return s->sa_.links[k]; }
  int leave_run(int k, int stop) const { return s->leave_chain_run(k, stop); }
  void leave_link(int k, int stop, bool correct) const {
    s->leave_link(k, correct && s->sa_.links[k].parent == stop);
  }
};

template <class A, int K>
template <bool kGiven>
struct LaneStep<A, K>::Entering {
  LaneStep* s;
  int num_links() const { return s->p_.num_links; }
  const LinkConstants& link(int i) const { return s->sa_.links[i]; }
  void leave(int k, int stop, bool correct) const {
    sweep_walk::leave_links<Leaving>(k, stop, correct, s);
  }
  struct Links {
    const int *first, *last;
    const int* begin() const { return first; }
    const int* end() const { return last; }
  };
  Links finish_after() const {
    return {s->p_.finish_after, s->p_.finish_after + s->p_.num_finish_after};
  }
  void finish(int i) const {
    const int p = s->sa_.links[i].parent;
    if (p < 0 || !s->sa_.links[p].finish_down) s->finish_link(i);  // else finished in p's run
  }
  // Link i alone: a chained link's base comes from its parent through the scratch (chain_in).
  [[gnu::always_inline]] void enter(int i) const {
    LaneStep& t = *s;
    const LinkConstants& k = t.sa_.links[i];
    const V* dvp = k.parent >= 0 ? t.sa_.dv + 6 * k.parent : t.sa_.zero;
    V* dv = t.sa_.dv + 6 * i;
    if (k.type == 0 || k.type == 3) {  // no rows (a floating root's are finished after the sweep)
      if (!k.leaf || k.contacts)  // a childless link's dv is read by no one
        for (int r = 0; r < 6; ++r) dv[r] = dvp[r];
    } else if (k.type == 4) {
      t.template enter_ball<kGiven>(i, dvp, dv);
    } else {
      // A lone drive: one vector at a time. With friction or a limit row in the block the whole
      // pack measured faster (the welded humanoid). An actuator's clip on the state needs the pack.
      if (!kGiven && kVectorByVector && t.any_row(k.v_index)[kDriveAlone] != 0.0)
        for (int j = 0; j < K; ++j) t.template enter_link<kGiven>(OneVector{j}, i, dvp, dv);
      else
        t.template enter_link<kGiven>(WholePack{}, i, dvp, dv);
    }
    if (k.contacts) t.template contact_link<kGiven>(i);  // right after its joint's rows (C15)
  }
};

// The sweep's passes over the links (sweep_walk::sweep): the rows' impulses, or (kGiven) the
// impulses given.
template <class A, int K>
template <bool kGiven>
void LaneStep<A, K>::sweep_links() {
  Entering<kGiven> side{this};
  sweep_walk::sweep(side);
}

// Every link's velocity in frame 0 from qd with the step-start subspaces (contact_rows.cpp's
// link_velocities0), for the contact rows.
template <class A, int K>
void LaneStep<A, K>::contact_velocities() {
  for (int i = 0; i < p_.num_links; ++i) {
    const LinkConstants& k = p_.links[i];
    V* v = at(l_.contact_vel + 6 * i);
    const V* vp = k.parent >= 0 ? at(l_.contact_vel + 6 * k.parent) : at(l_.zero);
    const V* qd = k.type != 0 ? &at(l_.qd)[k.v_index] : nullptr;
    if (one_dof(k)) {
      const V* S = at(l_.S + 6 * i);
      for (int r = 0; r < 6; ++r) v[r] = vp[r] + S[r] * qd[0];
    } else if (k.type == 3) {  // S qd by multi_dof_law (AP14), as in ABA's pass 1
      multi_dof_law::joint_motion(multi_dof_law::RotationPair<V>{at(l_.root_R)}, qd, v);
    } else if (k.type == 4) {
      V Sqd[6];
      multi_dof_law::joint_motion(multi_dof_law::DenseSubspace<V, 3>{at(l_.ball_S + 18 * i)}, qd,
                                  Sqd);
      for (int r = 0; r < 6; ++r) v[r] = vp[r] + Sqd[r];
    } else {
      for (int r = 0; r < 6; ++r) v[r] = vp[r];
    }
  }
  if (!p_.physx_contacts) return;
  // compat physx: PhysX's link velocities, with the bias B of the free update (C23a).
  for (int i = p_.num_links - 1; i >= 0; --i) {
    V* v = at(l_.contact_vel + 6 * i);
    const V* b = at(l_.contact_bias + 6 * i);
    for (int r = 0; r < 6; ++r) v[r] = v[r] + b[r];
  }
}

// compat physx, once a step (Stepper::setup_contacts): each link's bias B, at its centre of mass
// in world axes (link_bias), as a twist in frame 0, and its tracked motion zero.
template <class A, int K>
void LaneStep<A, K>::contact_bias() {
  for (int i = 0; i < p_.num_links; ++i) {
    const V* bw = at(l_.bias_w + 3 * i);
    const V* bv = at(l_.bias_v + 3 * i);
    V t[3];
    cross(bw, at(l_.start_com + 3 * i), t);
    V* b = at(l_.contact_bias + 6 * i);
    for (int r = 0; r < 3; ++r) b[r] = bw[r], b[3 + r] = bv[r] - t[r];
    for (int r = 0; r < 6; ++r) at(l_.contact_motion + 6 * i)[r] = V(0.0);
  }
}

// Link i's contact rows in a sweep, each live lane's own: their impulse starts its subtree
// impulse (0 in the other lanes and in kGiven's sweeps, which solve no rows).
template <class A, int K>
template <bool kGiven>
void LaneStep<A, K>::contact_link(int i) {
  V* pA = at(l_.subtree + 6 * i);
  for (int r = 0; r < 6; ++r) pA[r] = V(0.0);
  if constexpr (!kGiven)
    for (int l = 0; l < b_.valid; ++l)
      if (live_[l])
        contact_solve(*b_.contacts, p_, b_.env0 + l, i, contact_phase_, scratch(), kW, l);
}

// TGS, after a sub-step's positions (Stepper::track_contacts).
template <class A, int K>
void LaneStep<A, K>::track_contacts(double h_step) {
  contact_velocities();
  double h_track = h_step;
  if (p_.physx_contacts) {
    // PhysX (recordDeltaMotion; contact.md C25a): a child link's linear motion is its centre of
    // mass's move to the posed sub-step, its angular motion its turn (track_prismatic); the
    // root's the sum of h V. Their increments over the sub-step take the velocities' place.
    // The poses of the sub-step are from frame 0's origin then: the root's move is added.
    const LinkConstants& root = p_.links[0];
    V move[3] = {V(0.0), V(0.0), V(0.0)};
    if (root.type == 3) {
      V now[3], before[3];
      root_origin(&at(l_.q)[root.q_index], now);
      root_origin(&at(l_.old_q)[root.q_index], before);
      for (int r = 0; r < 3; ++r)
        move[r] = root.tree_rotation_identity
                      ? at(l_.q)[root.q_index + r] - at(l_.old_q)[root.q_index + r]
                      : now[r] - before[r];
    } else if (root.type == 2) {
      const V dx = at(l_.q)[root.q_index] - at(l_.old_q)[root.q_index];
      for (int r = 0; r < 3; ++r)  // E^T axis, kinematics.cpp's prismatic root
        move[r] = (V(root.E[r]) * V(root.axis[0]) + V(root.E[3 + r]) * V(root.axis[1]) +
                   V(root.E[6 + r]) * V(root.axis[2])) * dx;
    }
    for (int i = 0; i < p_.num_links; ++i) {
      V* M = at(l_.contact_motion + 6 * i);
      V* v = at(l_.contact_vel + 6 * i);
      V next[6];
      if (p_.links[i].parent < 0) {
        for (int r = 0; r < 6; ++r) next[r] = M[r] + V(h_step) * v[r];
      } else {
        const V* theta = at(l_.turn + 3 * i);
        const V* start = at(l_.start_com + 3 * i);
        V now[3], t[3];
        link_com(i, at(l_.now_R + 9 * i), at(l_.now_pos + 3 * i), now);
        cross(theta, start, t);
        for (int r = 0; r < 3; ++r) {
          next[r] = theta[r];
          next[3 + r] = ((now[r] + move[r]) - start[r]) - t[r];
        }
      }
      for (int r = 0; r < 6; ++r) {
        v[r] = next[r] - M[r];
        M[r] = next[r];
      }
    }
    h_track = 1.0;
  }
  for (int l = 0; l < b_.valid; ++l)
    if (live_[l]) contact_track(*b_.contacts, p_, b_.env0 + l, h_track, scratch(), kW, l);
}

// Once a step, after the response (mimic_solve.cpp's setup): each mimic row's velocity change at
// the coupled dofs per unit impulse, from rest, by a sweep with the impulses (1, G) given, and
// its row (docs/math/mimic_joints.md, eq. 2-4).
template <class A, int K>
void LaneStep<A, K>::setup_mimic() {
  V* qd = at(l_.qd);
  V* saved = at(l_.saved);
  V* given = at(l_.given);
  const int k = p_.num_mimic_dofs;
  for (int d = 0; d < p_.nv; ++d) {
    saved[d] = qd[d];
    given[d] = V(0.0);
  }
  for (int j = 0; j < p_.num_mimic; ++j) {
    const MimicConstants& m = p_.mimic[j];
    const V gear = mimic_parameter(j, mimic_gear_ratio);
    given[m.dof_a] = V(1.0);
    given[m.dof_b] = gear;
    for (int d = 0; d < p_.nv; ++d) qd[d] = V(0.0);
    sweep_links<true>();
    given[m.dof_a] = given[m.dof_b] = V(0.0);
    for (int s = 0; s < k; ++s) at(l_.mimic_change)[j * k + s] = qd[p_.mimic_dofs[s]];
    const V r = qd[m.dof_a] + gear * qd[m.dof_b];
    const MimicRowOf<V> row =
        mimic_law::setup(mimic_parameter(j, mimic_natural_frequency),
                         mimic_parameter(j, mimic_damping_ratio), r, h_solve_, p_.limit_erp);
    V* out = at(l_.mimic_row) + 3 * j;
    out[0] = row.response, out[1] = row.bias_per_error, out[2] = row.effective_mass;
  }
  for (int d = 0; d < p_.nv; ++d) qd[d] = saved[d];
}

// Every mimic row once, in order, at the exact current velocities, then their impulses applied by
// a sweep (mimic_solve.cpp's solve): qd is exact on exit.
template <class A, int K>
void LaneStep<A, K>::solve_mimic() {
  V* qd = at(l_.qd);
  V* q = at(l_.q);
  V* velocity = at(l_.mimic_velocity);
  V* given = at(l_.given);
  const int k = p_.num_mimic_dofs;
  for (int s = 0; s < k; ++s)
    velocity[s] = p_.physx_prismatic ? qd[p_.mimic_dofs[s]] + row_bias(p_.mimic_dofs[s])
                                     : qd[p_.mimic_dofs[s]];
  struct Rows {  // the packed mimic rows, as mimic_law::solve_rows reads them
    LaneStep& s;
    V* q;
    V* velocity_;
    V* given_;
    int k;
    const MimicConstants& m(int j) const { return s.p_.mimic[j]; }
    MimicRowOf<V> row(int j) const {
      const V* rw = s.at(s.l_.mimic_row) + 3 * j;
      return {rw[0], rw[1], rw[2]};
    }
    V gear(int j) const { return s.mimic_parameter(j, mimic_gear_ratio); }
    V offset(int j) const { return s.mimic_parameter(j, mimic_offset); }
    V q_a(int j) const { return q[m(j).q_a]; }
    V q_b(int j) const { return q[m(j).q_b]; }
    int slot_a(int j) const { return m(j).slot_a; }
    int slot_b(int j) const { return m(j).slot_b; }
    int dof_a(int j) const { return m(j).dof_a; }
    int dof_b(int j) const { return m(j).dof_b; }
    const V* change(int j) const { return s.at(s.l_.mimic_change) + j * k; }
    V* velocity() const { return velocity_; }
    V& given(int dof) const { return given_[dof]; }
  } rows{*this, q, velocity, given, k};
  mimic_law::solve_rows<V>(rows, p_.num_mimic, k, velocity_iteration_);
  sweep_links<true>();
  for (int s = 0; s < k; ++s) given[p_.mimic_dofs[s]] = V(0.0);
}

// compat physx at a prismatic joint (link_bias.cpp, docs/math/physx_departures.md): after the
// kinematics, from the step's start poses and velocities, each link's bias B (PD-1) and each
// prismatic row's bias u . (B_child - B_parent) at the joint point (PD-2); a revolute row's is 0.
template <class A, int K>
void LaneStep<A, K>::link_bias() {
  const V dt(p_.dt);
  for (int i = 0; i < p_.num_links; ++i) {
    const LinkConstants& k = p_.links[i];
    const V* R = at(l_.R + 9 * i);
    const V* pos = at(l_.pos + 3 * i);
    const V* v = at(l_.vel + 6 * i);  // [w; velocity of the point at frame 0's origin]
    V* c = at(l_.start_com + 3 * i);
    V* vc = at(l_.com_velocity + 3 * i);
    V* bw = at(l_.bias_w + 3 * i);
    V* bv = at(l_.bias_v + 3 * i);
    link_com(i, R, pos, c);
    link_motion_law::point_velocity(v, c, vc);  // eq. P1-6, as link_bias.cpp
    for (int r = 0; r < 3; ++r) at(l_.turn + 3 * i)[r] = V(0.0);
    if (k.parent < 0) {
      for (int r = 0; r < 3; ++r) bw[r] = bv[r] = V(0.0);
      continue;
    }
    const int p = k.parent;
    V rr[3];
    for (int r = 0; r < 3; ++r) rr[r] = c[r] - at(l_.start_com + 3 * p)[r];
    link_bias_law::link_bias(at(l_.vel + 6 * p), at(l_.com_velocity + 3 * p),
                             at(l_.bias_w + 3 * p), at(l_.bias_v + 3 * p), v, vc, rr, dt, bw, bv);
  }
  for (int d = 0; d < p_.nv; ++d) at(l_.row_bias)[d] = V(0.0);
  for (int i = 0; i < p_.num_links; ++i) {
    const LinkConstants& k = p_.links[i];
    if (k.type == 4 && k.parent >= 0) {  // its axes' angular bias (spherical_joints.md, S-8)
      const V* R = at(l_.R + 9 * i);
      const V* bw = at(l_.bias_w + 3 * i);
      const V* bp = at(l_.bias_w + 3 * k.parent);
      const V d[3] = {bw[0] - bp[0], bw[1] - bp[1], bw[2] - bp[2]};
      for (int a = 0; a < 3; ++a)
        at(l_.row_bias)[k.v_index + a] = (R[a] * d[0] + R[3 + a] * d[1]) + R[6 + a] * d[2];
    }
    if (k.type != 2) continue;
    const int p = k.parent;
    at(l_.row_bias)[k.v_index] = link_bias_law::prismatic_row_bias(
        at(l_.S + 6 * i) + 3, at(l_.pos + 3 * i), at(l_.start_com + 3 * i),
        at(l_.start_com + 3 * p), at(l_.bias_w + 3 * i), at(l_.bias_v + 3 * i),
        at(l_.bias_w + 3 * p), at(l_.bias_v + 3 * p));
  }
}

// compat physx, TGS, after a sub-step of h moved q (link_bias.cpp's
// track_prismatic_position_change): every link's turn, and a prismatic row's position change
// measured from the links' centres of mass (PD-3).
template <class A, int K>
void LaneStep<A, K>::track_prismatic(double h_step) {
  const V h(h_step);
  for (int i = 0; i < p_.num_links; ++i) {
    const LinkConstants& k = p_.links[i];
    link_pose<false>(i);
    // World angular velocity in the step's start frame, kept in the turn's room for the children.
    V* turn = at(l_.turn + 3 * i);
    V* w = at(l_.com_velocity + 3 * i);
    V root_w[3] = {V(0.0), V(0.0), V(0.0)};  // a floating root's, world axes of the start
    if (k.type == 3) {
      const V* R0 = at(l_.root_R);
      const V* qd = &at(l_.qd)[k.v_index];
      for (int r = 0; r < 3; ++r)
        root_w[r] = R0[3 * r] * qd[0] + R0[3 * r + 1] * qd[1] + R0[3 * r + 2] * qd[2];
    }
    for (int r = 0; r < 3; ++r) {
      V x = k.parent >= 0 ? at(l_.com_velocity + 3 * k.parent)[r] : root_w[r];
      if (k.type == 1) x = x + at(l_.S + 6 * i)[r] * at(l_.qd)[k.v_index];
      if (k.type == 4) {  // S's angular rows: the start rotation's columns
        const V* S3 = at(l_.ball_S + 18 * i);
        const V* qd = &at(l_.qd)[k.v_index];
        x = x + ((S3[r] * qd[0] + S3[6 + r] * qd[1]) + S3[12 + r] * qd[2]);
      }
      w[r] = x;
      turn[r] = turn[r] + h * (x + at(l_.bias_w + 3 * i)[r]);
    }
  }
  for (int i = 0; i < p_.num_links; ++i) {
    const LinkConstants& k = p_.links[i];
    if (k.type != 2) continue;
    const int p = k.parent;
    V ci[3], cp[3];
    link_com(i, at(l_.now_R + 9 * i), at(l_.now_pos + 3 * i), ci);
    link_com(p, at(l_.now_R + 9 * p), at(l_.now_pos + 3 * p), cp);
    row(k.v_index)[Layout::delta_x] = link_bias_law::prismatic_position_change(
        at(l_.S + 6 * i) + 3, ci, at(l_.start_com + 3 * i), cp, at(l_.start_com + 3 * p),
        at(l_.turn + 3 * p));
  }
}

// compat physx: every prismatic joint's position back within its limits (prismatic_limits.cpp).
template <class A, int K>
void LaneStep<A, K>::clamp_prismatic() {
  for (int i = 0; i < p_.num_links; ++i) {
    const LinkConstants& k = p_.links[i];
    if (k.type != 2) continue;
    V& q = at(l_.q)[k.q_index];
    q = clamp_select(q, dof_parameter(k.v_index, lower), dof_parameter(k.v_index, upper));
  }
}

// q += h qd on every 1-dof joint; TGS also accumulates the position change delta_x.
template <class A, int K>
void LaneStep<A, K>::integrate(double h_step, bool track) {
  const V h(h_step);
  // compat physx: the poses before the (sub)step, which a spherical joint's link turns from.
  if (p_.physx_spherical)
    for (int i = 0; i < p_.num_links; ++i) link_pose<false>(i);
  for (int i = 0; i < p_.num_links; ++i) {
    const LinkConstants& k = p_.links[i];
    if (k.type == 0) continue;
    if (k.type == 3) {
      if (p_.physx_floating) integrate_root_physx(h_step);
      else integrate_root(h_step);
      continue;
    }
    if (k.type == 4) {  // q times the quaternion of the body turn w h, normalised
      V* q = &at(l_.q)[k.q_index];
      const V* w = &at(l_.qd)[k.v_index];
      // compat physx turns it in the world (integrate_balls_physx)
      if (!p_.physx_spherical) quaternion_law::integrate_body(q, w, h, q);
      if (track)
        for (int a = 0; a < 3; ++a) {
          V& dx = row(k.v_index + a)[Layout::delta_x];
          dx = dx + h * w[a];
          if (p_.physx_spherical) dx = dx + h * row_bias(k.v_index + a);  // S-8
        }
      continue;
    }
    const V qd = at(l_.qd)[k.v_index];
    V& q = at(l_.q)[k.q_index];
    q = q + h * qd;
    if (track) {
      V& dx = row(k.v_index)[Layout::delta_x];
      dx = dx + h * qd;
    }
  }
  if (p_.physx_spherical) integrate_balls_physx(h_step);
}

// compat physx: a spherical joint's link turned in the world by h (w + B^w), w its angular
// velocity in the step's start frames and B^w its link bias, and its quaternion read back from
// the turned rotation in its new parent's joint frame (spherical_rows.cpp's
// integrate_spherical_joints); the other links' rotations follow their new positions. now_R holds
// the poses before the (sub)step on entry (integrate), after it on return.
template <class A, int K>
void LaneStep<A, K>::integrate_balls_physx(double h_step) {
  const V h(h_step);
  for (int i = 0; i < p_.num_links; ++i) {
    const LinkConstants& k = p_.links[i];
    V* w = at(l_.ball_w + 3 * i);
    for (int r = 0; r < 3; ++r) w[r] = k.parent >= 0 ? at(l_.ball_w + 3 * k.parent)[r] : V(0.0);
    if (k.type == 1) {
      for (int r = 0; r < 3; ++r) w[r] = w[r] + at(l_.S + 6 * i)[r] * at(l_.qd)[k.v_index];
    } else if (k.type == 3 || k.type == 4) {
      const V* qd = &at(l_.qd)[k.v_index];
      V t[3];  // AP14's angular rows (multi_dof_law::joint_turn), as integrate_spherical_joints
      if (k.type == 3)
        multi_dof_law::joint_turn(multi_dof_law::RotationPair<V>{at(l_.root_R)}, qd, t);
      else
        multi_dof_law::joint_turn(multi_dof_law::DenseSubspace<V, 3>{at(l_.ball_S + 18 * i)}, qd, t);
      for (int r = 0; r < 3; ++r) w[r] = w[r] + t[r];
    }
    if (k.type != 4) {
      link_pose<false>(i);
      continue;
    }
    V* R = at(l_.now_R + 9 * i);
    const V* bw = at(l_.bias_w + 3 * i);
    const V turn[3] = {w[0] + bw[0], w[1] + bw[1], w[2] + bw[2]};
    V Rn[9];  // exp(h turn) R (quaternion_law::turn_rotation, as integrate_spherical_joints)
    quaternion_law::turn_rotation(turn, h, R, Rn);
    // The link's rotation in its joint frame: E_T P^T R, P its parent's new rotation.
    V P[9];
    if (k.parent >= 0)
      for (int e = 0; e < 9; ++e) P[e] = at(l_.now_R + 9 * k.parent)[e];
    else
      for (int e = 0; e < 9; ++e) P[e] = V(e % 4 == 0 ? 1.0 : 0.0);
    V EP[9], Mj[9];
    for (int a = 0; a < 3; ++a)
      for (int cc = 0; cc < 3; ++cc)
        EP[3 * a + cc] = (V(k.E[3 * a]) * P[3 * cc] + V(k.E[3 * a + 1]) * P[3 * cc + 1]) +
                         V(k.E[3 * a + 2]) * P[3 * cc + 2];
    for (int a = 0; a < 3; ++a)
      for (int d = 0; d < 3; ++d)
        Mj[3 * a + d] = (EP[3 * a] * Rn[d] + EP[3 * a + 1] * Rn[3 + d]) + EP[3 * a + 2] * Rn[6 + d];
    alignas(64) double m[9][kW], qo[4][kW];
    for (int e = 0; e < 9; ++e) Mj[e].store_aligned(m[e]);
    V* q = &at(l_.q)[k.q_index];
    for (int e = 0; e < 4; ++e) q[e].store_aligned(qo[e]);
    for (int l = 0; l < kW; ++l) {
      double ml[9], ql[4];
      for (int e = 0; e < 9; ++e) ml[e] = m[e][l];
      for (int e = 0; e < 4; ++e) ql[e] = qo[e][l];
      rotation_quaternion(ml, ql);
      for (int e = 0; e < 4; ++e) qo[e][l] = ql[e];
    }
    for (int e = 0; e < 4; ++e) q[e] = V::load_aligned(qo[e]);
    for (int e = 0; e < 9; ++e) R[e] = Rn[e];
  }
}

// qd scaled down, all joints by one ratio, until none exceeds its velocity limit (step.cpp's
// scale_to_velocity_limits, dof by dof in the same order).
template <class A, int K>
void LaneStep<A, K>::scale_to_velocity_limits() {
  const V one(1.0);
  V ratio = one;
  for (int d = 0; d < p_.nv; ++d) {
    if (any_row(d)[3] == 0.0) continue;
    ratio = row_law::velocity_scale(ratio, at(l_.qd)[d], row(d)[Layout::vmax]);
  }
  const M scaled = ratio < one;
  if (!any(scaled)) return;
  for (int d = 0; d < p_.nv; ++d) at(l_.qd)[d] = select(scaled, at(l_.qd)[d] * ratio, at(l_.qd)[d]);
}

// A floating root's rotation R0 = E_T^T R_q, with R_q that of its normalised quaternion (w x y z)
// (kinematics.cpp's position_link on joint_motion.cpp's transform). With kStart, R0 and R_q are
// kept for the step: R0 gives S = diag(R0, R0) and R_q the axes of compat none's root velocity.
template <class A, int K>
template <bool kStart>
void LaneStep<A, K>::root_pose(V* R) {
  const LinkConstants& k = p_.links[0];
  V Rq[9];
  quaternion_rotation(&at(l_.q)[k.q_index + 3], Rq);
  // R0 = P R_q with P = E_T^T, the world being the root's parent (joint_transform_law, eq. JT-6).
  if (k.tree_rotation_identity)
    for (int e = 0; e < 9; ++e) R[e] = Rq[e];
  else
    joint_transform_law::compose(BroadcastTransposed{k.E}, joint_transform_law::rows(Rq),
                                 joint_transform_law::rows(R));
  if (!kStart) return;
  for (int e = 0; e < 9; ++e) {
    at(l_.root_R)[e] = R[e];
    at(l_.root_Rq)[e] = Rq[e];
  }
}

// ABA pass 2 at a floating root: multi_dof_law (docs/math/unit_response.md, eq. AP7-AP9) on
// S = diag(R0, R0), as Simulation's.
template <class A, int K>
void LaneStep<A, K>::root_articulated() {
  const LinkConstants& k = p_.links[0];
  const multi_dof_law::RotationPair<V> S{at(l_.root_R)};
  auto armature = [&](int a) { return dof_parameter(k.v_index + a, simd::armature); };
  multi_dof_law::joint_inertia<6>(SymmetricPack{at(l_.IA)}, S, armature, PackSqrt{},
                                  at(l_.root_U), at(l_.root_D_inv));
  multi_dof_law::joint_force<6>(&at(l_.tau)[k.v_index], S, at(l_.pA), &at(l_.u)[k.v_index]);
}

// ABA pass 3 at a floating root: multi_dof_law (eq. AP12-AP13), and the free velocity
// qd += dt qdd, to which compat none adds dt (w x v) of the root's velocity before it (step.cpp's
// begin_classical_root; docs/math/contact.md, C26).
template <class A, int K>
void LaneStep<A, K>::root_acceleration(V* a, const V& dt) {
  const LinkConstants& k = p_.links[0];
  V* qd = &at(l_.qd)[k.v_index];
  V qdd[6];
  multi_dof_law::joint_acceleration<6>(at(l_.root_U), at(l_.root_D_inv), &at(l_.u)[k.v_index], a,
                                       qdd);
  multi_dof_law::add_joint_motion(multi_dof_law::RotationPair<V>{at(l_.root_R)}, qdd, a);
  V wv[3];
  cross(qd, qd + 3, wv);
  for (int d = 0; d < 6; ++d) qd[d] = qd[d] + dt * qdd[d];
  if (p_.physx_floating) return;  // PhysX's root has its own departures (physx_free_momentum)
  for (int r = 0; r < 3; ++r) qd[3 + r] = qd[3 + r] + dt * wv[r];
}

// A floating root's whole-articulation response Lambda = S D^-1 S^T (its parent is the world),
// by response_law (docs/math/unit_response.md, eq. R10) over S = diag(R0, R0).
template <class A, int K>
void LaneStep<A, K>::root_response() {
  SymmetricPacksAssign Lambda{at(l_.Lambda)};
  response_law::world_response<6, V>(multi_dof_law::RotationPair<V>{at(l_.root_R)},
                                     RowMajorPacks<6>{at(l_.root_D_inv)}, Lambda);
}

// The end of a sweep at a floating root (gauss_seidel.hpp's finish_link; sweep_law, eq. SW11).
template <class A, int K>
void LaneStep<A, K>::root_finish() {
  sweep_law::finish_rowless_root<6>(multi_dof_law::RotationPair<V>{at(l_.root_R)},
                                    at(l_.root_D_inv), at(l_.subtree),
                                    &at(l_.qd)[p_.links[0].v_index]);
}

// A floating root moved over h (step.cpp's integrate_positions, compat none): its origin with the
// world velocity R_q v in the step's start axes, its quaternion by the body rotation w h
// (quaternion_law::integrate_body, as joint_motion.cpp's integrate_configuration).
template <class A, int K>
void LaneStep<A, K>::integrate_root(double h_step) {
  const LinkConstants& k = p_.links[0];
  const V h(h_step);
  V* q = &at(l_.q)[k.q_index];
  const V* qd = &at(l_.qd)[k.v_index];
  const V* Rq = at(l_.root_Rq);
  for (int r = 0; r < 3; ++r)
    q[r] = q[r] + h * (Rq[3 * r] * qd[3] + Rq[3 * r + 1] * qd[4] + Rq[3 * r + 2] * qd[5]);
  quaternion_law::integrate_body(q + 3, qd, h, q + 3);
}

// compat none, the step's end: a floating root's linear velocity, kept in its start axes R_q
// through the step, in its new ones (step.cpp's end_classical_root; contact.md, C28).
template <class A, int K>
void LaneStep<A, K>::end_classical_root() {
  const LinkConstants& k = p_.links[0];
  V R1[9];
  quaternion_rotation(&at(l_.q)[k.q_index + 3], R1);
  const V* Rq = at(l_.root_Rq);
  V* v = &at(l_.qd)[k.v_index + 3];
  V t[3];
  link_motion_law::in_world_axes(joint_transform_law::rows(Rq), v, t);
  link_motion_law::in_link_axes(joint_transform_law::rows(R1), t, v);
}

// compat physx, a floating root, after the kinematics and the link bias: the step's start poses
// kept (the response takes their room), the centre of mass C and total mass M, and the free
// velocity's momentum targets: the start momentum plus dt times the external wrench (gravity at
// C, the force applied on the root's dofs, link damping) (momentum_law, as
// momentum_correction.cpp; physx_departures.md PD-4, PD-5, PD-8 to PD-10).
template <class A, int K>
void LaneStep<A, K>::physx_start() {
  const int L = p_.num_links;
  for (int e = 0; e < 9 * L; ++e) at(l_.start_R)[e] = at(l_.R)[e];
  for (int e = 0; e < 3 * L; ++e) at(l_.start_pos)[e] = at(l_.pos)[e];
  V* t = at(l_.targets);  // P0, L0, C, M
  V M(0.0), C[3] = {V(0.0), V(0.0), V(0.0)};
  for (int i = 0; i < L; ++i) {
    const V m = link_parameter_pack(i, mass);
    for (int r = 0; r < 3; ++r) C[r] = C[r] + m * at(l_.start_com + 3 * i)[r];
    M = M + m;
  }
  for (int r = 0; r < 3; ++r) C[r] = select(V(0.0) < M, C[r] / M, C[r]);
  for (int i = 0; i < L; ++i) {  // the start velocities: w from the kinematics, v of the COM
    for (int r = 0; r < 3; ++r) {
      at(l_.vel_w + 3 * i)[r] = at(l_.vel + 6 * i)[r];
      at(l_.vel_v + 3 * i)[r] = at(l_.com_velocity + 3 * i)[r];
    }
  }
  V P0[3], L0[3];
  const PoseLinks start{*this, at(l_.start_R), at(l_.start_com)};
  momentum_law::momentum(start, L, C, M, P0, L0);
  const V dt(p_.dt);
  const V* R0 = at(l_.start_R);
  const V* tau = &at(l_.tau)[p_.links[0].v_index];
  V n[3], f[3];  // the root's wrench in world axes (eq. PD-7), at frame 0's origin
  link_motion_law::in_world_axes(joint_transform_law::rows(R0), tau, n);
  link_motion_law::in_world_axes(joint_transform_law::rows(R0), tau + 3, f);
  const V g[3] = {parameter(gravity_entry(0)), parameter(gravity_entry(1)),
                  parameter(gravity_entry(2))};
  const V origin[3] = {V(0.0), V(0.0), V(0.0)};
  momentum_law::add_root_wrench(dt, M, g, n, f, origin, C, P0, L0);
  if (p_.any_link_damping)  // [torque about frame 0's origin; force]
    for (int i = 0; i < L; ++i) momentum_law::add_link_wrench(dt, at(l_.link_force + 6 * i), C, P0, L0);
  for (int r = 0; r < 3; ++r) t[r] = P0[r], t[3 + r] = L0[r], t[6 + r] = C[r];
  t[9] = M;
  momentum_law::compound_inverse(start, L, C, at(l_.compound_inverse));
}

// Link i's angular velocity and COM velocity (vel_w, vel_v) in the pose (R, pos, com) from the
// root's world twist (w0, origin velocity v0) and the joint rates qd: eq. PD-6 by
// link_motion_law::world_velocity, as link_bias.cpp's world_velocity.
template <class A, int K>
void LaneStep<A, K>::world_velocity(const V* R, const V* pos, const V* com, const V* qd,
                                    const V* w0, const V* v0) {
  using link_motion_law::JointRates;
  for (int i = 0; i < p_.num_links; ++i) {
    const LinkConstants& k = p_.links[i];
    const bool root = k.parent < 0;
    const JointRates joint = root ? JointRates::none
                             : k.type == 1 ? JointRates::about_axis
                             : k.type == 2 ? JointRates::along_axis
                             : k.type == 4 ? JointRates::ball
                                           : JointRates::none;
    link_motion_law::world_velocity(root ? w0 : at(l_.vel_w + 3 * k.parent),
                                    root ? v0 : at(l_.vel_v + 3 * k.parent),
                                    root ? nullptr : com + 3 * k.parent,
                                    joint_transform_law::rows(R + 9 * i), pos + 3 * i,
                                    com + 3 * i, joint, k.axis,
                                    joint == JointRates::none ? qd : qd + k.v_index,
                                    at(l_.vel_w + 3 * i), at(l_.vel_v + 3 * i));
  }
}

// Link i's inertia about its centre of mass in world axes at rotation Ri (momentum_law's, eq.
// PD-8).
template <class A, int K>
void LaneStep<A, K>::world_inertia(int i, const V* Ri, V* I) const {
  V Ic[9];
  inertia_com(i, Ic);
  momentum_law::world_inertia(joint_transform_law::rows(Ri), joint_transform_law::rows(Ic), I);
}

template <class A, int K>
void LaneStep<A, K>::inertia_com(int i, V* Ic) const {
  const V xx = link_parameter_pack(i, inertia_xx), yy = link_parameter_pack(i, inertia_yy),
          zz = link_parameter_pack(i, inertia_zz), xy = link_parameter_pack(i, inertia_xy),
          xz = link_parameter_pack(i, inertia_xz), yz = link_parameter_pack(i, inertia_yz);
  const V m[9] = {xx, xy, xz, xy, yy, yz, xz, yz, zz};
  for (int e = 0; e < 9; ++e) Ic[e] = m[e];
}

// compat physx, after the free velocity: the root's twist changed by a rigid motion so that the
// biased free velocities have |L0| about C and the linear momentum P0 (PD-4, PD-5;
// momentum_correction.cpp's correct_free_velocity_momentum).
template <class A, int K>
void LaneStep<A, K>::physx_free_momentum() {
  const V* t = at(l_.targets);
  const V* R0 = at(l_.start_R);
  V* qd = &at(l_.qd)[p_.links[0].v_index];
  V w0[3], v0[3];  // eq. PD-7
  link_motion_law::in_world_axes(joint_transform_law::rows(R0), qd, w0);
  link_motion_law::in_world_axes(joint_transform_law::rows(R0), qd + 3, v0);
  world_velocity(at(l_.start_R), at(l_.start_pos), at(l_.start_com), at(l_.qd), w0, v0);
  V P1[3], L1[3];
  const int L = p_.num_links;
  const PoseLinks biased{*this, at(l_.start_R), at(l_.start_com), true, true};
  momentum_law::momentum(biased, L, t + 6, t[9], P1, L1);
  const V l1 = sqrt_of(L1[0] * L1[0] + L1[1] * L1[1] + L1[2] * L1[2]);
  const V l0 = sqrt_of(t[3] * t[3] + t[4] * t[4] + t[5] * t[5]);
  const V ratio = select(l1 == V(0.0), V(1.0), l0 / l1);
  V dw[3], dv[3];
  momentum_law::rigid_correction(biased, L, at(l_.compound_inverse), t + 6, t[9], P1, L1, ratio, t,
                                 dw, dv);
  const V origin[3] = {V(0.0), V(0.0), V(0.0)};  // frame 0's
  momentum_law::move_root(dw, dv, origin, t + 6, w0, v0);
  link_motion_law::in_link_axes(joint_transform_law::rows(R0), w0, qd);
  link_motion_law::in_link_axes(joint_transform_law::rows(R0), v0, qd + 3);
}

// A floating root's origin in the world from its q: r_T + E_T^T q (kinematics.cpp's X_J X_T).
template <class A, int K>
void LaneStep<A, K>::root_origin(const V* q, V* p) {
  const LinkConstants& k = p_.links[0];
  if (k.tree_rotation_identity) {
    for (int r = 0; r < 3; ++r) p[r] = V(k.r[r]) + q[r];
    return;
  }
  V E[9], Eq[3];
  for (int e = 0; e < 9; ++e) E[e] = V(k.E[e]);
  link_motion_law::in_link_axes(joint_transform_law::rows(E), q, Eq);
  for (int r = 0; r < 3; ++r) p[r] = V(k.r[r]) + Eq[r];
}

// compat physx: a floating root moved over h about its centre of mass with the world velocities
// of the step's start axes (integration_law::root_about_com, as momentum_correction.cpp's
// integrate_root_about_com).
template <class A, int K>
void LaneStep<A, K>::integrate_root_physx(double h_step) {
  const LinkConstants& k = p_.links[0];
  V c[3];
  for (int r = 0; r < 3; ++r) c[r] = link_parameter_pack(0, com_x + r);
  const integration_law::RootFrame frame{k.E, k.r, k.frame_q, k.tree_rotation_identity};
  integration_law::root_about_com(frame, c, at(l_.start_R), &at(l_.qd)[k.v_index], V(h_step),
                                  &at(l_.q)[k.q_index]);
}

// compat physx, the step's end (momentum_correction.cpp's correct_end_of_step_momentum): targets
// from the solver's biased velocities in the start pose, the velocities in the new pose from the
// root's world twist and the joint rates, a rigid correction to them, and the COM moved where the
// velocity the positions moved with puts it.
template <class A, int K>
void LaneStep<A, K>::physx_end_momentum() {
  const LinkConstants& k = p_.links[0];
  const int L = p_.num_links;
  const V* t = at(l_.targets);
  const V M = t[9];
  const V* sR = at(l_.start_R);
  const V* scom = at(l_.start_com);
  V* qd = &at(l_.qd)[k.v_index];
  const V* qp = &at(l_.qd_position)[k.v_index];
  V w0[3], v0[3], pw[3], pv[3];  // eq. PD-7
  link_motion_law::in_world_axes(joint_transform_law::rows(sR), qd, w0);
  link_motion_law::in_world_axes(joint_transform_law::rows(sR), qd + 3, v0);
  link_motion_law::in_world_axes(joint_transform_law::rows(sR), qp, pw);
  link_motion_law::in_world_axes(joint_transform_law::rows(sR), qp + 3, pv);
  V PT[3], LT[3], Ppos[3];
  world_velocity(sR, at(l_.start_pos), scom, at(l_.qd), w0, v0);
  momentum_law::momentum(PoseLinks{*this, sR, scom, true, true}, L, t + 6, M, PT, LT);
  world_velocity(sR, at(l_.start_pos), scom, at(l_.qd_position), pw, pv);
  momentum_law::momentum(PoseLinks{*this, sR, scom, false, true}, L, t + 6, M, Ppos,
                         static_cast<V*>(nullptr));
  // The new pose, from the root's new origin.
  V* ncom = at(l_.now_com);
  V C1[3] = {V(0.0), V(0.0), V(0.0)};
  for (int i = 0; i < L; ++i) {
    link_pose<false>(i);
    link_com(i, at(l_.now_R + 9 * i), at(l_.now_pos + 3 * i), ncom + 3 * i);
    const V m = link_parameter_pack(i, mass);
    for (int r = 0; r < 3; ++r) C1[r] = C1[r] + m * ncom[3 * i + r];
  }
  for (int r = 0; r < 3; ++r) C1[r] = select(V(0.0) < M, C1[r] / M, C1[r]);
  // The root keeps its world angular velocity and its COM's velocity (its origins, start and
  // now, are frame 0's).
  const V origin[3] = {V(0.0), V(0.0), V(0.0)};
  V vo[3];
  momentum_law::keep_root_com_velocity(w0, v0, scom, origin, ncom, origin, vo);
  world_velocity(at(l_.now_R), at(l_.now_pos), ncom, at(l_.qd), w0, vo);
  const PoseLinks now{*this, at(l_.now_R), ncom};
  V P1[3], L1[3], Iinv[9];
  momentum_law::momentum(now, L, C1, M, P1, L1);
  const V l1 = sqrt_of(L1[0] * L1[0] + L1[1] * L1[1] + L1[2] * L1[2]);
  const V lt = sqrt_of(LT[0] * LT[0] + LT[1] * LT[1] + LT[2] * LT[2]);
  const V ratio = select(l1 == V(0.0), V(0.0), lt / l1);
  momentum_law::compound_inverse(now, L, C1, Iinv);
  V dw[3], dv[3];
  momentum_law::rigid_correction(now, L, Iinv, C1, M, P1, L1, ratio, PT, dw, dv);
  momentum_law::move_root(dw, dv, origin, C1, w0, vo);
  // The COM shifted to C_start + dt P_pos / M, in world positions (the root's origin at q), the
  // shift into the joint frame's axes (E_T shift).
  V* q = &at(l_.q)[k.q_index];
  const V* q0 = &at(l_.old_q)[k.q_index];
  const V per_mass = V(p_.dt) / M;
  V o0[3], o1[3], C_start[3], C_now[3], shift[3];
  root_origin(q0, o0);
  root_origin(q, o1);
  for (int r = 0; r < 3; ++r) C_start[r] = o0[r] + t[6 + r], C_now[r] = o1[r] + C1[r];
  momentum_law::com_shift(C_start, Ppos, per_mass, C_now, shift);
  if (k.tree_rotation_identity) {
    for (int a = 0; a < 3; ++a) q[a] = q[a] + shift[a];
  } else {
    V E[9], Es[3];
    for (int e = 0; e < 9; ++e) E[e] = V(k.E[e]);
    link_motion_law::in_world_axes(joint_transform_law::rows(E), shift, Es);
    for (int a = 0; a < 3; ++a) q[a] = q[a] + Es[a];
  }
  const V* nR = at(l_.now_R);
  link_motion_law::in_link_axes(joint_transform_law::rows(nR), w0, qd);
  link_motion_law::in_link_axes(joint_transform_law::rows(nR), vo, qd + 3);
}

// A spherical joint's rotation R = P R(q), P its joint frame's axes, R(q) its normalised
// quaternion's (kinematics.cpp's position_link); with start, S's three columns
// [R e_k; pos x R e_k] (joint_transform_law::ball_subspace, eq. JT-11, as aba.cpp).
template <class A, int K>
void LaneStep<A, K>::ball_pose(int i, const V* P, V* R, const V* pos, bool start) {
  V Rq[9];
  quaternion_rotation(&at(l_.q)[p_.links[i].q_index], Rq);
  joint_transform_law::compose(joint_transform_law::rows(P), joint_transform_law::rows(Rq),
                               joint_transform_law::rows(R));
  if (!start) return;
  joint_transform_law::ball_subspace(joint_transform_law::rows(R), pos,
                                     joint_transform_law::columns(at(l_.ball_S + 18 * i)));
}

// ABA passes 2 and 3 at a spherical joint: multi_dof_law (docs/math/unit_response.md, eq.
// AP7-AP13) on S = ball_S's three columns, as Simulation's; pass 3 also does qd += dt qdd.
template <class A, int K>
void LaneStep<A, K>::ball_articulated(int i) {
  const LinkConstants& k = p_.links[i];
  const SymmetricPack IA{at(l_.IA + 21 * i)};
  const V* pA = at(l_.pA + 6 * i);
  const multi_dof_law::DenseSubspace<V, 3> S{at(l_.ball_S + 18 * i)};
  V* U3 = at(l_.ball_U + 18 * i);
  V* Di = at(l_.ball_D_inv + 9 * i);
  V* u = &at(l_.u)[k.v_index];
  auto armature = [&](int a) { return dof_parameter(k.v_index + a, simd::armature); };
  multi_dof_law::joint_inertia<3>(IA, S, armature, PackSqrt{}, U3, Di);
  multi_dof_law::joint_force<3>(&at(l_.tau)[k.v_index], S, pA, u);
  if (k.parent < 0) return;
  V UD[18], Ia[36];
  SymmetricPackSum parent{at(l_.IA + 21 * k.parent)};
  multi_dof_law::project_inertia<3>(IA, U3, Di, parent, UD, Ia);
  multi_dof_law::project_bias<3>(Ia, UD, pA, u, at(l_.c + 6 * i), at(l_.pA + 6 * k.parent));
}

template <class A, int K>
void LaneStep<A, K>::ball_acceleration(int i, V* a, const V& dt) {
  const LinkConstants& k = p_.links[i];
  V qdd[3];
  multi_dof_law::joint_acceleration<3>(at(l_.ball_U + 18 * i), at(l_.ball_D_inv + 9 * i),
                                       &at(l_.u)[k.v_index], a, qdd);
  multi_dof_law::add_joint_motion(multi_dof_law::DenseSubspace<V, 3>{at(l_.ball_S + 18 * i)},
                                  qdd, a);
  for (int b = 0; b < 3; ++b) {
    V& qd = at(l_.qd)[k.v_index + b];
    qd = qd + dt * qdd[b];
  }
}

// A spherical joint's response by response_law (docs/math/unit_response.md, eq. R6-R9): W = T U
// with T its parent's Lambda (zero for the world), Lambda and the unit-response block
// (M^-1)_ii.
template <class A, int K>
void LaneStep<A, K>::ball_response(int i) {
  const LinkConstants& k = p_.links[i];
  const V* T = k.parent >= 0 ? at(l_.Lambda + 21 * k.parent) : at(l_.zero);
  SymmetricPacksAssign Lambda{at(l_.Lambda + 21 * i)};
  response_law::response_n<3>(SymmetricPack{T}, response_law::Columns<V>{at(l_.ball_S + 18 * i)},
                              at(l_.ball_U + 18 * i),
                              RowMajorPacks<3>{at(l_.ball_D_inv + 9 * i)}, at(l_.ball_W + 18 * i),
                              at(l_.ball_response + 9 * i), Lambda);
}

// A spherical joint's three rows (step.cpp's setup_dof_rows): each axis's position and its drive's
// error from the quaternion, as PhysX has them (spherical_axes.hpp, called per lane), and its
// unit response, the block's diagonal.
template <class A, int K>
void LaneStep<A, K>::ball_rows(int i) {
  const LinkConstants& k = p_.links[i];
  const int v = k.v_index;
  alignas(64) double q[4][kW], target[3][kW], driven[3][kW], position[3][kW], error[3][kW];
  for (int e = 0; e < 4; ++e) at(l_.q)[k.q_index + e].store_aligned(q[e]);
  for (int a = 0; a < 3; ++a) {
    dof_parameter(v + a, target_position).store_aligned(target[a]);
    dof_parameter(v + a, has_drive).store_aligned(driven[a]);
  }
  for (int l = 0; l < kW; ++l) {
    const double ql[4] = {q[0][l], q[1][l], q[2][l], q[3][l]};
    const double tl[3] = {target[0][l], target[1][l], target[2][l]};
    const double dl[3] = {driven[0][l], driven[1][l], driven[2][l]};
    double x[3], err[3];
    spherical_axes(ql, tl, dl, x, err);
    for (int a = 0; a < 3; ++a) position[a][l] = x[a], error[a][l] = err[a];
  }
  const V* Minv = at(l_.ball_response + 9 * i);
  for (int a = 0; a < 3; ++a) {
    const V x0 = V::load_aligned(position[a]);
    const V drive_x0 = select(V::load_aligned(driven[a]) != V(0.0),
                              V::load_aligned(target[a]) - V::load_aligned(error[a]), x0);
    setup_dof_row(i, v + a, Minv[4 * a], x0, drive_x0);
  }
}

// A spherical joint entered in a sweep (gauss_seidel.hpp, several dofs; sweep_law, eq.
// SW6-SW8): its axes' rows in turn, each at the velocity the impulses before it leave (kGiven: the
// impulses given at its dofs), then its velocity change and its link's.
template <class A, int K>
template <bool kGiven>
void LaneStep<A, K>::enter_ball(int i, const V* dvp, V* dv) {
  const int v = p_.links[i].v_index;
  const V* Di = at(l_.ball_D_inv + 9 * i);
  const V* Minv = at(l_.ball_response + 9 * i);
  V base[3], impulse[3] = {V(0.0), V(0.0), V(0.0)};
  sweep_law::base_n<3>(Di, at(l_.ball_U + 18 * i), dvp, base);
  for (int a = 0; a < 3; ++a) {
    if constexpr (kGiven) {
      impulse[a] = at(l_.given)[v + a];
      continue;
    }
    V current = sweep_law::row_velocity<3>(at(l_.qd)[v + a], base[a], Minv, a, impulse);
    if (p_.physx_spherical) current = current + row_bias(v + a);  // S-8
    impulse[a] = impulse[a] + solve_row(v + a, current, row(v + a)[Layout::delta_x]);
  }
  for (int a = 0; a < 3; ++a) at(l_.jimp)[v + a] = impulse[a];
  sweep_law::after_rows_n<3>(impulse, Di, at(l_.ball_W + 18 * i), at(l_.ball_U + 18 * i),
                             multi_dof_law::DenseSubspace<V, 3>{at(l_.ball_S + 18 * i)}, dvp,
                             &at(l_.entry)[v], dv);
}

// The impulse a spherical joint's link hands its parent (sweep_law, eq. SW9).
template <class A, int K>
void LaneStep<A, K>::leave_ball(int k, V* pa) {
  sweep_law::hand_over_n<3>(&at(l_.jimp)[p_.links[k].v_index],
                            multi_dof_law::DenseSubspace<V, 3>{at(l_.ball_S + 18 * k)},
                            at(l_.ball_U + 18 * k), at(l_.ball_D_inv + 9 * k),
                            at(l_.subtree + 6 * k), pa);
}

// A spherical joint after a sweep (gauss_seidel.hpp's finish_link, several dofs; sweep_law, eq.
// SW10 and SW5): its velocity change from its subtree and from later subtrees (E).
template <class A, int K>
void LaneStep<A, K>::finish_ball(int i, const V* E) {
  const int v = p_.links[i].v_index;
  const multi_dof_law::DenseSubspace<V, 3> S{at(l_.ball_S + 18 * i)};
  const V* U3 = at(l_.ball_U + 18 * i);
  const V* Di = at(l_.ball_D_inv + 9 * i);
  V dqd[3];
  sweep_law::finished_n<3>(&at(l_.entry)[v], S, at(l_.ball_W + 18 * i),
                           at(l_.ball_response + 9 * i), Di, at(l_.subtree + 6 * i), dqd);
  if (E) sweep_law::later_n<3>(Di, U3, S, E, dqd, at(l_.later + 6 * i));
  for (int a = 0; a < 3; ++a) at(l_.qd)[v + a] = at(l_.qd)[v + a] + dqd[a];
}

// A wrapped revolute joint's position back into [-2 pi, 2 pi] by one turn of 4 pi, then clamped
// to [-4 pi, 4 pi] (wrap_law, docs/math/revolute_wrap.md eq. 1).
template <class A, int K>
void LaneStep<A, K>::wrap_positions() {
  for (int i = 0; i < p_.num_links; ++i) {
    const LinkConstants& k = p_.links[i];
    if (k.type != 1 || any_row(k.v_index)[4] == 0.0) continue;
    V& q = at(l_.q)[k.q_index];
    q = select(dof_parameter(k.v_index, wrapped) != V(0.0), wrap_law::wrapped(q), q);
  }
}

template <class A, int K>
void LaneStep<A, K>::step() {
  if (p_.any_velocity_limit) scale_to_velocity_limits();
  kinematics_and_bias();
  if (p_.contacts) {  // the poses, before the response takes their room
    alignas(64) double stopped[kW];
    select(stopped_, V(1.0), V(0.0)).store_aligned(stopped);
    for (int l = 0; l < b_.valid; ++l) {
      live_[l] = stopped[l] == 0.0 && contacts_active(*b_.contacts, b_.env0 + l);
      self_live_[l] = live_[l] && self_contacts_active(*b_.contacts, b_.env0 + l);
      if (live_[l]) contact_poses(*b_.contacts, p_, b_.env0 + l, scratch(), kW, l);
    }
  }
  if (p_.physx_prismatic || p_.physx_floating || p_.physx_spherical || p_.physx_contacts)
    link_bias();
  if (p_.physx_floating) physx_start();
  articulated_pass();
  forward_pass();
  if (p_.physx_floating) physx_free_momentum();
  // A leaf's subtree impulse is never written by a sweep (no child hands it one) and must read 0;
  // its room held the bias forces until now.
  for (int i = 0; i < p_.num_links; ++i)
    if (p_.links[i].leaf)
      for (int r = 0; r < 6; ++r) at(l_.subtree + 6 * i)[r] = V(0.0);
  if (p_.num_mimic > 0) setup_mimic();
  if (p_.contacts) {  // Stepper::setup_contacts, from the free velocity
    if (p_.physx_contacts) contact_bias();
    contact_velocities();
    for (int l = 0; l < b_.valid; ++l)
      if (live_[l]) contact_setup(*b_.contacts, p_, b_.env0 + l, scratch(), kW, l);
  }
  const double dt = p_.dt;
  velocity_iteration_ = false;
  // Convergence tracking (step.cpp's solve_pgs): each drive impulse before the last position
  // iteration, then its change; TGS solves each sub-step's impulse once: 0. A stopped lane keeps
  // the change of the step it stopped in, as its Simulation does.
  V* const change = at(l_.change);
  if (!p_.tgs) {
    h_ = dt;
    recip_h_ = 1.0 / dt;
    find_held_limits();  // the step's rows are set up; no sweep has run
    for (int it = 0; it < p_.position_iterations; ++it) {
      if (b_.drive_change && it == p_.position_iterations - 1)
        for (int d = 0; d < p_.nv; ++d) at(l_.before)[d] = row(d)[Layout::dimp];
      sweep();
    }
    if (b_.drive_change)
      for (int d = 0; d < p_.nv; ++d)
        change[d] = select(stopped_, change[d], row(d)[Layout::dimp] - at(l_.before)[d]);
    if (p_.physx_floating)  // the velocity the positions move with
      for (int d = 0; d < p_.nv; ++d) at(l_.qd_position)[d] = at(l_.qd)[d];
    integrate(dt, false);
    velocity_iteration_ = true;
    for (int it = 0; it < p_.velocity_iterations; ++it) sweep();
    if (p_.physx_prismatic) clamp_prismatic();  // after the rows, which never see it
  } else {
    const int n = p_.position_iterations;
    const double rho = dt / n;
    h_ = rho;
    recip_h_ = 1.0 / rho;
    if (b_.drive_change)
      for (int d = 0; d < p_.nv; ++d) change[d] = select(stopped_, change[d], V(0.0));
    if (p_.physx_floating)
      for (int d = 0; d < p_.nv; ++d) at(l_.qd_position)[d] = V(0.0);
    const V share(1.0 / n);
    for (int i = 1; i <= n; ++i) {
      time_to_step_end_ = dt - i * rho;
      sweep();
      integrate(rho, true);
      if (p_.physx_prismatic) {  // the next sub-step's rows see the clamped pose (PD-3)
        clamp_prismatic();
        track_prismatic(rho);
      } else if (p_.physx_contacts) {
        track_prismatic(rho);  // the sub-step's poses and turns, the contacts' motion (C25a)
      }
      if (p_.contacts) track_contacts(rho);
      if (p_.physx_floating)  // the mean of the sub-steps' velocities
        for (int d = 0; d < p_.nv; ++d)
          at(l_.qd_position)[d] = at(l_.qd_position)[d] + share * at(l_.qd)[d];
    }
    velocity_iteration_ = true;
    // Only friction, limit and mimic rows act in TGS velocity iterations; lanes without keep
    // their velocities.
    if (p_.num_mimic > 0) {
      for (int it = 0; it < p_.velocity_iterations; ++it) sweep();
    } else if (const M acting = undriven_ | grounded_ | colliding_;
               any(acting) && p_.velocity_iterations > 0) {
      V* saved = at(l_.saved_tgs);
      for (int d = 0; d < p_.nv; ++d) saved[d] = at(l_.qd)[d];
      for (int it = 0; it < p_.velocity_iterations; ++it) sweep();
      for (int d = 0; d < p_.nv; ++d) at(l_.qd)[d] = select(acting, at(l_.qd)[d], saved[d]);
    }
  }
  if (p_.physx_floating) physx_end_momentum();
  else if (p_.floating_base) end_classical_root();
  wrap_positions();
  const V inv_dt(1.0 / dt);
  for (int d = 0; d < p_.nv; ++d) {
    const V* rw = row(d);
    at(forces_.df)[d] = rw[Layout::dimp] * inv_dt;
    if (p_.any_implicit_actuator) {  // the row was the actuator's (step.cpp's row_forces)
      const M actuated = dof_parameter(d, implicit_actuator) != V(0.0);
      at(l_.af)[d] = select_zero(actuated, at(forces_.df)[d]);
      at(forces_.df)[d] = select(actuated, V(0.0), at(forces_.df)[d]);
    }
    at(forces_.lf)[d] = (rw[Layout::low] + rw[Layout::high]) * inv_dt;
    at(forces_.ff)[d] = (rw[Layout::fimp] + rw[Layout::tf_applied]) * inv_dt;
    at(forces_.vf)[d] = rw[Layout::vlimp] * inv_dt;
    // The row kinds' forces (step.cpp's row_kind_forces): 0 on a lane without the row.
    if (p_.any_row_kinds)
      RowKinds::for_each([&]<class E>(E, int, int slot) {
        const M on = rw[Layout::kind_masks + E::index] != V(0.0);
        at(l_.rk)[E::index * p_.nv + d] =
            select_zero(on, rw[Layout::kind_slots + slot + E::Kind::kImpulse] * inv_dt);
      });
  }
  if (p_.contacts)  // Stepper::contact_forces: the forces, checked with the state
    for (int l = 0; l < b_.valid; ++l)
      if (live_[l]) contact_stop_[l] = contact_report(*b_.contacts, p_, b_.env0 + l);
}

// After a step: lanes with a non-finite value stop with the state before it (the first culprit
// recorded in Simulation's order); the others count the step.
template <class A, int K>
void LaneStep<A, K>::finish_step() {
  const V zero(0.0);
  V z = zero;  // x * 0 is 0 for finite x, NaN otherwise
  for (int d = 0; d < p_.nv; ++d)
    z = z + (at(l_.qd)[d] * zero + at(forces_.df)[d] * zero + at(forces_.lf)[d] * zero +
             at(forces_.ff)[d] * zero + at(forces_.vf)[d] * zero);
  for (int k = 0; p_.any_row_kinds && k < RowKinds::size * p_.nv; ++k) z = z + at(l_.rk)[k] * zero;
  for (int k = 0; k < p_.nq; ++k) z = z + at(l_.q)[k] * zero;
  if (p_.contacts) {
    alignas(64) double forces[kW] = {};
    for (int l = 0; l < b_.valid; ++l)
      if (live_[l] && contact_stop_[l].quantity != 0) forces[l] = __builtin_nan("");
    z = z + V::load_aligned(forces);
  }
  // Not z != 0: xsimd 8's != is unordered with SSE2 and ordered with AVX (false for a NaN).
  const M bad = !(z == zero);
  const M fresh = bad & (!stopped_);
  if (any(fresh)) {
    alignas(64) double fresh_lanes[kW];
    select(fresh, V(1.0), zero).store_aligned(fresh_lanes);
    for (int l = 0; l < b_.valid; ++l) {
      if (fresh_lanes[l] == 0.0) continue;
      Stop stop;
      auto lane = [&](V x) {
        alignas(64) double t[kW];
        x.store_aligned(t);
        return t[l];
      };
      auto check = [&](int quantity, int dof, double value) {
        if (stop.quantity == 0 && !(value * 0.0 == 0.0)) stop = Stop{quantity, dof, value};
      };
      for (int d = 0; d < p_.nv; ++d) {
        check(1, d, lane(at(l_.qd)[d]));
        check(2, d, lane(at(forces_.df)[d]));
        check(3, d, lane(at(forces_.lf)[d]));
        check(4, d, lane(at(forces_.ff)[d]));
        check(5, d, lane(at(forces_.vf)[d]));
        for (int e = 0; p_.any_row_kinds && e < RowKinds::size; ++e)
          check(10 + e, d, lane(at(l_.rk)[e * p_.nv + d]));
      }
      for (int i = 0; i < p_.num_links; ++i) {
        const LinkConstants& k = p_.links[i];
        if (one_dof(k)) check(6, k.v_index, lane(at(l_.q)[k.q_index]));
        if (k.type == 3)  // position, quaternion: the dofs of q's entries (Simulation's order)
          for (int e = 0; e < 7; ++e)
            check(6, k.v_index + (e < 5 ? e : 5), lane(at(l_.q)[k.q_index + e]));
        if (k.type == 4)
          for (int e = 0; e < 4; ++e)
            check(6, k.v_index + (e < 2 ? e : 2), lane(at(l_.q)[k.q_index + e]));
      }
      if (stop.quantity == 0 && p_.contacts && live_[l]) stop = contact_stop_[l];
      b_.stop[b_.env0 + l] = stop;
      b_.stopped_now[b_.env0 + l] = true;
    }
  }
  stopped_ = stopped_ | bad;
  if (p_.contacts) {  // the anchors kept only from a step that ends
    alignas(64) double bad_lanes[kW];
    select(bad, V(1.0), zero).store_aligned(bad_lanes);
    for (int l = 0; l < b_.valid; ++l)
      if (live_[l]) contact_conclude(*b_.contacts, b_.env0 + l, bad_lanes[l] == 0.0);
  }
  if (any(stopped_)) {
    for (int k = 0; k < p_.nq; ++k) at(l_.q)[k] = select(stopped_, at(l_.old_q)[k], at(l_.q)[k]);
    for (int d = 0; d < p_.nv; ++d) {
      at(l_.qd)[d] = select(stopped_, at(l_.old_qd)[d], at(l_.qd)[d]);
      at(forces_.df)[d] = select(stopped_, at(old_forces_.df)[d], at(forces_.df)[d]);
      at(forces_.lf)[d] = select(stopped_, at(old_forces_.lf)[d], at(forces_.lf)[d]);
      at(forces_.ff)[d] = select(stopped_, at(old_forces_.ff)[d], at(forces_.ff)[d]);
      at(forces_.vf)[d] = select(stopped_, at(old_forces_.vf)[d], at(forces_.vf)[d]);
    }
    for (int k = 0; p_.any_row_kinds && k < RowKinds::size * p_.nv; ++k)
      at(l_.rk)[k] = select(stopped_, at(l_.old_rk)[k], at(l_.rk)[k]);
  }
  alignas(64) double stopped_lanes[kW];
  select(stopped_, V(1.0), zero).store_aligned(stopped_lanes);
  for (int l = 0; l < b_.valid; ++l) {
    if (stopped_lanes[l] != 0.0) continue;
    ++b_.step_count[row_of(b_.env0 + l)];
    b_.time[row_of(b_.env0 + l)] += p_.dt;
  }
}

template <class A, int K>
void LaneStep<A, K>::run(int steps) {
  const int nq = p_.nq, nv = p_.nv;
  // Every quantity is written before it is read in a step (a leaf's subtree impulse included),
  // so only the world's zeros need setting (clearing the whole scratch cost calls of one step
  // about a tenth of their time).
  for (int e = 0; e < 21; ++e) at(l_.zero)[e] = V(0.0);
  gather_rows(b_.q, nq, nq, at(l_.q));
  gather_rows(b_.qd, nv, nv, at(l_.qd));
  gather_rows(b_.applied, nv, nv, at(l_.tau));
  gather_rows(b_.drive_force, nv, nv, at(forces_.df));
  gather_rows(b_.limit_force, nv, nv, at(forces_.lf));
  gather_rows(b_.friction_force, nv, nv, at(forces_.ff));
  gather_rows(b_.velocity_limit_force, nv, nv, at(forces_.vf));
  if (b_.drive_change) gather_rows(b_.drive_change, nv, nv, at(l_.change));
  // Without a row kind in any lane the forces are 0: written once, at the call's end.
  if (p_.any_row_kinds)
    gather_rows(b_.row_force, RowKinds::size * nv, RowKinds::size * nv, at(l_.rk));
  else
    for (int k = 0; k < RowKinds::size * nv; ++k) at(l_.rk)[k] = V(0.0);
  alignas(64) double stopped[kW];
  for (int l = 0; l < kW; ++l) stopped[l] = b_.stop[env_of_lane(l)].quantity != 0 ? 1.0 : 0.0;
  stopped_ = V::load_aligned(stopped) != V(0.0);
  setup_row_constants(p_.tgs ? p_.dt / p_.position_iterations : p_.dt);
  prepare_sweeps();
  if (p_.contacts) {  // a grounded lane sweeps (and iterates) with or without joint rows
    alignas(64) double grounded[kW], colliding[kW];
    for (int l = 0; l < kW; ++l) {
      grounded[l] = ground_active(*b_.contacts, env_of_lane(l)) ? 1.0 : 0.0;
      colliding[l] = self_contacts_active(*b_.contacts, env_of_lane(l)) ? 1.0 : 0.0;
    }
    grounded_ = V::load_aligned(grounded) != V(0.0);
    // A lane with self contacts alone iterates in TGS's velocity iterations too, but sweeps
    // only with joint rows (Stepper::sweep solves its rows before the sweep).
    colliding_ = V::load_aligned(colliding) != V(0.0);
    rowless_ = rowless_ & !grounded_;
  }
  for (int s = 0; s < steps; ++s) {
    for (int k = 0; k < nq; ++k) at(l_.old_q)[k] = at(l_.q)[k];
    for (int d = 0; d < nv; ++d) at(l_.old_qd)[d] = at(l_.qd)[d];
    std::swap(forces_, old_forces_);
    for (int k = 0; p_.any_row_kinds && k < RowKinds::size * nv; ++k) at(l_.old_rk)[k] = at(l_.rk)[k];
    step();
    finish_step();
  }
  scatter_rows(at(l_.q), b_.q, nq, nq);
  scatter_rows(at(l_.qd), b_.qd, nv, nv);
  scatter_rows(at(forces_.df), b_.drive_force, nv, nv);
  scatter_rows(at(forces_.lf), b_.limit_force, nv, nv);
  scatter_rows(at(forces_.ff), b_.friction_force, nv, nv);
  scatter_rows(at(forces_.vf), b_.velocity_limit_force, nv, nv);
  if (b_.drive_change) scatter_rows(at(l_.change), b_.drive_change, nv, nv);
  // A stopped lane's are the diverged step's: Batch reads only those of lanes still stepping.
  if (b_.actuator_force && p_.any_implicit_actuator)
    scatter_rows(at(l_.af), b_.actuator_force, nv, nv);
  scatter_rows(at(l_.rk), b_.row_force, RowKinds::size * nv, RowKinds::size * nv);
  if (b_.guard_rows) {  // GuardField's order
    static constexpr int kField[guard_row_kinds] = {
        Layout::dimp,     Layout::low,  Layout::high,   Layout::fimp,   Layout::tf_applied,
        Layout::vlimp, Layout::response, Layout::maxi, Layout::driven, Layout::has_envelope};
    for (int d = 0; d < nv; ++d) {
      for (int f = 0; f < guard_row_kinds; ++f)
        scatter(row(d)[kField[f]], b_.guard_rows, nv * kGuardFields, d * kGuardFields + f);
      // A kind's impulse where the lane has it, 0 elsewhere (the scalar step's GuardRow).
      RowKinds::for_each([&]<class E>(E, int, int slot) {
        const M on = row(d)[Layout::kind_masks + E::index] != V(0.0);
        scatter(select_zero(on, row(d)[Layout::kind_slots + slot + E::Kind::kImpulse]),
                b_.guard_rows, nv * kGuardFields, d * kGuardFields + guard_row_kinds + E::index);
      });
    }
  }
}

}  // namespace
}  // namespace featherdrive::simd
