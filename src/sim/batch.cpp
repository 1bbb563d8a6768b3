#include "featherdrive/sim/batch.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <map>
#include <string>
#include <utility>

#include <tbb/blocked_range.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "featherdrive/algorithm/crba.hpp"
#include "featherdrive/algorithm/frame_kinematics.hpp"
#include "featherdrive/algorithm/jacobian.hpp"
#include "featherdrive/algorithm/kinematics.hpp"
#include "featherdrive/algorithm/rnea.hpp"
#include "featherdrive/core/format.hpp"
#include "featherdrive/model/model_variant.hpp"
#include "featherdrive/sim/state.hpp"
#include "lane_engine.hpp"
#include "workspace.hpp"

namespace featherdrive {
namespace {

void check_size(const VecX& x, int expected, const char* function, const char* what) {
  if (x.size() != expected)
    throw std::invalid_argument(std::string(function) + ": " + what + " has " +
                                std::to_string(x.size()) + " values, expected nv = " +
                                std::to_string(expected));
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
    if (dof_has_rows(model, d)) {
      drive.type = type;
      // Refused here, before anything changes, rather than half-way by set_drive.
      if (type != DriveType::none && sim.has_actuator(d))
        throw std::invalid_argument("set_drive_gains: dof " + std::to_string(d) + " of joint '" +
                                    link.joint_name + "' has an explicit actuator: clear it "
                                    "before giving the dof a " + to_string(type) + " drive");
    } else if (stiffness[d] != 0.0 || damping[d] != 0.0) {
      throw std::invalid_argument("set_drive_gains: dof " + std::to_string(d) + " of joint '" +
                                  link.joint_name + "' is " + to_string(link.joint_type) +
                                  ": drives act on revolute, prismatic and spherical joints "
                                  "only, so its stiffness and damping must be 0");
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

namespace {

/// Row j of values given per environment, or their one row for all.
auto row_of(const RowMatrix& m, size_t j) {
  return m.row(m.rows() == 1 ? 0 : static_cast<Eigen::Index>(j));
}

/// Throws unless m is (k, cols) or (1, cols).
void check_values(const RowMatrix& m, size_t k, Eigen::Index cols, const std::string& what) {
  if (m.cols() == cols && (m.rows() == 1 || m.rows() == static_cast<Eigen::Index>(k))) return;
  throw std::invalid_argument("Batch: " + what + " has shape (" + std::to_string(m.rows()) + ", " +
                              std::to_string(m.cols()) + "), expected (" + std::to_string(k) +
                              ", " + std::to_string(cols) + ") for " + std::to_string(k) +
                              " environments, or (1, " + std::to_string(cols) + ") for all");
}

[[noreturn]] void rethrow_for(int env, const std::exception& e) {
  throw std::invalid_argument("Batch: environment " + std::to_string(env) + ": " + e.what());
}

std::vector<int> every(int n) {
  std::vector<int> ids(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) ids[static_cast<size_t>(i)] = i;
  return ids;
}

/// The drives make(sim, j) of every environment envs[j], all made (and checked) before any is set.
template <class Make>
void set_drives(std::vector<Simulation>& sims, const std::vector<int>& envs, Make make) {
  std::vector<std::vector<Drive>> drives(envs.size());
  for (size_t j = 0; j < envs.size(); ++j) {
    try {
      drives[j] = make(sims[static_cast<size_t>(envs[j])], j);
    } catch (const std::invalid_argument& e) {
      rethrow_for(envs[j], e);
    }
  }
  for (size_t j = 0; j < envs.size(); ++j)
    apply_drives(sims[static_cast<size_t>(envs[j])], drives[j]);
}

/// (N, nv) of value(sim, dof) over every environment.
template <class F>
RowMatrix per_dof_matrix(const std::vector<Simulation>& sims, F value) {
  const int nv = sims.front().model().nv;
  RowMatrix m(static_cast<Eigen::Index>(sims.size()), nv);
  for (size_t i = 0; i < sims.size(); ++i)
    for (int d = 0; d < nv; ++d) m(static_cast<Eigen::Index>(i), d) = value(sims[i], d);
  return m;
}

}  // namespace

Batch::Batch(std::shared_ptr<const Model> model, int count, const SimulationOptions& options)
    : Batch(Simulation(std::move(model), options), count) {}

Batch::Batch(std::shared_ptr<const Model> model, int count, const Settings& settings)
    : Batch(Simulation(std::move(model), settings), count) {}

Batch::Batch(const Simulation& prototype, int count) {
  if (count < 1 || count > kMaxSize)
    throw std::invalid_argument("Batch: count = " + std::to_string(count) + " must be in [1, " +
                                std::to_string(kMaxSize) + "]");
  sims_.assign(static_cast<size_t>(count), prototype);
  initial_q_ = prototype.q();
  divergences_.resize(static_cast<size_t>(count));
  lend_rows();
}

Batch::Batch(const Batch& other)
    : sims_(other.sims_),
      initial_q_(other.initial_q_),
      threads_(other.threads_),
      lanes_allowed_(other.lanes_allowed_),
      isa_(other.isa_),
      divergences_(other.divergences_) {
  lend_rows();
}

// Row i of every array becomes environment i's storage (its values copied there).
void Batch::lend_rows() {
  repack_.assign(sims_.size(), repack_all);
  handed_out_.assign(sims_.size(), 0);
  for (int f = 0; f < StateStorage::kFields; ++f)
    rows_[static_cast<size_t>(f)].resize(size(), sims_.front().state_.size(StateStorage::Field(f)));
  for (int i = 0; i < size(); ++i) {
    std::array<double*, StateStorage::kFields> row{};
    for (size_t f = 0; f < row.size(); ++f)
      row[f] = rows_[f].cols() > 0 ? rows_[f].data() + i * rows_[f].cols() : nullptr;
    sims_[static_cast<size_t>(i)].state_.lend(row);
  }
}

Simulation& Batch::sim(int i) {
  if (i < 0 || i >= size())
    throw std::invalid_argument("Batch: environment index " + std::to_string(i) +
                                " is out of range [0, " + std::to_string(size()) + ")");
  // Whatever the caller changes through it, the lanes read again at every step.
  handed_out_[static_cast<size_t>(i)] = 1;
  return sims_[static_cast<size_t>(i)];
}

const Simulation& Batch::sim(int i) const {
  if (i < 0 || i >= size())
    throw std::invalid_argument("Batch: environment index " + std::to_string(i) +
                                " is out of range [0, " + std::to_string(size()) + ")");
  return sims_[static_cast<size_t>(i)];
}

Simulation Batch::simulation(int i) const {
  return sim(i);  // the copy owns its state (StateStorage's copy)
}

void Batch::set_isa(std::optional<SimdIsa> isa) {
  if (isa) check_simd_isa(*isa, "Batch: isa");
  isa_ = isa;
}

SimdIsa Batch::isa() const { return isa_ ? *isa_ : simd::lane_isa(size()); }

std::vector<long> Batch::step_count() const {
  std::vector<long> out(sims_.size());
  for (size_t i = 0; i < sims_.size(); ++i) out[i] = sims_[i].step_count();
  return out;
}

std::vector<double> Batch::time() const {
  std::vector<double> out(sims_.size());
  for (size_t i = 0; i < sims_.size(); ++i) out[i] = sims_[i].time();
  return out;
}

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
  lanes_.reset();  // plans of other options: grouped again
  mark_all(repack_all);
}

std::vector<int> Batch::check_env_ids(std::span<const int> env_ids) const {
  std::vector<int> first(static_cast<size_t>(size()), -1);
  for (size_t j = 0; j < env_ids.size(); ++j) {
    const int i = env_ids[j];
    const std::string entry = "Batch: env_ids[" + std::to_string(j) + "] = " + std::to_string(i);
    if (i < 0 || i >= size())
      throw std::invalid_argument(entry + " is out of range [0, " + std::to_string(size()) + ")");
    if (first[static_cast<size_t>(i)] >= 0)
      throw std::invalid_argument(entry + " appears twice (also env_ids[" +
                                  std::to_string(first[static_cast<size_t>(i)]) + "])");
    first[static_cast<size_t>(i)] = static_cast<int>(j);
  }
  return {env_ids.begin(), env_ids.end()};
}

// set(sim, row) for the environments env_ids, every row checked first (check(row) throws the
// setter's message), so that a bad one throws before anything changes.
template <class Check, class Set>
void Batch::set_rows(std::span<const int> env_ids, const RowMatrix& values, Eigen::Index cols,
                     const char* what, Check check, Set set) {
  const std::vector<int> envs = check_env_ids(env_ids);
  check_values(values, envs.size(), cols, what);
  for (size_t j = 0; j < envs.size(); ++j) {
    try {
      check(row_of(values, j).transpose());
    } catch (const std::invalid_argument& e) {
      rethrow_for(envs[j], e);
    }
  }
  for (size_t j = 0; j < envs.size(); ++j)
    set(sims_[static_cast<size_t>(envs[j])], row_of(values, j).transpose());
}

void Batch::set_q(const RowMatrix& q) { set_q(every(size()), q); }
void Batch::set_q(std::span<const int> env_ids, const RowMatrix& q) {
  set_rows(
      env_ids, q, model().nq, "q", [&](const VecX& v) { checked_configuration(model(), v); },
      [](Simulation& s, const VecX& v) { s.set_q(v); });
}
void Batch::set_qd(const RowMatrix& qd) { set_qd(every(size()), qd); }
void Batch::set_qd(std::span<const int> env_ids, const RowMatrix& qd) {
  set_rows(
      env_ids, qd, model().nv, "qd",
      [&](const VecX& v) { check_state_vector(v, model().nv, "qd"); },
      [](Simulation& s, const VecX& v) { s.set_qd(v); });
}
void Batch::set_applied_force(const RowMatrix& tau) { set_applied_force(every(size()), tau); }
void Batch::set_applied_force(std::span<const int> env_ids, const RowMatrix& tau) {
  set_rows(
      env_ids, tau, model().nv, "applied_force",
      [&](const VecX& v) { check_state_vector(v, model().nv, "applied_force"); },
      [](Simulation& s, const VecX& v) { s.set_applied_force(v); });
}

void Batch::set_drive_targets(const RowMatrix& positions, const RowMatrix& velocities) {
  set_drive_targets(every(size()), positions, velocities);
}
void Batch::set_drive_targets(std::span<const int> env_ids, const RowMatrix& positions,
                              const RowMatrix& velocities) {
  const std::vector<int> envs = check_env_ids(env_ids);
  check_values(positions, envs.size(), model().nv, "positions");
  check_values(velocities, envs.size(), model().nv, "velocities");
  set_drives(sims_, envs, [&](const Simulation& s, size_t j) {
    return drives_with_targets(s, row_of(positions, j).transpose(),
                               row_of(velocities, j).transpose());
  });
  mark(envs, repack_drives);
}

void Batch::set_drive_gains(const RowMatrix& stiffness, const RowMatrix& damping, DriveType type) {
  set_drive_gains(every(size()), stiffness, damping, type);
}
void Batch::set_drive_gains(std::span<const int> env_ids, const RowMatrix& stiffness,
                            const RowMatrix& damping, DriveType type) {
  const std::vector<int> envs = check_env_ids(env_ids);
  check_values(stiffness, envs.size(), model().nv, "stiffness");
  check_values(damping, envs.size(), model().nv, "damping");
  set_drives(sims_, envs, [&](const Simulation& s, size_t j) {
    return drives_with_gains(s, row_of(stiffness, j).transpose(), row_of(damping, j).transpose(),
                             type);
  });
  mark(envs, repack_drives);
}

void Batch::set_drive(const std::string& joint, const Drive& drive) {
  // The check on environment 0 is the check for all: the joint and the drive are the same.
  sims_.front().set_drive(joint, drive);
  for (Simulation& s : sims_) s.set_drive(joint, drive);
  mark_all(repack_drives);
}

void Batch::reset(std::span<const int> env_ids, const std::optional<RowMatrix>& q,
                  const std::optional<RowMatrix>& qd) {
  const std::vector<int> envs = check_env_ids(env_ids);
  if (q) check_values(*q, envs.size(), model().nq, "q");
  if (qd) check_values(*qd, envs.size(), model().nv, "qd");
  for (size_t j = 0; j < envs.size(); ++j) {
    try {
      if (q) checked_configuration(model(), row_of(*q, j).transpose());
      if (qd) check_state_vector(row_of(*qd, j).transpose(), model().nv, "qd");
    } catch (const std::invalid_argument& e) {
      rethrow_for(envs[j], e);
    }
  }
  for (size_t j = 0; j < envs.size(); ++j) {
    const auto i = static_cast<Eigen::Index>(envs[j]);
    // The default q is the prototype's, already normalised: copied, not normalised again.
    if (q) sims_[static_cast<size_t>(i)].set_q(row_of(*q, j).transpose());
    else rows_[StateStorage::q].row(i) = initial_q_.transpose();
    if (qd) rows_[StateStorage::qd].row(i) = row_of(*qd, j);
    else rows_[StateStorage::qd].row(i).setZero();
    for (int f = StateStorage::applied_force; f < StateStorage::kFields; ++f)
      rows_[static_cast<size_t>(f)].row(i).setZero();
    sims_[static_cast<size_t>(i)].set_clock(0.0, 0);
    sims_[static_cast<size_t>(i)].reset_actuator_history();  // as Isaac Lab's delay buffers
    sims_[static_cast<size_t>(i)].reset_drive_delay_history();
    sims_[static_cast<size_t>(i)].ws_->guard_account = {};  // a new episode, a new account
    divergences_[static_cast<size_t>(i)].reset();
    // Contacts start over too: no friction anchors kept from the episode before, no contact
    // outputs. A ground and self-collision switched off forget both; switched on again they are
    // as they were.
    Simulation& s = sims_[static_cast<size_t>(i)];
    if (s.ground().enabled || s.contact_options().self_collision) {
      const Ground ground = s.ground();
      const ContactOptions options = s.contact_options();
      Ground no_ground = ground;
      no_ground.enabled = false;
      ContactOptions no_self = options;
      no_self.self_collision = false;
      s.set_ground(no_ground);
      s.set_contact_options(no_self);
      s.set_ground(ground);
      s.set_contact_options(options);
    }
  }
}

// For every environment envs[j] and dof d: apply(sim, d, x) with x[k] = values[k] at (j, d), on
// dofs of revolute and prismatic joints and spherical axes, every one checked first
// (check(model, d, x): the setter's check, settings.hpp); dofs of other joints take no such
// setting and must be given what they have (same(sim, d, x)).
template <class Check, class Apply, class Same>
void Batch::set_per_dof(const std::vector<int>& envs,
                        std::initializer_list<const RowMatrix*> values, const char* what,
                        Check check, Apply apply, Same same) {
  const Model& model = this->model();
  std::vector<double> x(values.size());
  auto at = [&](size_t j, int d) {
    size_t k = 0;
    for (const RowMatrix* v : values) x[k++] = row_of(*v, j)[d];
    return x.data();
  };
  for (size_t j = 0; j < envs.size(); ++j) {
    const Simulation& sim = sims_[static_cast<size_t>(envs[j])];
    for (int d = 0; d < model.nv; ++d) {
      try {
        if (dof_has_rows(model, d)) {
          check(model, d, at(j, d));
        } else if (!same(sim, d, at(j, d))) {
          const Link& link =
              model.links[static_cast<size_t>(model.dof_link[static_cast<size_t>(d)])];
          throw std::invalid_argument(std::string(what) + ": dof " + std::to_string(d) +
                                      " of joint '" + link.joint_name + "' is " +
                                      to_string(link.joint_type) +
                                      ": it takes no such setting and must be given the value "
                                      "it has, not " + std::to_string(x[0]));
        }
      } catch (const std::invalid_argument& e) {
        rethrow_for(envs[j], e);
      }
    }
  }
  for (size_t j = 0; j < envs.size(); ++j)
    for (int d = 0; d < model.nv; ++d)
      if (dof_has_rows(model, d)) apply(sims_[static_cast<size_t>(envs[j])], d, at(j, d));
  mark(envs, repack_joints);
}

void Batch::set_joint_limits(std::span<const int> env_ids, const RowMatrix& lower,
                             const RowMatrix& upper) {
  const std::vector<int> envs = check_env_ids(env_ids);
  check_values(lower, envs.size(), model().nv, "lower");
  check_values(upper, envs.size(), model().nv, "upper");
  set_per_dof(
      envs, {&lower, &upper}, "joint limits",
      [](const Model& m, int d, const double* x) { check_joint_limits(m, d, x[0], x[1]); },
      [](Simulation& s, int d, const double* x) { s.set_joint_limits(d, x[0], x[1]); },
      [](const Simulation& s, int d, const double* x) {
        return x[0] == s.lower_limit(d) && x[1] == s.upper_limit(d);
      });
}

void Batch::set_joint_friction(std::span<const int> env_ids, const RowMatrix& static_effort,
                               const RowMatrix& dynamic_effort, const RowMatrix& viscous) {
  const std::vector<int> envs = check_env_ids(env_ids);
  check_values(static_effort, envs.size(), model().nv, "static friction");
  check_values(dynamic_effort, envs.size(), model().nv, "dynamic friction");
  check_values(viscous, envs.size(), model().nv, "viscous friction");
  set_per_dof(
      envs, {&static_effort, &dynamic_effort, &viscous}, "joint friction",
      [](const Model& m, int d, const double* x) {
        check_joint_friction(m, d, JointFriction{x[0], x[1], x[2]});
      },
      [](Simulation& s, int d, const double* x) {
        s.set_joint_friction(d, JointFriction{x[0], x[1], x[2]});
      },
      [](const Simulation& s, int d, const double* x) {
        const JointFriction& f = s.joint_friction(d);
        return x[0] == f.static_effort && x[1] == f.dynamic_effort && x[2] == f.viscous;
      });
}

void Batch::set_max_joint_velocity(std::span<const int> env_ids, const RowMatrix& max_velocity) {
  const std::vector<int> envs = check_env_ids(env_ids);
  check_values(max_velocity, envs.size(), model().nv, "max joint velocity");
  set_per_dof(
      envs, {&max_velocity}, "max joint velocity",
      [](const Model& m, int d, const double* x) { check_max_joint_velocity(m, d, x[0]); },
      [](Simulation& s, int d, const double* x) { s.set_max_joint_velocity(d, x[0]); },
      [](const Simulation& s, int d, const double* x) { return x[0] == s.max_joint_velocity(d); });
}

void Batch::set_row_parameter(std::string_view kind, std::string_view field,
                              std::span<const int> env_ids, const RowMatrix& values) {
  const RowKindInfo& k = row_kind(kind);
  const int column = row_field_column(k, field);
  const std::vector<int> envs = check_env_ids(env_ids);
  const std::string what = std::string(kind) + "." + std::string(field);
  check_values(values, envs.size(), model().nv, what.c_str());
  // The dof's fields with this one replaced: what the setter and its check see.
  auto fields = [&](const Simulation& s, int d, double x) {
    std::vector<double> v(k.fields.size());
    for (size_t j = 0; j < v.size(); ++j)
      v[j] = s.settings().row_parameters(d, k.offset + static_cast<Eigen::Index>(j));
    v[static_cast<size_t>(column - k.offset)] = x;
    return v;
  };
  // Checked against each environment's own other fields.
  for (size_t j = 0; j < envs.size(); ++j) {
    const Simulation& sim = sims_[static_cast<size_t>(envs[j])];
    for (int d = 0; d < model().nv; ++d) {
      const double x = row_of(values, j)[d];
      try {
        if (dof_has_rows(model(), d)) check_row_parameters(model(), d, k, fields(sim, d, x));
        else if (!(x == sim.settings().row_parameters(d, column)))
          throw std::invalid_argument(what + ": dof " + std::to_string(d) + " of joint '" +
                                      model().links[model().dof_link[d]].joint_name +
                                      "' takes no such setting and must be given the value it "
                                      "has, not " + format_double(x));
      } catch (const std::invalid_argument& e) {
        rethrow_for(envs[j], e);
      }
    }
  }
  for (size_t j = 0; j < envs.size(); ++j) {
    Simulation& sim = sims_[static_cast<size_t>(envs[j])];
    for (int d = 0; d < model().nv; ++d)
      if (dof_has_rows(model(), d)) sim.set_row_parameters(kind, d, fields(sim, d, row_of(values, j)[d]));
  }
  mark(envs, repack_joints);
}

RowMatrix Batch::row_parameter(std::string_view kind, std::string_view field) const {
  const int column = row_field_column(row_kind(kind), field);
  return per_dof_matrix(sims_, [&](const Simulation& s, int d) {
    return s.settings().row_parameters(d, column);
  });
}

RowMatrix Batch::row_force(std::string_view kind) const {
  const int nv = model().nv;
  return rows_[StateStorage::row_force].middleCols(row_kind(kind).index * nv, nv);
}

void Batch::set_drive_delay(std::span<const int> env_ids, const RowMatrix& delay) {
  const std::vector<int> envs = check_env_ids(env_ids);
  check_values(delay, envs.size(), model().nv, "drive delay");
  const int nv = model().nv;
  // Checked on the environments themselves: a delay needs the dof's drive.
  std::vector<int> delays(static_cast<size_t>(size()) * static_cast<size_t>(nv));
  for (int i = 0; i < size(); ++i)
    for (int d = 0; d < nv; ++d)
      delays[static_cast<size_t>(i) * nv + d] = sims_[static_cast<size_t>(i)].drive_delay(d);
  for (size_t j = 0; j < envs.size(); ++j) {
    const Simulation& sim = sims_[static_cast<size_t>(envs[j])];
    for (int d = 0; d < nv; ++d) {
      const double k = row_of(delay, j)[d];
      try {
        if (k != std::floor(k) || !(std::abs(k) <= kMaxDelay + 1.0))
          throw std::invalid_argument("drive delay of joint '" + model().dof_names[d] +
                                      "' = " + format_double(k) +
                                      " must be a whole number of steps in [0, " +
                                      std::to_string(kMaxDelay) + "]");
        sim.check_drive_delay(d, static_cast<int>(k));
      } catch (const std::invalid_argument& e) {
        rethrow_for(envs[j], e);
      }
      delays[static_cast<size_t>(envs[j]) * nv + d] = static_cast<int>(k);
    }
  }
  // The histories the batch would hold (delay + 1 samples per delayed dof), bounded before any
  // is allocated.
  long long samples = 0;
  for (const int k : delays) samples += k > 0 ? k + 1LL : 0LL;
  if (samples > kMaxDelaySamples)
    throw std::invalid_argument(
        "set_drive_delay: these delays need " + std::to_string(samples) +
        " samples of delay history over the batch's " + std::to_string(size()) +
        " environments, more than the " + std::to_string(kMaxDelaySamples) +
        " a batch may hold (kMaxDelaySamples): nothing changed");
  // Every new history is allocated before any environment changes (a std::bad_alloc leaves the
  // batch as it was); the moves that commit them allocate nothing.
  std::vector<DriveDelays> made;
  made.reserve(envs.size());
  for (size_t j = 0; j < envs.size(); ++j) {
    DriveDelays& lines = made.emplace_back(sims_[static_cast<size_t>(envs[j])].ws_->drive_delays);
    for (int d = 0; d < nv; ++d) lines.set(d, static_cast<int>(row_of(delay, j)[d]));
  }
  for (size_t j = 0; j < envs.size(); ++j) {
    Simulation& sim = sims_[static_cast<size_t>(envs[j])];
    sim.ws_->drive_delays = std::move(made[j]);
    for (int d = 0; d < nv; ++d)
      sim.settings_.drive_delay[static_cast<size_t>(d)] = sim.ws_->drive_delays.delay(d);
    sim.ws_->row_kinds_changed = true;
  }
  // The lanes' targets of a dof no longer delayed are the drive's again.
  mark(envs, repack_drives);
}

// Each environment envs[j] gets the model make(its model, j); with broadcast values, one new
// model per distinct old one. All are made (and checked) before any is set.
template <class Make>
void Batch::vary_models(const std::vector<int>& envs, bool broadcast, Make make) {
  std::vector<std::shared_ptr<const Model>> models(envs.size());
  std::map<const Model*, std::shared_ptr<const Model>> made;
  for (size_t j = 0; j < envs.size(); ++j) {
    const Model& old = sims_[static_cast<size_t>(envs[j])].model();
    if (broadcast && made.count(&old)) {
      models[j] = made[&old];
      continue;
    }
    try {
      models[j] = std::make_shared<const Model>(make(old, j));
    } catch (const std::invalid_argument& e) {
      rethrow_for(envs[j], e);
    }
    if (broadcast) made[&old] = models[j];
  }
  for (size_t j = 0; j < envs.size(); ++j)
    sims_[static_cast<size_t>(envs[j])].set_model(std::move(models[j]));
  mark(envs, repack_model);
}

void Batch::set_armature(std::span<const int> env_ids, const RowMatrix& armature) {
  const std::vector<int> envs = check_env_ids(env_ids);
  check_values(armature, envs.size(), model().nv, "armature");
  vary_models(envs, armature.rows() == 1, [&](const Model& m, size_t j) {
    return with_armature(m, row_of(armature, j).transpose());
  });
}

void Batch::set_link_mass(std::span<const int> env_ids, int link, const VecX& mass,
                          bool scale_inertia) {
  const std::vector<int> envs = check_env_ids(env_ids);
  check_link_index(model(), link);
  if (mass.size() != 1 && mass.size() != static_cast<Eigen::Index>(envs.size()))
    throw std::invalid_argument("Batch: mass has " + std::to_string(mass.size()) +
                                " values, expected " + std::to_string(envs.size()) +
                                " (one per environment) or 1");
  vary_models(envs, mass.size() == 1, [&](const Model& m, size_t j) {
    const Link& l = m.links[static_cast<size_t>(link)];
    const double x = mass[mass.size() == 1 ? 0 : static_cast<Eigen::Index>(j)];
    if (scale_inertia && !(l.mass > 0.0))
      throw std::invalid_argument("link '" + l.name +
                                  "' has mass 0: its inertia cannot scale with the mass "
                                  "(give scale_inertia = false)");
    const Mat3 inertia = scale_inertia ? Mat3(l.inertia_com * (x / l.mass)) : l.inertia_com;
    return with_link_inertial(m, link, x, l.com, inertia);
  });
}

void Batch::set_link_com(std::span<const int> env_ids, int link, const RowMatrix& com) {
  const std::vector<int> envs = check_env_ids(env_ids);
  check_link_index(model(), link);
  check_values(com, envs.size(), 3, "com");
  vary_models(envs, com.rows() == 1, [&](const Model& m, size_t j) {
    const Link& l = m.links[static_cast<size_t>(link)];
    return with_link_inertial(m, link, l.mass, row_of(com, j).transpose(), l.inertia_com);
  });
}

void Batch::set_gravity(std::span<const int> env_ids, const RowMatrix& gravity) {
  const std::vector<int> envs = check_env_ids(env_ids);
  check_values(gravity, envs.size(), 3, "gravity");
  vary_models(envs, gravity.rows() == 1, [&](const Model& m, size_t j) {
    const Vec3 g = row_of(gravity, j).transpose();
    if (!g.allFinite())
      throw std::invalid_argument("gravity = " + format_vec3(g) + " is not finite");
    Model out = m;
    out.gravity = g;
    return out;
  });
}

RowMatrix Batch::gravity() const {
  RowMatrix out(size(), 3);
  for (int i = 0; i < size(); ++i)
    out.row(i) = sims_[static_cast<size_t>(i)].model().gravity.transpose();
  return out;
}

RowMatrix Batch::stiffness() const {
  return per_dof_matrix(sims_, [](const Simulation& s, int d) { return s.drive(d).stiffness; });
}
RowMatrix Batch::damping() const {
  return per_dof_matrix(sims_, [](const Simulation& s, int d) { return s.drive(d).damping; });
}
RowMatrix Batch::target_position() const {
  return per_dof_matrix(sims_,
                        [](const Simulation& s, int d) { return s.drive(d).target_position; });
}
RowMatrix Batch::target_velocity() const {
  return per_dof_matrix(sims_,
                        [](const Simulation& s, int d) { return s.drive(d).target_velocity; });
}
RowMatrix Batch::armature() const {
  return per_dof_matrix(sims_, [](const Simulation& s, int d) { return s.model().armature[d]; });
}
RowMatrix Batch::lower_limit() const {
  return per_dof_matrix(sims_, [](const Simulation& s, int d) { return s.lower_limit(d); });
}
RowMatrix Batch::upper_limit() const {
  return per_dof_matrix(sims_, [](const Simulation& s, int d) { return s.upper_limit(d); });
}
RowMatrix Batch::static_friction() const {
  return per_dof_matrix(
      sims_, [](const Simulation& s, int d) { return s.joint_friction(d).static_effort; });
}
RowMatrix Batch::dynamic_friction() const {
  return per_dof_matrix(
      sims_, [](const Simulation& s, int d) { return s.joint_friction(d).dynamic_effort; });
}
RowMatrix Batch::viscous_friction() const {
  return per_dof_matrix(sims_,
                        [](const Simulation& s, int d) { return s.joint_friction(d).viscous; });
}
RowMatrix Batch::max_joint_velocity() const {
  return per_dof_matrix(sims_, [](const Simulation& s, int d) { return s.max_joint_velocity(d); });
}

RowMatrix Batch::drive_delay() const {
  return per_dof_matrix(sims_, [](const Simulation& s, int d) { return s.drive_delay(d); });
}

VecX Batch::link_mass(int link) const {
  check_link_index(model(), link);
  VecX m(size());
  for (int i = 0; i < size(); ++i)
    m[i] = sims_[static_cast<size_t>(i)].model().links[static_cast<size_t>(link)].mass;
  return m;
}

RowMatrix Batch::link_com(int link) const {
  check_link_index(model(), link);
  RowMatrix m(size(), 3);
  for (int i = 0; i < size(); ++i)
    m.row(i) =
        sims_[static_cast<size_t>(i)].model().links[static_cast<size_t>(link)].com.transpose();
  return m;
}

RowMatrix Batch::link_contact_force() const {
  const int links = model().num_links();
  RowMatrix out(size(), 3 * links);
  for (int i = 0; i < size(); ++i) {
    const std::vector<Vec3>& f = sims_[static_cast<size_t>(i)].link_contact_force();
    for (int l = 0; l < links; ++l)
      out.row(i).segment<3>(3 * l) = f[static_cast<size_t>(l)].transpose();
  }
  return out;
}

RowMatrix Batch::observe(std::span<const Observation> fields) const {
  const Model& m = model();
  Eigen::Index width = 0;
  for (Observation f : fields) width += f == Observation::q ? m.nq : m.nv;
  RowMatrix out(size(), width);
  Eigen::Index col = 0;
  for (Observation f : fields) {
    if (f == Observation::target_position || f == Observation::target_velocity) {
      const bool position = f == Observation::target_position;
      for (int i = 0; i < size(); ++i)
        for (int d = 0; d < m.nv; ++d) {
          const Drive& drive = sims_[static_cast<size_t>(i)].drive(d);
          out(i, col + d) = position ? drive.target_position : drive.target_velocity;
        }
      col += m.nv;
      continue;
    }
    // The other fields are the storage arrays, in StateStorage's order.
    const RowMatrix& rows = rows_[static_cast<size_t>(f)];
    out.middleCols(col, rows.cols()) = rows;
    col += rows.cols();
  }
  return out;
}

RowMatrix Batch::frame_positions(int link, const Vec3& point) const {
  check_link_index(model(), link);
  if (!point.allFinite())
    throw std::invalid_argument("frame_positions: point = " + format_vec3(point) +
                                " is not finite");
  return per_environment(
      3, [&](const Simulation& s, Data& data, const VecX& q, const VecX&, auto row) {
        forward_kinematics(s.model(), data, q);
        row = frame_position(s.model(), data, link, point).transpose();
      });
}

RowMatrix Batch::link_poses(int link) const {
  check_link_index(model(), link);
  const auto l = static_cast<size_t>(link);
  return per_environment(12, [&](const Simulation& s, Data& data, const VecX& q, const VecX&,
                                 auto row) {
    forward_kinematics(s.model(), data, q);
    Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(row.data()) = data.world_rotation[l];
    row.template tail<3>() = data.world_position[l].transpose();
  });
}

RowMatrix Batch::frame_jacobians(int link, const Vec3& point, ReferenceFrame frame) const {
  check_link_index(model(), link);
  if (!point.allFinite())
    throw std::invalid_argument("frame_jacobians: point = " + format_vec3(point) +
                                " is not finite");
  const int nv = model().nv;
  return per_environment(6 * nv, [&, J = MatX()](const Simulation& s, Data& data, const VecX& q,
                                                 const VecX&, auto row) mutable {
    forward_kinematics(s.model(), data, q);
    frame_jacobian(s.model(), data, link, point, frame, J);
    Eigen::Map<RowMatrix>(row.data(), 6, nv) = J;
  });
}

RowMatrix Batch::mass_matrices() const {
  const int nv = model().nv;
  return per_environment(
      nv * nv, [&](const Simulation& s, Data& data, const VecX& q, const VecX&, auto row) {
        Eigen::Map<RowMatrix>(row.data(), nv, nv) = crba(s.model(), data, q);
      });
}

RowMatrix Batch::bias_forces() const {
  return per_environment(
      model().nv, [&](const Simulation& s, Data& data, const VecX& q, const VecX& qd, auto row) {
        row = nonlinear_effects(s.model(), data, q, qd).transpose();
      });
}

// (N, cols): row i from row_of(environment i, a workspace, its q and qd, the row). Chunks of
// environments share a workspace (the topology, all the queries read of it, is shared); each row
// depends only on its environment, so the result is the same on any number of threads.
template <class F>
RowMatrix Batch::per_environment(Eigen::Index cols, F row_of) const {
  RowMatrix out(size(), cols);
  const int grain = std::max(1, size() / (8 * effective_num_threads()));
  parallel(size(), grain, [&](int begin, int end) {
    Data data(model());
    VecX q(model().nq), qd(model().nv);
    F f = row_of;  // a private copy: a query may keep scratch in its closure
    for (int i = begin; i < end; ++i) {
      const Simulation& s = sims_[static_cast<size_t>(i)];
      q = s.q();
      qd = s.qd();
      f(s, data, q, qd, out.row(i));
    }
  });
  return out;
}

// f(begin, end) over ranges of [0, n) of at least `grain`, on effective_num_threads() threads.
template <class F>
void Batch::parallel(int n, int grain, F f) const {
  const int threads = effective_num_threads();
  if (threads <= 1 || n == 1) return f(0, n);
  tbb::task_arena arena(threads);
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<int>(0, n, static_cast<size_t>(grain)),
                      [&](const tbb::blocked_range<int>& r) { f(r.begin(), r.end()); });
  });
}

void Batch::mark(const std::vector<int>& envs, unsigned char what) {
  for (int e : envs) repack_[static_cast<size_t>(e)] |= what;
}

void Batch::mark_all(unsigned char what) {
  for (unsigned char& r : repack_) r |= what;
}

// Why no environment steps in lanes (lanes off, FEATHERDRIVE_SIMD=scalar), else empty.
std::string Batch::lanes_off() const {
  if (!lanes_allowed_) return "lanes off (set_lanes)";
  if (!isa_ && simd_forced_scalar()) return "FEATHERDRIVE_SIMD=scalar";
  return {};
}

// Groups the environments again when one's plan-level settings changed since (only environments
// a setter marked or handed out can have changed), then packs what changed into each lane
// group's parameters. False when no environment steps in lanes.
bool Batch::prepare_lanes() {
  if (!lanes_off().empty()) return false;
  const int n = size();
  bool regroup = !lanes_;
  for (int i = 0; i < n && !regroup; ++i) {
    if (!repack_[static_cast<size_t>(i)] && !handed_out_[static_cast<size_t>(i)]) continue;
    const Simulation& s = sims_[static_cast<size_t>(i)];
    const int g = lanes_->group_of[static_cast<size_t>(i)];
    if (!lanes_->groups[static_cast<size_t>(g)].key.matches(
            s.options(), s.mimic_joints(), s.ws_->contact_rows.links_with_shapes()))
      regroup = true;
  }
  if (regroup) {
    // Allocates: a new set of groups and engines, each packed whole below.
    auto lanes = std::make_shared<simd::LaneGroups>();
    lanes->group_of.assign(static_cast<size_t>(n), -1);
    lanes->lane_of.assign(static_cast<size_t>(n), -1);
    int last = -1;
    for (int i = 0; i < n; ++i) {
      const Simulation& s = sims_[static_cast<size_t>(i)];
      const std::vector<char>& shapes = s.ws_->contact_rows.links_with_shapes();
      auto fits = [&](int g) {
        return g >= 0 && lanes->groups[static_cast<size_t>(g)].key.matches(
                             s.options(), s.mimic_joints(), shapes);
      };
      int g = fits(last) ? last : -1;
      for (int k = 0; g < 0 && k < static_cast<int>(lanes->groups.size()); ++k)
        if (fits(k)) g = k;
      if (g < 0) {
        g = static_cast<int>(lanes->groups.size());
        lanes->groups.push_back(
            {simd::PlanKey(s.options(), s.mimic_joints(), shapes), {}, {}, {}, {}});
      }
      simd::LaneGroup& group = lanes->groups[static_cast<size_t>(g)];
      lanes->group_of[static_cast<size_t>(i)] = g;
      lanes->lane_of[static_cast<size_t>(i)] = static_cast<int>(group.members.size());
      group.members.push_back(i);
      last = g;
    }
    for (simd::LaneGroup& group : lanes->groups) {
      const int count = static_cast<int>(group.members.size());
      group.engine =
          std::make_unique<simd::LaneEngine>(sims_[static_cast<size_t>(group.members[0])], count);
    }
    lanes_ = std::move(lanes);
    mark_all(repack_all);
  }
  for (simd::LaneGroup& group : lanes_->groups) {
    // The group's own width: narrowed for a small group as for a small batch (every width
    // gives the same bits).
    group.isa = isa_ ? *isa_ : simd::lane_isa(static_cast<int>(group.members.size()));
    group.one_lane = !isa_ && simd::one_lane_blocks(static_cast<int>(group.members.size()));
    for (size_t j = 0; j < group.members.size(); ++j) {
      const int i = group.members[j];
      unsigned char& what = repack_[static_cast<size_t>(i)];
      if (handed_out_[static_cast<size_t>(i)]) what = repack_all;
      const Simulation& s = sims_[static_cast<size_t>(i)];
      const int lane = static_cast<int>(j);
      if (what & repack_drives) group.engine->pack_drives(lane, s);
      if (what & repack_joints) group.engine->pack_joints(lane, s);
      if (what & repack_model) group.engine->pack_model(lane, s.model());
      what = 0;
    }
  }
  return !lanes_->groups.empty();
}

std::string Batch::step_path() {
  const std::string off = lanes_off();
  if (!off.empty()) return "scalar: " + off;
  prepare_lanes();
  const simd::LaneGroups& l = *lanes_;
  int one_lane = 0;  // environments in one-lane blocks
  for (const simd::LaneGroup& g : l.groups)
    if (g.one_lane) one_lane += static_cast<int>(g.members.size());
  const std::string at_one = std::to_string(one_lane) + " at one lane";
  if (l.groups.size() == 1) {
    const std::string path = std::string(to_string(l.groups.front().isa)) + " lanes";
    return one_lane > 0 ? path + " (" + at_one + ")" : path;
  }
  bool one_isa = true;
  for (const simd::LaneGroup& g : l.groups) one_isa = one_isa && g.isa == l.groups.front().isa;
  std::string path =
      one_isa ? std::string(to_string(l.groups.front().isa)) + " lanes: " : "lanes: ";
  path += std::to_string(l.groups.size()) + " groups (";
  for (size_t g = 0; g < l.groups.size(); ++g) {
    if (g > 0) path += ", ";
    if (!one_isa) path += std::string(to_string(l.groups[g].isa)) + " ";
    path += std::to_string(l.groups[g].members.size());
  }
  return path + " environments" + (one_lane > 0 ? "; " + at_one : std::string()) + ")";
}

std::string Batch::env_path(int i) {
  static_cast<const Batch&>(*this).sim(i);  // the index check
  const std::string off = lanes_off();
  if (!off.empty()) return "scalar: " + off;
  prepare_lanes();
  const int g = lanes_->group_of[static_cast<size_t>(i)];
  const simd::LaneGroup& group = lanes_->groups[static_cast<size_t>(g)];
  return std::string(to_string(group.isa)) + " lanes, group " + std::to_string(g) +
         (group.one_lane ? " (one lane)" : "");
}

// Every lane group's environments through its lanes (all groups' blocks on one pool of
// threads), each environment's clock as its Simulation keeps it, and each one stopped in this
// call recorded in divergences_.
void Batch::step_lanes(int count) {
  simd::LaneGroups& l = *lanes_;
  const int n = size();
  lane_steps_.resize(static_cast<size_t>(n));
  lane_time_.resize(static_cast<size_t>(n));
  bool control = false, actuated = false, implicit = false, tracking = false, guarded = false;
  for (simd::LaneGroup& g : l.groups) {
    // Each environment's contact rows, reports and anchors are its Simulation's
    // (lane_contacts.cpp).
    simd::ContactLanes& contacts = g.engine->contacts();
    contacts.envs.resize(g.members.size());
    bool touching = false;  // some environment's ground or self-collision is on
    for (size_t j = 0; j < g.members.size(); ++j) {
      const auto i = static_cast<size_t>(g.members[j]);
      Simulation& s = sims_[i];
      lane_steps_[i] = s.step_count_;
      lane_time_[i] = s.time_;
      g.engine->clear_stop(static_cast<int>(j));  // a diverged one steps again, as its Simulation
      contacts.envs[j] = {&s, &*s.ws_, s.options().guard.enabled};
      touching = touching || s.ws_->contacts_active || s.ws_->self_contacts_active;
      guarded = guarded || s.options().guard.enabled;
      control = control || s.ws_->has_control_stages();
      actuated = actuated || s.ws_->actuators.any() || s.ws_->actuated;
      implicit = implicit || s.ws_->actuators.any_implicit();
      tracking = tracking || s.ws_->track_convergence;
    }
    g.engine->set_contacts(touching, g.key.shape_links);
  }
  simd::Block a;
  a.q = rows_[StateStorage::q].data(), a.qd = rows_[StateStorage::qd].data();
  a.applied = rows_[StateStorage::applied_force].data();
  a.drive_force = rows_[StateStorage::drive_force].data();
  a.limit_force = rows_[StateStorage::limit_force].data();
  a.friction_force = rows_[StateStorage::friction_force].data();
  a.velocity_limit_force = rows_[StateStorage::velocity_limit_force].data();
  a.row_force = rows_[StateStorage::row_force].data();
  a.step_count = lane_steps_.data(), a.time = lane_time_.data();
  const int nv = model().nv;
  // The implicit actuators' forces and the tracked drive changes, copied into each Simulation's
  // workspace after the call (lane_results). Implicit actuators are control stages: one step a run.
  if (implicit) {
    lane_actuator_force_.resize(n, nv);
    a.actuator_force = lane_actuator_force_.data();
  }
  if (tracking) {  // the lanes keep a stopped lane's: they start from every environment's own
    lane_drive_change_.resize(n, nv);
    for (const simd::LaneGroup& g : l.groups)
      for (int i : g.members)
        lane_drive_change_.row(i) =
            sims_[static_cast<size_t>(i)].ws_->last_drive_change.transpose();
    a.drive_change = lane_drive_change_.data();
  }
  // Without actuators the joint force is the applied force itself.
  if (control && actuated) {
    lane_tau_.resize(n, nv);
    a.applied = lane_tau_.data();
  }
  if (guarded) {  // the rows the guard reads (lane_guard.cpp)
    lane_guard_rows_.resize(n, nv * simd::kGuardFields);
    a.guard_rows = lane_guard_rows_.data();
  }
  // Groups without control stages or the guard make all their steps in one run; the others one
  // step a run: each step's control stages read the state it starts from, and the guard tests
  // each step (a guarded environment's group holds only guarded ones: PlanKey).
  l.jobs.clear();
  l.stepwise.clear();
  for (simd::LaneGroup& g : l.groups) {
    simd::Block b = a;
    b.rows = g.members.data();
    if (!g.key.guarded) b.guard_rows = nullptr;
    (control || g.key.guarded ? l.stepwise : l.jobs)
        .push_back({g.engine.get(), b, g.isa, g.one_lane});
  }
  const int threads = effective_num_threads();
  if (!l.jobs.empty()) l.pool.run(l.jobs, count, threads);
  for (int k = 0; k < count && !l.stepwise.empty(); ++k) {
    if (control) lane_control_stages(actuated);
    if (guarded) lane_guard_start();
    l.pool.run(l.stepwise, 1, threads);
    if (guarded) lane_guard_finish(tracking ? &lane_drive_change_ : nullptr);
    if (!control) continue;
    for (const simd::LaneGroup& g : l.groups)
      for (size_t j = 0; j < g.members.size(); ++j) {
        const int lane = static_cast<int>(j), i = g.members[j];
        Simulation& s = sims_[static_cast<size_t>(i)];
        if (guarded && lane_guard_redone(i)) continue;  // its Simulation's step wrote all
        if (g.engine->stopped_now(lane)) {  // Stepper::check_finite_or_throw takes the pushes back
          s.stepper().undo_actuators();
        } else if (implicit && g.engine->stop(lane).quantity == 0 && s.ws_->actuators.any()) {
          // Stepper::row_forces: an implicit actuator's row force is its actuator force.
          for (int d = 0; d < nv; ++d)
            if (s.ws_->actuators.implicit(d))
              s.ws_->actuator_force[d] = lane_actuator_force_(i, d);
        }
      }
  }
  for (const simd::LaneGroup& g : l.groups)
    for (size_t j = 0; j < g.members.size(); ++j) {
      const int i = g.members[j];
      Simulation& s = sims_[static_cast<size_t>(i)];
      if (tracking && s.ws_->track_convergence)
        s.ws_->last_drive_change = lane_drive_change_.row(i).transpose();
      s.step_count_ = lane_steps_[static_cast<size_t>(i)];
      s.time_ = lane_time_[static_cast<size_t>(i)];
      // The lanes wrote the row kinds' forces; without a kind in the group they wrote zeros.
      if (g.engine->plan().any_row_kinds) s.ws_->row_force_live = true;
      // Stops were cleared above: one now stopped in this call, in Simulation's words at the
      // clock it kept.
      if (g.engine->stop(static_cast<int>(j)).quantity == 0) continue;
      divergences_[static_cast<size_t>(i)] = BatchDivergence{
          s.step_count() + 1,
          g.engine->divergence_message(static_cast<int>(j), s.model(), s.step_count(), s.time())};
    }
}

// The step's control stages (Stepper::control_stages: explicit actuators, drive delays) of
// every lane environment still stepping, in scalar on its step-start state, as its Simulation
// runs them; the lanes read their results: the joint force and the delayed dofs' targets.
void Batch::lane_control_stages(bool actuated) {
  const int nv = model().nv;
  const RowMatrix& applied = rows_[StateStorage::applied_force];
  for (const simd::LaneGroup& g : lanes_->groups)
    for (size_t j = 0; j < g.members.size(); ++j) {
      const int lane = static_cast<int>(j), i = g.members[j];
      simd::LaneEngine& lanes = *g.engine;
      if (lanes.stop(lane).quantity != 0) continue;  // stopped in this call: pushes no more
      Simulation& s = sims_[static_cast<size_t>(i)];
      // Only the actuators read the step-start state (the delays read the drives): the copy of
      // 1024 environments' states was an eighth of a delayed WAM's step.
      const bool reads_state = s.ws_->actuators.any() || s.ws_->actuated;
      Stepper stepper = s.stepper();
      if (reads_state) stepper.load_state();
      const VecX& tau = stepper.control_stages();
      if (actuated) {
        if (reads_state)
          lane_tau_.row(i) = tau.transpose();
        else
          lane_tau_.row(i) = applied.row(i);
      }
      const ExplicitActuators& actuators = s.ws_->actuators;
      if (actuators.any())
        for (int d = 0; d < nv; ++d)  // the command each implicit one sees this step (I16)
          if (actuators.implicit(d)) lanes.set_command(lane, d, actuators.command_seen(d));
      const DriveDelays& delays = s.drive_delays();
      if (!delays.any()) continue;
      for (int d = 0; d < nv; ++d) {
        if (!delays.delayed(d)) continue;
        const Drive& seen = delays.drive_seen(d);
        const int x = d * simd::kDofParameters;
        lanes.set_parameter(lane, x + simd::target_position, seen.target_position);
        lanes.set_parameter(lane, x + simd::target_velocity, seen.target_velocity);
      }
    }
}

void Batch::step(int count) {
  if (count < 0)
    throw std::invalid_argument("step count = " + std::to_string(count) + " must be >= 0");
  if (count == 0) return;
  for (std::optional<BatchDivergence>& d : divergences_) d.reset();
  const bool lanes = prepare_lanes();
  if (lanes) step_lanes(count);
  // Without lanes every environment is its Simulation.
  const int n = size();
  // One slot per environment: environments never share anything a step writes.
  std::vector<std::exception_ptr>& failed = failed_;
  failed.resize(static_cast<size_t>(n));
  if (!lanes)
    parallel(n, 1, [&](int begin, int end) {
      for (int i = begin; i < end; ++i) {
        Simulation& s = sims_[static_cast<size_t>(i)];
        try {
          s.step(count);
        } catch (const DivergenceError& e) {
          divergences_[static_cast<size_t>(i)] = BatchDivergence{s.step_count() + 1, e.what()};
        } catch (...) {
          failed[static_cast<size_t>(i)] = std::current_exception();
        }
      }
    });
  for (std::exception_ptr& e : failed)
    if (e) std::rethrow_exception(std::exchange(e, nullptr));
  int first = -1, count_diverged = 0;
  for (int i = 0; i < n; ++i)
    if (divergences_[static_cast<size_t>(i)]) {
      if (first < 0) first = i;
      ++count_diverged;
    }
  if (first >= 0)
    throw DivergenceError("batch copy " + std::to_string(first) + " (" +
                          std::to_string(count_diverged) + " of " + std::to_string(n) +
                          " copies diverged): " +
                          divergences_[static_cast<size_t>(first)]->message);
}

}  // namespace featherdrive
