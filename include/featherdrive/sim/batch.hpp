// N copies of one Model stepped together on all cores (TBB): independent Simulation objects that
// share the Model and nothing else, so each copy's result is bit-identical to stepping it alone,
// whatever the number of threads. Also whole-vector drive setters for one Simulation.
#pragma once

#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "featherdrive/sim/simulation.hpp"

namespace featherdrive {

/// One row per copy: (N, nq) or (N, nv), row-major like numpy's default.
using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// Sets the target position and velocity of every dof (nv each). Throws std::invalid_argument
/// naming the vector and the size or the joint and value; on a throw nothing changed.
void set_drive_targets(Simulation& sim, const VecX& positions, const VecX& velocities);

/// Sets the stiffness and damping of every dof (nv each), keeping max_force, max_impulse and the
/// targets. Dofs of revolute and prismatic joints get `type`; dofs of other joints (spherical,
/// floating) take no drive and must be given 0 gains. Throws std::invalid_argument naming the
/// vector, the joint and the value; on a throw nothing changed.
void set_drive_gains(Simulation& sim, const VecX& stiffness, const VecX& damping,
                     DriveType type = DriveType::force);

class Batch {
 public:
  /// `count` (>= 1) copies of a new Simulation of `model` with `options`.
  Batch(std::shared_ptr<const Model> model, int count, const SimulationOptions& options = {});
  /// `count` (>= 1) copies of `prototype`: state, drives, limits and all other settings.
  Batch(const Simulation& prototype, int count);

  int size() const { return static_cast<int>(sims_.size()); }
  const Model& model() const { return sims_.front().model(); }
  const std::shared_ptr<const Model>& model_ptr() const { return sims_.front().model_ptr(); }

  /// Copy i, for any per-copy setting; throws std::invalid_argument for i out of [0, size()).
  Simulation& sim(int i);
  const Simulation& sim(int i) const;

  /// The most threads set_num_threads accepts.
  static constexpr int kMaxThreads = 4096;
  /// Threads step() uses: 0 = all cores (the default), 1 = serial on the calling thread; throws
  /// std::invalid_argument outside [0, kMaxThreads].
  void set_num_threads(int threads);
  int num_threads() const { return threads_; }
  /// The threads step() will use (num_threads(), or the number of cores for 0).
  int effective_num_threads() const;

  /// Sets every copy's options.
  void set_options(const SimulationOptions& options);

  // States and outputs as (N, nq) / (N, nv) copies.
  RowMatrix q() const;
  RowMatrix qd() const;
  RowMatrix drive_force() const;
  RowMatrix limit_force() const;
  RowMatrix friction_force() const;
  RowMatrix velocity_limit_force() const;
  void set_q(const RowMatrix& q);    ///< (N, nq); quaternions are normalised
  void set_qd(const RowMatrix& qd);  ///< (N, nv)
  void set_applied_force(const RowMatrix& tau);  ///< (N, nv)

  /// Per-copy targets and gains, (N, nv) each, as set_drive_targets / set_drive_gains do for one
  /// copy. Everything is checked before anything changes.
  void set_drive_targets(const RowMatrix& positions, const RowMatrix& velocities);
  void set_drive_gains(const RowMatrix& stiffness, const RowMatrix& damping,
                       DriveType type = DriveType::force);
  /// The same drive on one joint of every copy.
  void set_drive(const std::string& joint, const Drive& drive);

  /// Steps every copy `count` times (>= 0), copies in parallel. A copy that diverges stops at the
  /// step that diverged with the state it had before that step (as Simulation::step does); every
  /// other copy still makes all its steps. Then throws DivergenceError naming the lowest diverged
  /// copy, its message and how many copies diverged; step_count() of each copy tells how far it got.
  void step(int count = 1);

 private:
  RowMatrix gather(const VecX& (Simulation::*get)() const, Eigen::Index cols) const;
  void check_rows(const RowMatrix& m, Eigen::Index cols, const char* what) const;

  std::vector<Simulation> sims_;
  int threads_ = 0;
};

}  // namespace featherdrive
