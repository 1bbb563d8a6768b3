// N environments of one robot stepped together on all cores (TBB): in SIMD lanes, in lane groups
// of the environments whose plans agree, each environment whose settings are within the lane
// step's (the same bits whatever the group, lane, width, batch size and threads, within 1e-12 of
// each stepped alone), every other one as an independent Simulation that shares nothing a step
// writes, bit-identical to stepping it alone whatever the number of threads. Their states lie in
// (N, n) row-major arrays, one row per environment (each Simulation's storage is its row), and
// each may have its own model parameters (masses, centres of mass, armature, gravity) over one
// topology. Also whole-vector drive setters for one Simulation. docs/conventions.md, "Batch".
#pragma once

#include <array>
#include <exception>
#include <initializer_list>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "featherdrive/algorithm/frame_kinematics.hpp"
#include "featherdrive/sim/simd_isa.hpp"
#include "featherdrive/sim/simulation.hpp"

namespace featherdrive {

namespace simd {
struct LaneGroups;
}

/// One row per environment: (N, nq) or (N, nv), row-major like numpy's default.
using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// Sets the target position and velocity of every dof (nv each). Throws std::invalid_argument
/// naming the vector and the size or the joint and value; on a throw nothing changed.
void set_drive_targets(Simulation& sim, const VecX& positions, const VecX& velocities);

/// Sets the stiffness and damping of every dof (nv each), keeping max_force, max_impulse and the
/// targets. Dofs of revolute and prismatic joints and a spherical joint's axes get `type`; a
/// floating root's dofs take no drive and must be given 0 gains. Throws std::invalid_argument naming the
/// vector, the joint and the value; on a throw nothing changed.
void set_drive_gains(Simulation& sim, const VecX& stiffness, const VecX& damping,
                     DriveType type = DriveType::force);

/// Where and why an environment stopped in Batch::step: the step (1-based, its step_count + 1)
/// and Simulation's DivergenceError message (the quantity, the joint and the value).
struct BatchDivergence {
  long step = 0;
  std::string message;
};

/// What Batch::observe gathers: the state and outputs, and the drives' targets.
enum class Observation {
  q, qd, applied_force, drive_force, limit_force, friction_force, velocity_limit_force,
  target_position, target_velocity
};

class Batch {
 public:
  /// The most environments a Batch holds (2^24; the lanes' padding to whole blocks stays within
  /// int): std::invalid_argument above.
  static constexpr int kMaxSize = 1 << 24;
  /// `count` in [1, kMaxSize] environments, each a new Simulation of `model` with `options`.
  Batch(std::shared_ptr<const Model> model, int count, const SimulationOptions& options = {});
  /// `count` environments, each a new Simulation of `model` with `settings` (throws
  /// std::invalid_argument as Simulation::set_settings does).
  Batch(std::shared_ptr<const Model> model, int count, const Settings& settings);
  /// `count` in [1, kMaxSize] copies of `prototype`: state, drives, limits and all other settings.
  Batch(const Simulation& prototype, int count);
  Batch(const Batch& other);  ///< environments with their own rows
  Batch& operator=(const Batch&) = delete;
  Batch(Batch&&) noexcept = default;
  Batch& operator=(Batch&&) noexcept = default;

  int size() const { return static_cast<int>(sims_.size()); }
  /// Environment 0's model; every environment's model has its topology.
  const Model& model() const { return sims_.front().model(); }
  const std::shared_ptr<const Model>& model_ptr() const { return sims_.front().model_ptr(); }

  /// Environment i, live: its vectors are row i of q(), qd(), ...; throws std::invalid_argument
  /// for i out of [0, size()). Assigning it a Simulation of other sizes throws.
  Simulation& sim(int i);
  const Simulation& sim(int i) const;
  /// Environment i as a Simulation of its own (a copy: its model, settings and state), e.g. for
  /// comparing with the lanes.
  Simulation simulation(int i) const;

  /// The most threads set_num_threads accepts.
  static constexpr int kMaxThreads = 4096;
  /// Threads step() uses: 0 = all cores (the default), 1 = serial on the calling thread; throws
  /// std::invalid_argument outside [0, kMaxThreads].
  void set_num_threads(int threads);
  int num_threads() const { return threads_; }
  /// The threads step() will use (num_threads(), or the number of cores for 0).
  int effective_num_threads() const;

  /// Sets every environment's options.
  void set_options(const SimulationOptions& options);

  /// Whether step() may step the environments in SIMD lanes (the default). It steps in lanes
  /// every environment whose settings are within what the lane step simulates
  /// (docs/simd_batch.md: fixed and floating bases, revolute, prismatic and spherical joints,
  /// drives, limits, friction, velocity limits, wrap, drive delays and explicit actuators (run
  /// per environment before each lane step), implicit actuators, convergence tracking, mimic
  /// rows, ground contacts, PGS and TGS, compat none and physx), with the CPU's widest
  /// instruction set (FEATHERDRIVE_SIMD names a narrower one, or `scalar` for none): in lane
  /// groups of the environments that share dt, solver, iteration counts, compat, mimic dofs and
  /// the links with shapes (gravity and every other setting may differ from lane to lane), each
  /// environment giving the same bits whatever its group, lane, the width, the batch size and
  /// the threads, within 1e-12 of its Simulation stepped alone (the operation order differs).
  /// With lanes off every environment is its Simulation stepped alone, bit for bit.
  void set_lanes(bool allowed) { lanes_allowed_ = allowed; }
  bool lanes() const { return lanes_allowed_; }
  /// How the next step() runs: "avx2 lanes" (one lane group), "avx2 lanes: 2 groups (1021, 3
  /// environments)", the environments in one-lane blocks (a group of one) counted last ("sse2
  /// lanes (1 at one lane)", "avx2 lanes: 2 groups (1021, 1 environments; 1 at one lane)"), or
  /// "scalar: " and why (lanes off, FEATHERDRIVE_SIMD=scalar).
  std::string step_path();
  /// How the next step() runs environment i: "avx2 lanes, group 1", "sse2 lanes, group 2 (one
  /// lane)" or "scalar: " and why; std::invalid_argument for i out of [0, size()).
  std::string env_path(int i);
  /// The lanes' instruction set: one this CPU runs (std::invalid_argument naming it otherwise),
  /// or nullopt (the default) for default_simd_isa(), narrowed while a block of two vectors would
  /// hold more lanes than environments (of the batch here; of its group for each lane group).
  /// Every width gives the same bits. One set here is used
  /// even with FEATHERDRIVE_SIMD=scalar.
  void set_isa(std::optional<SimdIsa> isa);
  SimdIsa isa() const;
  int width() const { return simd_width(isa()); }

  // States and outputs, (N, nq) / (N, nv): the environments' storage itself (no copy).
  const RowMatrix& q() const { return rows_[StateStorage::q]; }
  const RowMatrix& qd() const { return rows_[StateStorage::qd]; }
  const RowMatrix& applied_force() const { return rows_[StateStorage::applied_force]; }
  const RowMatrix& drive_force() const { return rows_[StateStorage::drive_force]; }
  const RowMatrix& limit_force() const { return rows_[StateStorage::limit_force]; }
  const RowMatrix& friction_force() const { return rows_[StateStorage::friction_force]; }
  const RowMatrix& velocity_limit_force() const {
    return rows_[StateStorage::velocity_limit_force];
  }
  /// The row kinds' forces (constraint/row_kinds.hpp), (N, kinds nv), kind after kind: the
  /// environments' storage itself.
  const RowMatrix& row_force() const { return rows_[StateStorage::row_force]; }
  /// One row kind's forces, (N, nv) (a copy).
  RowMatrix row_force(std::string_view kind) const;
  /// Every environment's step count and time (copies).
  std::vector<long> step_count() const;
  std::vector<double> time() const;

  /// The ground's force on each link of every environment over the last step (world axes, N):
  /// (N, 3 num_links), row i environment i's Simulation::link_contact_force() as fx, fy, fz of
  /// link 0, then link 1, ...; a copy (0 without a ground or before a step).
  RowMatrix link_contact_force() const;
  /// Environment i's contact points of the last step (Simulation::contacts), valid until it
  /// steps again; throws std::invalid_argument for i out of [0, size()).
  std::span<const ContactReport> contacts(int i) const { return sim(i).contacts(); }

  // Setters for every environment, or for the environments env_ids (distinct, in [0, size());
  // std::invalid_argument naming the entry otherwise). Values have one row per environment given
  // (N or k = env_ids.size() rows), or one row for all of them. Each is checked by the
  // Simulation's own setter before anything changes: on a throw nothing changed.
  void set_q(const RowMatrix& q);  ///< quaternions are normalised
  void set_q(std::span<const int> env_ids, const RowMatrix& q);
  void set_qd(const RowMatrix& qd);
  void set_qd(std::span<const int> env_ids, const RowMatrix& qd);
  void set_applied_force(const RowMatrix& tau);
  void set_applied_force(std::span<const int> env_ids, const RowMatrix& tau);
  /// As set_drive_targets / set_drive_gains do for one Simulation.
  void set_drive_targets(const RowMatrix& positions, const RowMatrix& velocities);
  void set_drive_targets(std::span<const int> env_ids, const RowMatrix& positions,
                         const RowMatrix& velocities);
  void set_drive_gains(const RowMatrix& stiffness, const RowMatrix& damping,
                       DriveType type = DriveType::force);
  void set_drive_gains(std::span<const int> env_ids, const RowMatrix& stiffness,
                       const RowMatrix& damping, DriveType type = DriveType::force);
  /// The same drive on one joint of every environment.
  void set_drive(const std::string& joint, const Drive& drive);

  /// Puts environments env_ids back at the start: q (default: the configuration the batch was
  /// made with, initial_q()), qd (default 0), applied force, output forces and clock 0, no
  /// friction anchors kept and no contacts reported. Drives, targets and every other setting
  /// stay; other environments are untouched.
  void reset(std::span<const int> env_ids, const std::optional<RowMatrix>& q = std::nullopt,
             const std::optional<RowMatrix>& qd = std::nullopt);
  const VecX& initial_q() const { return initial_q_; }

  // Per-environment parameters (randomisation), values as for the setters above. Per-dof
  // settings act on revolute and prismatic joints; dofs of other joints must be given the value
  // they have. Armature and inertial parameters give each environment its own model
  // (model_variant.hpp, Simulation::set_model).
  void set_armature(std::span<const int> env_ids, const RowMatrix& armature);
  void set_joint_limits(std::span<const int> env_ids, const RowMatrix& lower,
                        const RowMatrix& upper);
  void set_joint_friction(std::span<const int> env_ids, const RowMatrix& static_effort,
                          const RowMatrix& dynamic_effort, const RowMatrix& viscous);
  void set_max_joint_velocity(std::span<const int> env_ids, const RowMatrix& max_velocity);
  /// One field of a row kind (row_kinds.hpp; e.g. "joint_spring", "stiffness"), (k|1, nv), as
  /// Simulation::set_row_parameters with the dof's other fields as they are.
  void set_row_parameter(std::string_view kind, std::string_view field,
                         std::span<const int> env_ids, const RowMatrix& values);
  /// Mass (k values or one) of `link`; scale_inertia: its inertia about the centre of mass scales
  /// with the mass (Isaac Lab's mass randomisation), else it stays.
  void set_link_mass(std::span<const int> env_ids, int link, const VecX& mass,
                     bool scale_inertia = true);
  void set_link_com(std::span<const int> env_ids, int link, const RowMatrix& com);  ///< (k|1, 3)
  /// Gravity (k|1, 3) [m/s^2], each finite (the lanes take it per environment).
  void set_gravity(std::span<const int> env_ids, const RowMatrix& gravity);
  /// The most samples of drive delay history (delay + 1 per delayed dof, 16 bytes each) a batch
  /// holds over all its environments: 2^26, 1 GiB.
  static constexpr long long kMaxDelaySamples = 1LL << 26;
  /// Drive delays in steps (whole numbers), as Simulation::set_drive_delay, each checked against
  /// its environment's drives; the environments' delay histories start over. All or nothing:
  /// std::invalid_argument (nothing changed) for a delay refused or more than kMaxDelaySamples in
  /// all; every history is allocated before any environment changes.
  void set_drive_delay(std::span<const int> env_ids, const RowMatrix& delay);
  // The same read back, (N, nv) / (N,) / (N, 3) copies.
  RowMatrix stiffness() const;
  RowMatrix damping() const;
  RowMatrix target_position() const;
  RowMatrix target_velocity() const;
  RowMatrix armature() const;
  RowMatrix lower_limit() const;
  RowMatrix upper_limit() const;
  RowMatrix static_friction() const;
  RowMatrix dynamic_friction() const;
  RowMatrix viscous_friction() const;
  RowMatrix max_joint_velocity() const;
  RowMatrix row_parameter(std::string_view kind, std::string_view field) const;
  RowMatrix drive_delay() const;
  VecX link_mass(int link) const;
  RowMatrix link_com(int link) const;
  RowMatrix gravity() const;

  /// The fields side by side, (N, sum of their widths), in the order given.
  RowMatrix observe(std::span<const Observation> fields) const;
  /// World position of `point` (link coordinates) on `link` in every environment, (N, 3), by
  /// forward kinematics of each environment's q, on num_threads() threads.
  RowMatrix frame_positions(int link, const Vec3& point) const;
  // Dynamics queries of every environment at its own q (and qd) with its own model, on
  // num_threads() threads, one row per environment; each row is the Simulation's query, bits
  // unchanged, whatever the threads.
  /// The pose of `link`: (N, 12), each row R (3 x 3, row-major) then p.
  RowMatrix link_poses(int link) const;
  /// frame_jacobian of `point` on `link` in `frame`: (N, 6 nv), each row J (6 x nv, row-major).
  RowMatrix frame_jacobians(int link, const Vec3& point, ReferenceFrame frame) const;
  /// crba's M(q), armature included: (N, nv nv), each row M (row-major).
  RowMatrix mass_matrices() const;
  /// nonlinear_effects' b(q, qd): (N, nv).
  RowMatrix bias_forces() const;

  /// Steps every environment `count` times (>= 0), in parallel. One that diverges stops at the
  /// step that diverged with the state it had before that step (as Simulation::step does); every
  /// other one still makes all its steps. Then throws DivergenceError naming the lowest diverged
  /// one, its message and how many diverged; step_count() of each tells how far it got.
  void step(int count = 1);
  /// Per environment: why it stopped in the last step() (none: it made all its steps there);
  /// reset() clears it.
  const std::vector<std::optional<BatchDivergence>>& divergences() const { return divergences_; }

 private:
  void lend_rows();
  std::vector<int> check_env_ids(std::span<const int> env_ids) const;
  template <class F>
  void parallel(int n, int grain, F f) const;
  template <class F>
  RowMatrix per_environment(Eigen::Index cols, F row_of) const;
  template <class Check, class Set>
  void set_rows(std::span<const int> env_ids, const RowMatrix& values, Eigen::Index cols,
                const char* what, Check check, Set set);
  template <class Check, class Apply, class Same>
  void set_per_dof(const std::vector<int>& envs, std::initializer_list<const RowMatrix*> values,
                   const char* what, Check check, Apply apply, Same same);
  template <class Make>
  void vary_models(const std::vector<int>& envs, bool broadcast, Make make);
  // The lanes: what of each environment to pack again before the next step (what a setter
  // changed), and the step through them.
  enum Repack : unsigned char { repack_drives = 1, repack_joints = 2, repack_model = 4, repack_all = 7 };
  void mark(const std::vector<int>& envs, unsigned char what);
  void mark_all(unsigned char what);
  std::string lanes_off() const;  ///< why no environment steps in lanes; empty: some may
  bool prepare_lanes();           ///< (re)groups and packs what changed; false: no lane group
  void step_lanes(int count);
  void lane_control_stages(bool actuated);  ///< actuated: the lanes read lane_tau_
  // The step guard on the lanes' step (lane_guard.cpp): each guarded environment's start kept,
  // then its guard run on the lanes' end: kept, or redone by its own scalar step.
  void lane_guard_start();
  void lane_guard_finish(RowMatrix* drive_change);
  bool lane_guard_redone(int i) const { return guard_redone_[static_cast<size_t>(i)] != 0; }

  std::vector<Simulation> sims_;
  std::array<RowMatrix, StateStorage::kFields> rows_;
  VecX initial_q_;
  int threads_ = 0;
  bool lanes_allowed_ = true;
  std::optional<SimdIsa> isa_;  // set_isa's; none: simd::lane_isa(size())
  std::vector<std::optional<BatchDivergence>> divergences_;
  std::shared_ptr<simd::LaneGroups> lanes_;  // made at the first step through lanes
  std::vector<unsigned char> repack_;        // per environment, Repack bits
  std::vector<char> handed_out_;             // sim(i) handed out writable: looked at every step
  std::vector<std::exception_ptr> failed_;   // per environment: a scalar step's other exception
  std::vector<long> lane_steps_;             // the environments' clocks during a lane step
  std::vector<double> lane_time_;
  RowMatrix lane_tau_;  // the joint force of each environment's lane step (control stages)
  RowMatrix lane_actuator_force_;  // the implicit actuators' forces of a lane step
  RowMatrix lane_drive_change_;    // the drive impulses' change in the last iteration (tracking)
  RowMatrix lane_guard_rows_;      // the rows the guard reads (simd::GuardField), per environment
  std::vector<char> guard_live_, guard_redone_;  // per environment: guarded this step; redone
  std::vector<long> guard_steps_;    // the guarded environments' clocks at the step's start
  std::vector<double> guard_time_;
};

}  // namespace featherdrive
