// The SIMD Batch's settings, checks and dispatch; the step itself is simd_lane_step.hpp.
// docs/simd_batch.md.
#include "featherdrive/sim/simd_batch.hpp"

#include <tbb/info.h>

#include <xsimd/config/xsimd_arch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <sstream>
#include <stdexcept>

#include "featherdrive/core/format.hpp"
#include "featherdrive/model/model_variant.hpp"
#include "lane_engine.hpp"

namespace featherdrive {



const char* to_string(SimdIsa isa) {
  switch (isa) {
    case SimdIsa::sse2:
      return "sse2";
    case SimdIsa::avx2:
      return "avx2";
    case SimdIsa::avx512:
      return "avx512";
  }
  return "unknown";
}

int simd_width(SimdIsa isa) {
  return isa == SimdIsa::avx512 ? 8 : isa == SimdIsa::avx2 ? 4 : 2;
}

std::vector<SimdIsa> available_simd_isas() {
  const auto cpu = xsimd::available_architectures();
  std::vector<SimdIsa> out{SimdIsa::sse2};  // every x86-64 CPU
  if (cpu.avx2) out.push_back(SimdIsa::avx2);
  if (cpu.avx512f) out.push_back(SimdIsa::avx512);
  return out;
}

namespace {

void check_isa(SimdIsa isa, const std::string& where) {
  const std::vector<SimdIsa> has = available_simd_isas();
  if (std::find(has.begin(), has.end(), isa) == has.end())
    throw std::invalid_argument(where + " = " + to_string(isa) + ": this CPU has only up to " +
                                to_string(has.back()));
}

}  // namespace

SimdIsa default_simd_isa() {
  const char* forced = std::getenv("FEATHERDRIVE_SIMD");
  if (!forced || !*forced) {  // the widest, without a vector (Batch::step allocates nothing)
    const auto cpu = xsimd::available_architectures();
    return cpu.avx512f ? SimdIsa::avx512 : cpu.avx2 ? SimdIsa::avx2 : SimdIsa::sse2;
  }
  if (std::string(forced) == "scalar") return SimdIsa::sse2;  // SimdBatch's narrowest
  for (SimdIsa isa : {SimdIsa::sse2, SimdIsa::avx2, SimdIsa::avx512})
    if (std::string(forced) == to_string(isa)) {
      check_isa(isa, "FEATHERDRIVE_SIMD");
      return isa;
    }
  throw std::invalid_argument(std::string("FEATHERDRIVE_SIMD = '") + forced +
                              "': expected scalar, sse2, avx2 or avx512");
}

bool simd_forced_scalar() {
  const char* forced = std::getenv("FEATHERDRIVE_SIMD");
  return forced && std::string(forced) == "scalar";
}

struct SimdBatch::Impl {
  Impl(const Simulation& prototype, int count) : engine(prototype, count), prototype(prototype) {}
  simd::LaneEngine engine;
  Simulation prototype;  // settings shared by all (for simulation(i))
};

namespace {

auto row_of(const RowMatrix& m, size_t j) {
  return m.row(m.rows() == 1 ? 0 : static_cast<Eigen::Index>(j));
}

void check_shape(const RowMatrix& m, size_t k, Eigen::Index cols, const std::string& what) {
  if (m.cols() == cols && (m.rows() == 1 || m.rows() == static_cast<Eigen::Index>(k))) return;
  std::ostringstream s;
  s << "SimdBatch: " << what << " has shape (" << m.rows() << ", " << m.cols() << "), expected ("
    << k << ", " << cols << ") or (1, " << cols << ")";
  throw std::invalid_argument(s.str());
}

[[noreturn]] void rethrow_for_env(int env, const std::exception& e) {
  throw std::invalid_argument("SimdBatch: environment " + std::to_string(env) + ": " + e.what());
}

int dof_index(int d, int field) {
  return d * simd::kDofParameters + field;
}

}  // namespace

SimdBatch::SimdBatch(const Simulation& prototype, int count, std::optional<SimdIsa> isa)
    : model_(prototype.model_ptr()), options_(prototype.options()), count_(count) {
  if (count < 1 || count > Batch::kMaxSize)
    throw std::invalid_argument("SimdBatch: count = " + std::to_string(count) + " must be in [1, " +
                                std::to_string(Batch::kMaxSize) + "]");
  if (const std::string refused = simd::lane_refusal(prototype); !refused.empty())
    throw std::invalid_argument("SimdBatch: " + refused +
                                ": not supported by the SIMD Batch (docs/simd_batch.md)");
  isa_ = isa ? *isa : simd::lane_isa(count);
  check_isa(isa_, "SimdBatch: isa");
  impl_ = std::make_unique<Impl>(prototype, count);
  auto rows = [count](const VecView& v) {
    RowMatrix r(count, v.size());
    for (int e = 0; e < count; ++e) r.row(e) = v.transpose();
    return r;
  };
  q_ = rows(prototype.q());
  qd_ = rows(prototype.qd());
  applied_force_ = rows(prototype.applied_force());
  drive_force_ = rows(prototype.drive_force());
  limit_force_ = rows(prototype.limit_force());
  friction_force_ = rows(prototype.friction_force());
  velocity_limit_force_ = rows(prototype.velocity_limit_force());
  initial_q_ = prototype.q();
  step_count_.assign(static_cast<size_t>(count), prototype.step_count());
  time_.assign(static_cast<size_t>(count), prototype.time());
  diverged_.resize(static_cast<size_t>(count));
}

SimdBatch::~SimdBatch() = default;

void SimdBatch::set_isa(SimdIsa isa) {
  check_isa(isa, "SimdBatch: isa");
  isa_ = isa;
}

void SimdBatch::set_num_threads(int threads) {
  if (threads < 0 || threads > Batch::kMaxThreads)
    throw std::invalid_argument("SimdBatch: threads = " + std::to_string(threads) +
                                " is out of range [0, " + std::to_string(Batch::kMaxThreads) + "]");
  threads_ = threads;
}

int SimdBatch::effective_num_threads() const {
  return threads_ > 0 ? threads_ : tbb::info::default_concurrency();
}

std::vector<int> SimdBatch::envs(std::span<const int> env_ids) const {
  std::vector<int> seen(static_cast<size_t>(count_), -1);
  for (size_t j = 0; j < env_ids.size(); ++j) {
    const int e = env_ids[j];
    const std::string entry =
        "SimdBatch: env_ids[" + std::to_string(j) + "] = " + std::to_string(e);
    if (e < 0 || e >= count_)
      throw std::invalid_argument(entry + " is out of range [0, " + std::to_string(count_) + ")");
    if (seen[static_cast<size_t>(e)] >= 0)
      throw std::invalid_argument(entry + " appears twice (also env_ids[" +
                                  std::to_string(seen[static_cast<size_t>(e)]) + "])");
    seen[static_cast<size_t>(e)] = static_cast<int>(j);
  }
  return {env_ids.begin(), env_ids.end()};
}

double SimdBatch::parameter(int env, int index) const {
  return impl_->engine.parameter(env, index);
}

void SimdBatch::set_parameter(int env, int index, double value) {
  impl_->engine.set_parameter(env, index, value);
}

RowMatrix SimdBatch::dof_parameter(int field) const {
  RowMatrix out(count_, model_->nv);
  for (int e = 0; e < count_; ++e)
    for (int d = 0; d < model_->nv; ++d) out(e, d) = parameter(e, dof_index(d, field));
  return out;
}

// Environment e's drive on dof d, from the packed parameters.
static Drive packed_drive(const SimdBatch& b, int e, int d,
                          double (SimdBatch::*get)(int, int) const) {
  auto x = [&](int f) { return (b.*get)(e, dof_index(d, f)); };
  Drive drive;
  drive.type = x(simd::has_drive) == 0.0      ? DriveType::none
               : x(simd::acceleration) != 0.0 ? DriveType::acceleration
                                              : DriveType::force;
  drive.stiffness = x(simd::stiffness);
  drive.damping = x(simd::damping);
  drive.max_force = x(simd::max_force);
  drive.max_impulse = x(simd::max_impulse);
  drive.target_position = x(simd::target_position);
  drive.target_velocity = x(simd::target_velocity);
  return drive;
}

void SimdBatch::set_q(std::span<const int> env_ids, const RowMatrix& q) {
  const std::vector<int> es = envs(env_ids);
  check_shape(q, es.size(), model_->nq, "q");
  Simulation& check = impl_->prototype;
  const VecX keep = check.q();
  for (size_t j = 0; j < es.size(); ++j) {
    try {
      check.set_q(row_of(q, j).transpose());
    } catch (const std::invalid_argument& e) {
      check.set_q(keep);
      rethrow_for_env(es[j], e);
    }
  }
  check.set_q(keep);
  for (size_t j = 0; j < es.size(); ++j) q_.row(es[j]) = row_of(q, j);
}

void SimdBatch::set_qd(std::span<const int> env_ids, const RowMatrix& qd) {
  const std::vector<int> es = envs(env_ids);
  check_shape(qd, es.size(), model_->nv, "qd");
  if (!qd.allFinite()) throw std::invalid_argument("SimdBatch: qd holds a non-finite value");
  for (size_t j = 0; j < es.size(); ++j) qd_.row(es[j]) = row_of(qd, j);
}

void SimdBatch::set_applied_force(std::span<const int> env_ids, const RowMatrix& tau) {
  const std::vector<int> es = envs(env_ids);
  check_shape(tau, es.size(), model_->nv, "applied force");
  if (!tau.allFinite())
    throw std::invalid_argument("SimdBatch: applied force holds a non-finite value");
  for (size_t j = 0; j < es.size(); ++j) applied_force_.row(es[j]) = row_of(tau, j);
}

void SimdBatch::set_drive_targets(std::span<const int> env_ids, const RowMatrix& positions,
                                  const RowMatrix& velocities) {
  const std::vector<int> es = envs(env_ids);
  const int nv = model_->nv;
  check_shape(positions, es.size(), nv, "positions");
  check_shape(velocities, es.size(), nv, "velocities");
  for (size_t j = 0; j < es.size(); ++j)
    for (int d = 0; d < nv; ++d) {
      Drive drive = packed_drive(*this, es[j], d, &SimdBatch::parameter);
      drive.target_position = row_of(positions, j)[d];
      drive.target_velocity = row_of(velocities, j)[d];
      const std::string& joint = model_->links[static_cast<size_t>(model_->dof_link[d])].joint_name;
      try {
        validate_drive(drive, joint);
        if (drive.type == DriveType::none &&
            (drive.target_position != 0.0 || drive.target_velocity != 0.0))
          throw std::invalid_argument("joint '" + joint +
                                      "' has no drive: a target would do "
                                      "nothing (give it gains first)");
      } catch (const std::invalid_argument& e) {
        rethrow_for_env(es[j], e);
      }
    }
  for (size_t j = 0; j < es.size(); ++j)
    for (int d = 0; d < nv; ++d) {
      set_parameter(es[j], dof_index(d, simd::target_position), row_of(positions, j)[d]);
      set_parameter(es[j], dof_index(d, simd::target_velocity), row_of(velocities, j)[d]);
    }
}

void SimdBatch::set_drive_gains(std::span<const int> env_ids, const RowMatrix& stiffness,
                                const RowMatrix& damping, DriveType type) {
  const std::vector<int> es = envs(env_ids);
  const int nv = model_->nv;
  check_shape(stiffness, es.size(), nv, "stiffness");
  check_shape(damping, es.size(), nv, "damping");
  for (size_t j = 0; j < es.size(); ++j)
    for (int d = 0; d < nv; ++d) {
      Drive drive = packed_drive(*this, es[j], d, &SimdBatch::parameter);
      drive.type = type;
      drive.stiffness = row_of(stiffness, j)[d];
      drive.damping = row_of(damping, j)[d];
      try {
        validate_drive(drive, model_->links[static_cast<size_t>(model_->dof_link[d])].joint_name);
      } catch (const std::invalid_argument& e) {
        rethrow_for_env(es[j], e);
      }
    }
  for (size_t j = 0; j < es.size(); ++j)
    for (int d = 0; d < nv; ++d) {
      set_parameter(es[j], dof_index(d, simd::has_drive), type != DriveType::none);
      set_parameter(es[j], dof_index(d, simd::acceleration), type == DriveType::acceleration);
      set_parameter(es[j], dof_index(d, simd::stiffness), row_of(stiffness, j)[d]);
      set_parameter(es[j], dof_index(d, simd::damping), row_of(damping, j)[d]);
      if (type == DriveType::none) {
        set_parameter(es[j], dof_index(d, simd::target_position), 0.0);
        set_parameter(es[j], dof_index(d, simd::target_velocity), 0.0);
      }
    }
}

void SimdBatch::set_joint_limits(std::span<const int> env_ids, const RowMatrix& lower,
                                 const RowMatrix& upper) {
  const std::vector<int> es = envs(env_ids);
  const int nv = model_->nv;
  check_shape(lower, es.size(), nv, "lower");
  check_shape(upper, es.size(), nv, "upper");
  for (size_t j = 0; j < es.size(); ++j)  // Simulation's own check of each pair
    for (int d = 0; d < nv; ++d) {
      try {
        check_joint_limits(*model_, d, row_of(lower, j)[d], row_of(upper, j)[d]);
      } catch (const std::invalid_argument& e) {
        rethrow_for_env(es[j], e);
      }
    }
  for (size_t j = 0; j < es.size(); ++j)
    for (int d = 0; d < nv; ++d) {
      set_parameter(es[j], dof_index(d, simd::lower), row_of(lower, j)[d]);
      set_parameter(es[j], dof_index(d, simd::upper), row_of(upper, j)[d]);
    }
}

void SimdBatch::set_joint_friction(std::span<const int> env_ids, const RowMatrix& static_effort,
                                   const RowMatrix& dynamic_effort, const RowMatrix& viscous) {
  const std::vector<int> es = envs(env_ids);
  const int nv = model_->nv;
  check_shape(static_effort, es.size(), nv, "static friction");
  check_shape(dynamic_effort, es.size(), nv, "dynamic friction");
  check_shape(viscous, es.size(), nv, "viscous friction");
  for (size_t j = 0; j < es.size(); ++j)  // Simulation's own check of each dof's friction
    for (int d = 0; d < nv; ++d) {
      try {
        check_joint_friction(
            *model_, d,
            JointFriction{row_of(static_effort, j)[d], row_of(dynamic_effort, j)[d],
                          row_of(viscous, j)[d]});
      } catch (const std::invalid_argument& e) {
        rethrow_for_env(es[j], e);
      }
    }
  for (size_t j = 0; j < es.size(); ++j)
    for (int d = 0; d < nv; ++d) {
      set_parameter(es[j], dof_index(d, simd::static_friction), row_of(static_effort, j)[d]);
      set_parameter(es[j], dof_index(d, simd::dynamic_friction), row_of(dynamic_effort, j)[d]);
      set_parameter(es[j], dof_index(d, simd::viscous_friction), row_of(viscous, j)[d]);
    }
}

void SimdBatch::set_armature(std::span<const int> env_ids, const RowMatrix& armature) {
  const std::vector<int> es = envs(env_ids);
  check_shape(armature, es.size(), model_->nv, "armature");
  for (size_t j = 0; j < es.size(); ++j) {
    try {
      with_armature(*model_, row_of(armature, j).transpose());  // the model's own check
    } catch (const std::invalid_argument& e) {
      rethrow_for_env(es[j], e);
    }
  }
  for (size_t j = 0; j < es.size(); ++j)
    for (int d = 0; d < model_->nv; ++d)
      set_parameter(es[j], dof_index(d, simd::armature), row_of(armature, j)[d]);
}

namespace {

struct Inertial {
  double mass;
  Vec3 com;
  Mat3 inertia;
};

}  // namespace

static Inertial packed_inertial(const SimdBatch& b, int e, int link, int nv,
                                double (SimdBatch::*get)(int, int) const) {
  auto x = [&](int f) {
    return (b.*get)(e, nv * simd::kDofParameters + link * simd::kLinkParameters + f);
  };
  Inertial out;
  out.mass = x(simd::mass);
  out.com = Vec3(x(simd::com_x), x(simd::com_y), x(simd::com_z));
  out.inertia << x(simd::inertia_xx), x(simd::inertia_xy), x(simd::inertia_xz), x(simd::inertia_xy),
      x(simd::inertia_yy), x(simd::inertia_yz), x(simd::inertia_xz), x(simd::inertia_yz),
      x(simd::inertia_zz);
  return out;
}

void SimdBatch::set_link_mass(std::span<const int> env_ids, int link, const VecX& mass,
                              bool scale_inertia) {
  set_link_com_or_mass(env_ids, link, &mass, nullptr, scale_inertia);
}

void SimdBatch::set_link_com(std::span<const int> env_ids, int link, const RowMatrix& com) {
  set_link_com_or_mass(env_ids, link, nullptr, &com, false);
}

void SimdBatch::set_link_com_or_mass(std::span<const int> env_ids, int link, const VecX* mass,
                                     const RowMatrix* com, bool scale_inertia) {
  const std::vector<int> es = envs(env_ids);
  const int L = model_->num_links(), nv = model_->nv;
  if (link < 0 || link >= L)
    throw std::invalid_argument("SimdBatch: link = " + std::to_string(link) +
                                " is out of range [0, " + std::to_string(L) + ")");
  if (mass && mass->size() != 1 && mass->size() != static_cast<Eigen::Index>(es.size()))
    throw std::invalid_argument("SimdBatch: mass has " + std::to_string(mass->size()) +
                                " values, expected " + std::to_string(es.size()) + " or 1");
  if (com) check_shape(*com, es.size(), 3, "com");
  std::vector<Inertial> next(es.size());
  const std::string& name = model_->links[static_cast<size_t>(link)].name;
  for (size_t j = 0; j < es.size(); ++j) {
    Inertial x = packed_inertial(*this, es[j], link, nv, &SimdBatch::parameter);
    try {
      if (mass) {
        const double m = (*mass)[mass->size() == 1 ? 0 : static_cast<Eigen::Index>(j)];
        if (scale_inertia && !(x.mass > 0.0))
          throw std::invalid_argument("link '" + name +
                                      "' has mass 0: its inertia cannot scale "
                                      "with the mass (give scale_inertia = false)");
        if (scale_inertia) x.inertia *= m / x.mass;
        x.mass = m;
      }
      if (com) x.com = row_of(*com, j).transpose();
      with_link_inertial(*model_, link, x.mass, x.com, x.inertia);  // the model's own check
    } catch (const std::invalid_argument& e) {
      rethrow_for_env(es[j], e);
    }
    next[j] = x;
  }
  for (size_t j = 0; j < es.size(); ++j) {
    const int base = nv * simd::kDofParameters + link * simd::kLinkParameters;
    const Inertial& x = next[j];
    const double values[simd::kLinkParameters] = {
        x.mass,          x.com[0],        x.com[1],        x.com[2],        x.inertia(0, 0),
        x.inertia(1, 1), x.inertia(2, 2), x.inertia(0, 1), x.inertia(0, 2), x.inertia(1, 2)};
    for (int f = 0; f < simd::kLinkParameters; ++f) set_parameter(es[j], base + f, values[f]);
  }
}

void SimdBatch::reset(std::span<const int> env_ids, const std::optional<RowMatrix>& q,
                      const std::optional<RowMatrix>& qd) {
  const std::vector<int> es = envs(env_ids);
  if (q) set_q(es, *q);  // checked before anything else changes
  if (qd) check_shape(*qd, es.size(), model_->nv, "qd");
  if (qd && !qd->allFinite()) throw std::invalid_argument("SimdBatch: qd holds a non-finite value");
  for (size_t j = 0; j < es.size(); ++j) {
    const int e = es[j];
    if (!q) q_.row(e) = initial_q_.transpose();
    if (qd)
      qd_.row(e) = row_of(*qd, j);
    else
      qd_.row(e).setZero();
    applied_force_.row(e).setZero();
    drive_force_.row(e).setZero();
    limit_force_.row(e).setZero();
    friction_force_.row(e).setZero();
    velocity_limit_force_.row(e).setZero();
    step_count_[static_cast<size_t>(e)] = 0;
    time_[static_cast<size_t>(e)] = 0.0;
    diverged_[static_cast<size_t>(e)].reset();
    impl_->engine.clear_stop(e);
  }
}

RowMatrix SimdBatch::stiffness() const {
  return dof_parameter(simd::stiffness);
}
RowMatrix SimdBatch::damping() const {
  return dof_parameter(simd::damping);
}
RowMatrix SimdBatch::target_position() const {
  return dof_parameter(simd::target_position);
}
RowMatrix SimdBatch::target_velocity() const {
  return dof_parameter(simd::target_velocity);
}
RowMatrix SimdBatch::lower_limit() const {
  return dof_parameter(simd::lower);
}
RowMatrix SimdBatch::upper_limit() const {
  return dof_parameter(simd::upper);
}
RowMatrix SimdBatch::armature() const {
  return dof_parameter(simd::armature);
}

VecX SimdBatch::link_mass(int link) const {
  VecX out(count_);
  for (int e = 0; e < count_; ++e)
    out[e] = packed_inertial(*this, e, link, model_->nv, &SimdBatch::parameter).mass;
  return out;
}

RowMatrix SimdBatch::link_com(int link) const {
  RowMatrix out(count_, 3);
  for (int e = 0; e < count_; ++e)
    out.row(e) = packed_inertial(*this, e, link, model_->nv, &SimdBatch::parameter).com.transpose();
  return out;
}

Simulation SimdBatch::simulation(int i) const {
  if (i < 0 || i >= count_)
    throw std::invalid_argument("SimdBatch: environment " + std::to_string(i) +
                                " is out of range [0, " + std::to_string(count_) + ")");
  const Model& m = *model_;
  Model variant = with_armature(m, armature().row(i).transpose());
  for (int link = 0; link < m.num_links(); ++link) {
    const Inertial x = packed_inertial(*this, i, link, m.nv, &SimdBatch::parameter);
    variant = with_link_inertial(variant, link, x.mass, x.com, x.inertia);
  }
  Simulation sim = impl_->prototype;
  sim.set_model(std::make_shared<const Model>(std::move(variant)));
  for (int d = 0; d < m.nv; ++d) {
    sim.set_drive(d, packed_drive(*this, i, d, &SimdBatch::parameter));
    sim.set_joint_limits(d, parameter(i, dof_index(d, simd::lower)),
                         parameter(i, dof_index(d, simd::upper)));
    sim.set_joint_friction(d, JointFriction{parameter(i, dof_index(d, simd::static_friction)),
                                            parameter(i, dof_index(d, simd::dynamic_friction)),
                                            parameter(i, dof_index(d, simd::viscous_friction))});
  }
  sim.restore_state(q_.row(i).transpose(), drive_force_.row(i).transpose(),
                    limit_force_.row(i).transpose(), friction_force_.row(i).transpose(),
                    velocity_limit_force_.row(i).transpose());
  sim.set_qd(qd_.row(i).transpose());
  sim.set_applied_force(applied_force_.row(i).transpose());
  sim.set_clock(time_[static_cast<size_t>(i)], step_count_[static_cast<size_t>(i)]);
  return sim;
}

void SimdBatch::step(int count) {
  if (count < 0)
    throw std::invalid_argument("SimdBatch: step count = " + std::to_string(count) +
                                " must be >= 0");
  if (count == 0) return;
  simd::LaneEngine& engine = impl_->engine;
  simd::Block arrays;
  arrays.q = q_.data(), arrays.qd = qd_.data(), arrays.applied = applied_force_.data();
  arrays.drive_force = drive_force_.data(), arrays.limit_force = limit_force_.data();
  arrays.friction_force = friction_force_.data();
  arrays.velocity_limit_force = velocity_limit_force_.data();
  arrays.step_count = step_count_.data(), arrays.time = time_.data();
  engine.run(arrays, count, isa_, effective_num_threads());
  // Messages for the environments that stopped in this call, as Simulation words them.
  int first = -1, stopped = 0;
  for (int e = 0; e < count_; ++e) {
    if (!engine.stopped_now(e)) continue;
    const long steps = step_count_[static_cast<size_t>(e)];
    diverged_[static_cast<size_t>(e)] = SimdDivergence{
        steps + 1, engine.divergence_message(e, *model_, steps, time_[static_cast<size_t>(e)])};
    if (first < 0) first = e;
    ++stopped;
  }
  if (first >= 0)
    throw DivergenceError(
        "SimdBatch: environment " + std::to_string(first) + " (" + std::to_string(stopped) +
        " of " + std::to_string(count_) +
        " environments diverged): " + diverged_[static_cast<size_t>(first)]->message);
}

}  // namespace featherdrive
