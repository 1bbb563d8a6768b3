#include "featherdrive/sim/batch.hpp"

#include <cmath>
#include <exception>
#include <sstream>
#include <string>

#include <tbb/blocked_range.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

namespace featherdrive {
namespace {

void check_size(const VecX& x, int expected, const char* function, const char* what) {
  if (x.size() != expected)
    throw std::invalid_argument(std::string(function) + ": " + what + " has " +
                                std::to_string(x.size()) + " values, expected nv = " +
                                std::to_string(expected));
}

bool drivable(const Model& model, int dof) {
  const JointType type = model.links[model.dof_link[dof]].joint_type;
  return type == JointType::revolute || type == JointType::prismatic;
}

/// The drives set_drive_targets would set; throws before anything changes.
std::vector<Drive> drives_with_targets(const Simulation& sim, const VecX& positions,
                                       const VecX& velocities) {
  const Model& model = sim.model();
  check_size(positions, model.nv, "set_drive_targets", "positions");
  check_size(velocities, model.nv, "set_drive_targets", "velocities");
  try {
    sim.check_targets_have_drives(positions, velocities);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("set_drive_targets: ") + e.what());
  }
  std::vector<Drive> drives(static_cast<size_t>(model.nv));
  for (int d = 0; d < model.nv; ++d) {
    Drive drive = sim.drive(d);
    drive.target_position = positions[d];
    drive.target_velocity = velocities[d];
    try {
      validate_drive(drive, model.links[model.dof_link[d]].joint_name);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("set_drive_targets: dof " + std::to_string(d) + ": " + e.what());
    }
    drives[static_cast<size_t>(d)] = drive;
  }
  return drives;
}

std::vector<Drive> drives_with_gains(const Simulation& sim, const VecX& stiffness,
                                     const VecX& damping, DriveType type) {
  const Model& model = sim.model();
  check_size(stiffness, model.nv, "set_drive_gains", "stiffness");
  check_size(damping, model.nv, "set_drive_gains", "damping");
  std::vector<Drive> drives(static_cast<size_t>(model.nv));
  for (int d = 0; d < model.nv; ++d) {
    const Link& link = model.links[model.dof_link[d]];
    Drive drive = sim.drive(d);
    drive.stiffness = stiffness[d];
    drive.damping = damping[d];
    if (drivable(model, d)) {
      drive.type = type;
    } else if (stiffness[d] != 0.0 || damping[d] != 0.0) {
      throw std::invalid_argument("set_drive_gains: dof " + std::to_string(d) + " of joint '" +
                                  link.joint_name + "' is " + to_string(link.joint_type) +
                                  ": drives act on revolute and prismatic joints only, so its "
                                  "stiffness and damping must be 0");
    }
    try {
      validate_drive(drive, link.joint_name);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("set_drive_gains: dof " + std::to_string(d) + ": " + e.what());
    }
    drives[static_cast<size_t>(d)] = drive;
  }
  return drives;
}

void apply_drives(Simulation& sim, const std::vector<Drive>& drives) {
  for (size_t d = 0; d < drives.size(); ++d) sim.set_drive(static_cast<int>(d), drives[d]);
}

}  // namespace

void set_drive_targets(Simulation& sim, const VecX& positions, const VecX& velocities) {
  apply_drives(sim, drives_with_targets(sim, positions, velocities));
}

void set_drive_gains(Simulation& sim, const VecX& stiffness, const VecX& damping, DriveType type) {
  apply_drives(sim, drives_with_gains(sim, stiffness, damping, type));
}

Batch::Batch(std::shared_ptr<const Model> model, int count, const SimulationOptions& options)
    : Batch(Simulation(std::move(model), options), count) {}

Batch::Batch(const Simulation& prototype, int count) {
  if (count < 1)
    throw std::invalid_argument("Batch: count = " + std::to_string(count) + " must be >= 1");
  sims_.assign(static_cast<size_t>(count), prototype);
}

Simulation& Batch::sim(int i) {
  if (i < 0 || i >= size())
    throw std::invalid_argument("Batch: copy index " + std::to_string(i) + " is out of range [0, " +
                                std::to_string(size()) + ")");
  return sims_[static_cast<size_t>(i)];
}

const Simulation& Batch::sim(int i) const { return const_cast<Batch*>(this)->sim(i); }

void Batch::set_num_threads(int threads) {
  // TBB's arena crashes for some hundred thousand threads; no machine needs more than this.
  if (threads < 0 || threads > kMaxThreads)
    throw std::invalid_argument("Batch: num_threads = " + std::to_string(threads) +
                                " must be in [0, " + std::to_string(kMaxThreads) +
                                "] (0 = all cores)");
  threads_ = threads;
}

int Batch::effective_num_threads() const {
  return threads_ > 0 ? threads_ : tbb::info::default_concurrency();
}

void Batch::set_options(const SimulationOptions& options) {
  validate_options(options);
  for (Simulation& s : sims_) s.set_options(options);
}

RowMatrix Batch::gather(const VecX& (Simulation::*get)() const, Eigen::Index cols) const {
  RowMatrix m(size(), cols);
  for (int i = 0; i < size(); ++i) m.row(i) = (sims_[static_cast<size_t>(i)].*get)().transpose();
  return m;
}

RowMatrix Batch::q() const { return gather(&Simulation::q, model().nq); }
RowMatrix Batch::qd() const { return gather(&Simulation::qd, model().nv); }
RowMatrix Batch::drive_force() const { return gather(&Simulation::drive_force, model().nv); }
RowMatrix Batch::limit_force() const { return gather(&Simulation::limit_force, model().nv); }
RowMatrix Batch::friction_force() const { return gather(&Simulation::friction_force, model().nv); }
RowMatrix Batch::velocity_limit_force() const {
  return gather(&Simulation::velocity_limit_force, model().nv);
}

void Batch::check_rows(const RowMatrix& m, Eigen::Index cols, const char* what) const {
  if (m.rows() != size() || m.cols() != cols)
    throw std::invalid_argument(std::string("Batch: ") + what + " has shape (" +
                                std::to_string(m.rows()) + ", " + std::to_string(m.cols()) +
                                "), expected (" + std::to_string(size()) + ", " +
                                std::to_string(cols) + ")");
}

namespace {

/// Runs set(copy i, row i) for every copy after a dry run of check(copy i, row i) for every copy,
/// so that a bad row changes nothing.
template <class Check, class Set>
void per_copy(std::vector<Simulation>& sims, Check check, Set set) {
  for (size_t i = 0; i < sims.size(); ++i) {
    try {
      check(sims[i], static_cast<Eigen::Index>(i));
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("Batch: copy " + std::to_string(i) + ": " + e.what());
    }
  }
  for (size_t i = 0; i < sims.size(); ++i) set(sims[i], static_cast<Eigen::Index>(i));
}

}  // namespace

namespace {

void check_finite(const RowMatrix& m, const char* what) {
  for (Eigen::Index i = 0; i < m.rows(); ++i)
    for (Eigen::Index j = 0; j < m.cols(); ++j)
      if (!std::isfinite(m(i, j))) {
        std::ostringstream s;
        s << "Batch: " << what << "[" << i << ", " << j << "] = " << m(i, j) << " is not finite";
        throw std::invalid_argument(s.str());
      }
}

}  // namespace

void Batch::set_q(const RowMatrix& q) {
  check_rows(q, model().nq, "q");
  check_finite(q, "q");
  for (size_t i = 0; i < sims_.size(); ++i) sims_[i].set_q(q.row(static_cast<Eigen::Index>(i)).transpose());
}

void Batch::set_qd(const RowMatrix& qd) {
  check_rows(qd, model().nv, "qd");
  check_finite(qd, "qd");
  for (size_t i = 0; i < sims_.size(); ++i) sims_[i].set_qd(qd.row(static_cast<Eigen::Index>(i)).transpose());
}

void Batch::set_applied_force(const RowMatrix& tau) {
  check_rows(tau, model().nv, "applied_force");
  check_finite(tau, "applied_force");
  for (size_t i = 0; i < sims_.size(); ++i)
    sims_[i].set_applied_force(tau.row(static_cast<Eigen::Index>(i)).transpose());
}

void Batch::set_drive_targets(const RowMatrix& positions, const RowMatrix& velocities) {
  check_rows(positions, model().nv, "positions");
  check_rows(velocities, model().nv, "velocities");
  std::vector<std::vector<Drive>> drives(sims_.size());
  per_copy(sims_, [&](Simulation& s, Eigen::Index i) {
    drives[static_cast<size_t>(i)] = drives_with_targets(s, positions.row(i).transpose(), velocities.row(i).transpose());
  }, [&](Simulation& s, Eigen::Index i) { apply_drives(s, drives[static_cast<size_t>(i)]); });
}

void Batch::set_drive_gains(const RowMatrix& stiffness, const RowMatrix& damping, DriveType type) {
  check_rows(stiffness, model().nv, "stiffness");
  check_rows(damping, model().nv, "damping");
  std::vector<std::vector<Drive>> drives(sims_.size());
  per_copy(sims_, [&](Simulation& s, Eigen::Index i) {
    drives[static_cast<size_t>(i)] = drives_with_gains(s, stiffness.row(i).transpose(), damping.row(i).transpose(), type);
  }, [&](Simulation& s, Eigen::Index i) { apply_drives(s, drives[static_cast<size_t>(i)]); });
}

void Batch::set_drive(const std::string& joint, const Drive& drive) {
  // The check on copy 0 is the check for all: the joint and the drive are the same for every copy.
  sims_.front().set_drive(joint, drive);
  for (Simulation& s : sims_) s.set_drive(joint, drive);
}

void Batch::step(int count) {
  if (count < 0)
    throw std::invalid_argument("step count = " + std::to_string(count) + " must be >= 0");
  const int n = size();
  // One slot per copy: copies never share anything a step writes.
  std::vector<std::string> diverged(static_cast<size_t>(n));
  std::vector<std::exception_ptr> failed(static_cast<size_t>(n));
  auto run = [&](int i) {
    try {
      sims_[static_cast<size_t>(i)].step(count);
    } catch (const DivergenceError& e) {
      diverged[static_cast<size_t>(i)] = e.what();
    } catch (...) {
      failed[static_cast<size_t>(i)] = std::current_exception();
    }
  };
  const int threads = effective_num_threads();
  if (threads <= 1 || n == 1) {
    for (int i = 0; i < n; ++i) run(i);
  } else {
    tbb::task_arena arena(threads);
    arena.execute([&] {
      tbb::parallel_for(tbb::blocked_range<int>(0, n, 1), [&](const tbb::blocked_range<int>& r) {
        for (int i = r.begin(); i < r.end(); ++i) run(i);
      });
    });
  }
  for (const std::exception_ptr& e : failed)
    if (e) std::rethrow_exception(e);
  int first = -1, count_diverged = 0;
  for (int i = 0; i < n; ++i)
    if (!diverged[static_cast<size_t>(i)].empty()) {
      if (first < 0) first = i;
      ++count_diverged;
    }
  if (first >= 0)
    throw DivergenceError("batch copy " + std::to_string(first) + " (" +
                          std::to_string(count_diverged) + " of " + std::to_string(n) +
                          " copies diverged): " + diverged[static_cast<size_t>(first)]);
}

}  // namespace featherdrive
