// N environments of one fixed-base robot of revolute and prismatic joints, stepped W at a time in
// SIMD lanes (one environment per lane; W = 2 with SSE2, 4 with AVX2, 8 with AVX-512, chosen at
// run time from the CPU), blocks of lanes on TBB's threads. Every lane does the same operations,
// so an environment's bits depend neither on its lane, the batch size, the width nor the thread
// count. Settings come from a Simulation prototype; each environment may have its own drive gains,
// targets, joint limits, joint friction, armature and link inertias. docs/simd_batch.md.
#pragma once

#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "featherdrive/sim/batch.hpp"
#include "featherdrive/sim/simd_isa.hpp"

namespace featherdrive {

/// Where and why an environment stopped: the step (1-based, its step_count + 1), the joint, the
/// quantity and its value, in Simulation's DivergenceError message.
struct SimdDivergence {
  long step = 0;
  std::string message;
};

class SimdBatch {
 public:
  /// `count` in [1, Batch::kMaxSize] copies of `prototype`: state, drives, limits, options,
  /// model (std::invalid_argument outside; the padding to whole blocks stays within int). Throws
  /// std::invalid_argument with one line naming the setting and the joint (or link) for what the
  /// SIMD step does not simulate: joints other than fixed, revolute and prismatic, compat physx,
  /// explicit actuators, drive delays, mimic rows and contacts. Joint velocity limits
  /// (max_velocity), friction coefficients, actuator envelopes and link parameters (cfm, link
  /// damping, link velocity limits) are simulated as Simulation does.
  /// Without isa, default_simd_isa(), narrowed (when FEATHERDRIVE_SIMD is not set) while a block
  /// of 2 W lanes would exceed count.
  SimdBatch(const Simulation& prototype, int count, std::optional<SimdIsa> isa = std::nullopt);
  ~SimdBatch();
  SimdBatch(const SimdBatch&) = delete;
  SimdBatch& operator=(const SimdBatch&) = delete;

  int size() const { return count_; }
  const Model& model() const { return *model_; }
  const std::shared_ptr<const Model>& model_ptr() const { return model_; }
  const SimulationOptions& options() const { return options_; }
  SimdIsa isa() const { return isa_; }
  int width() const { return simd_width(isa_); }
  /// Another instruction set the CPU has (throws std::invalid_argument otherwise).
  void set_isa(SimdIsa isa);

  /// Threads as Batch: 0 = all cores (the default), 1 = serial; std::invalid_argument outside
  /// [0, Batch::kMaxThreads].
  void set_num_threads(int threads);
  int num_threads() const { return threads_; }
  int effective_num_threads() const;

  // States and outputs, (N, nq) / (N, nv), row-major.
  const RowMatrix& q() const { return q_; }
  const RowMatrix& qd() const { return qd_; }
  const RowMatrix& applied_force() const { return applied_force_; }
  const RowMatrix& drive_force() const { return drive_force_; }
  const RowMatrix& limit_force() const { return limit_force_; }
  const RowMatrix& friction_force() const { return friction_force_; }
  const RowMatrix& velocity_limit_force() const { return velocity_limit_force_; }
  const std::vector<long>& step_count() const { return step_count_; }
  const std::vector<double>& time() const { return time_; }

  // Setters as Batch's, for the environments env_ids (distinct, in [0, size()); none when empty):
  // one row per environment named or one row for all. Each row is checked before anything
  // changes.
  void set_q(std::span<const int> env_ids, const RowMatrix& q);
  void set_qd(std::span<const int> env_ids, const RowMatrix& qd);
  void set_applied_force(std::span<const int> env_ids, const RowMatrix& tau);
  /// Targets of driven dofs (a dof without a drive takes 0).
  void set_drive_targets(std::span<const int> env_ids, const RowMatrix& positions,
                         const RowMatrix& velocities);
  /// Gains of every revolute and prismatic dof, of drive type `type`; max_force stays.
  void set_drive_gains(std::span<const int> env_ids, const RowMatrix& stiffness,
                       const RowMatrix& damping, DriveType type = DriveType::force);
  /// Lower <= upper, not NaN; +-inf for none.
  void set_joint_limits(std::span<const int> env_ids, const RowMatrix& lower,
                        const RowMatrix& upper);
  /// As Simulation::set_joint_friction, per dof (static, dynamic, viscous).
  void set_joint_friction(std::span<const int> env_ids, const RowMatrix& static_effort,
                          const RowMatrix& dynamic_effort, const RowMatrix& viscous);
  void set_armature(std::span<const int> env_ids, const RowMatrix& armature);
  /// As Batch::set_link_mass / set_link_com.
  void set_link_mass(std::span<const int> env_ids, int link, const VecX& mass,
                     bool scale_inertia = true);
  void set_link_com(std::span<const int> env_ids, int link, const RowMatrix& com);
  /// As Batch::reset: q (default initial_q()), qd (default 0), applied force, outputs and clock
  /// 0; a stopped (diverged) environment steps again.
  void reset(std::span<const int> env_ids, const std::optional<RowMatrix>& q = std::nullopt,
             const std::optional<RowMatrix>& qd = std::nullopt);
  const VecX& initial_q() const { return initial_q_; }

  // Per-environment parameters read back, (N, nv) / (N,) / (N, 3).
  RowMatrix stiffness() const;
  RowMatrix damping() const;
  RowMatrix target_position() const;
  RowMatrix target_velocity() const;
  RowMatrix lower_limit() const;
  RowMatrix upper_limit() const;
  RowMatrix armature() const;
  RowMatrix static_friction() const;
  RowMatrix dynamic_friction() const;
  RowMatrix viscous_friction() const;
  VecX link_mass(int link) const;
  RowMatrix link_com(int link) const;

  /// Environment i as a Simulation of its own (a copy: its model, settings and state), for
  /// comparing with the scalar step.
  Simulation simulation(int i) const;

  /// Steps every environment `count` times (>= 0). One that diverges stops at that step with the
  /// state before it, its divergence recorded; the others make all their steps. Then throws
  /// DivergenceError naming the lowest environment stopped in this call and how many stopped.
  void step(int count = 1);
  /// Per environment: why it stopped, if it did (cleared by reset).
  const std::vector<std::optional<SimdDivergence>>& divergences() const { return diverged_; }

  /// Entry `index` of environment env's packed parameters (simd_plan.hpp).
  double parameter(int env, int index) const;
  struct Impl;  // the packed parameters and the lane kernels (src/sim/simd_batch.cpp)

 private:
  std::vector<int> envs(std::span<const int> env_ids) const;
  void set_dof_parameter(std::span<const int> env_ids, const RowMatrix& values, int field,
                         const char* what);
  void set_parameter(int env, int index, double value);
  RowMatrix dof_parameter(int field) const;
  void set_link_com_or_mass(std::span<const int> env_ids, int link, const VecX* mass,
                            const RowMatrix* com, bool scale_inertia);

  std::shared_ptr<const Model> model_;
  SimulationOptions options_;
  int count_ = 0;
  SimdIsa isa_ = SimdIsa::sse2;
  int threads_ = 0;
  RowMatrix q_, qd_, applied_force_, drive_force_, limit_force_, friction_force_,
      velocity_limit_force_;
  std::vector<long> step_count_;
  std::vector<double> time_;
  std::vector<std::optional<SimdDivergence>> diverged_;
  VecX initial_q_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace featherdrive
