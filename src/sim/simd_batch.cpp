// The SIMD Batch's settings, checks and dispatch; the step itself is simd_lane_step.hpp.
// docs/simd_batch.md.
#include "featherdrive/sim/simd_batch.hpp"

#include <tbb/blocked_range.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <xsimd/config/xsimd_arch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <sstream>
#include <stdexcept>

#include "featherdrive/core/format.hpp"
#include "featherdrive/model/model_variant.hpp"
#include "simd_plan.hpp"

namespace featherdrive {

using simd::kGroup;

namespace simd {

Layout make_layout(const Plan& p) {
  const int L = p.num_links, n = p.nv;
  Layout l;
  int at = 0;
  auto take = [&at](int count) {
    const int o = at;
    at += count;
    return o;
  };
  // Arrays whose lives do not overlap share room, so that a block's scratch stays in the core's
  // L2 cache (docs/simd_batch.md, "Scratch"): the response's W and G take the poses' place, the
  // whole-articulation response Lambda the articulated inertias', the sweeps' arrays those of
  // the velocities, bias forces and accelerations.
  l.R = take(9 * L), l.pos = take(3 * L), l.W = l.R, l.G = l.R + 6 * L;
  l.IA = take(21 * L), l.Lambda = l.IA;
  l.vel = take(6 * L), l.pA = take(6 * L), l.c = take(6 * L), l.acc = take(6 * L);
  l.dv = l.vel, l.subtree = l.pA, l.after = l.c, l.later = l.acc;
  l.S = take(6 * L), l.U = take(6 * L), l.D_inv = take(L), l.inverse_mass = take(L);
  l.q = take(p.nq), l.qd = take(n);
  l.tau = take(n), l.u = take(n), l.old_q = take(p.nq), l.old_qd = take(n), l.old_df = take(n);
  l.old_lf = take(n), l.old_ff = take(n), l.old_vf = take(n), l.df = take(n), l.lf = take(n),
  l.ff = take(n), l.vf = take(n), l.row = take(Layout::kRowFields * n);
  l.jimp = take(n), l.entry = take(n), l.saved = take(n), l.saved_tgs = take(n);
  l.zero = take(21);
  l.flags = take(2 * n);  // eight doubles a dof (a vector holds at least four)
  l.size = at;
  return l;
}

std::size_t scratch_doubles(const Plan& p) {
  return static_cast<std::size_t>(make_layout(p).size) * kGroup * kMaxInterleave;
}

}  // namespace simd

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
  if (!forced || !*forced) return available_simd_isas().back();
  for (SimdIsa isa : {SimdIsa::sse2, SimdIsa::avx2, SimdIsa::avx512})
    if (std::string(forced) == to_string(isa)) {
      check_isa(isa, "FEATHERDRIVE_SIMD");
      return isa;
    }
  throw std::invalid_argument(std::string("FEATHERDRIVE_SIMD = '") + forced +
                              "': expected sse2, avx2 or avx512");
}

struct SimdBatch::Impl {
  std::vector<simd::LinkConstants> links;
  std::vector<int> finish_after;
  simd::Plan plan;
  std::vector<double> parameters;  // packed in groups of kGroup environments
  std::vector<simd::Stop> stops;
  std::unique_ptr<bool[]> stopped_now;
  std::vector<std::vector<double>> scratch;  // one per thread, 64 bytes of slack for alignment
  std::unique_ptr<Simulation> prototype;     // settings shared by all (for simulation(i))
  // Kept between calls: a fresh arena makes its workers join again each call, and with a few
  // blocks a call is over before they do.
  std::unique_ptr<tbb::task_arena> arena;
  int arena_threads = 0;
  double* scratch_of(int thread) {
    auto address = reinterpret_cast<std::uintptr_t>(scratch[static_cast<size_t>(thread)].data());
    return reinterpret_cast<double*>((address + 63) & ~std::uintptr_t{63});
  }
};

namespace {

[[noreturn]] void unsupported(const std::string& what, const std::string& name,
                              const std::string& value) {
  throw std::invalid_argument("SimdBatch: " + what + " '" + name + "' has " + value +
                              ": not supported by the SIMD Batch (docs/simd_batch.md)");
}

// What the lane step does not simulate, refused with the setting and the joint or link.
void check_supported(const Simulation& s) {
  const Model& m = s.model();
  if (s.options().compat != Compat::none) unsupported("simulation", "options", "compat: physx");
  // The lanes step in lockstep: one lane's redone step would hold up every other.
  if (s.options().guard.enabled) unsupported("simulation", "options", "the step guard");
  for (const Link& link : m.links) {
    const bool one_dof =
        link.joint_type == JointType::revolute || link.joint_type == JointType::prismatic;
    if (!one_dof && link.joint_type != JointType::fixed)
      unsupported("joint", link.joint_name,
                  link.joint_type == JointType::floating ? "a floating base" : "a spherical joint");
  }
  for (int i = 0; i < m.num_links(); ++i) {
    const LinkParameters& lp = s.link_parameters(i);
    const LinkParameters none;
    if (lp.cfm_scale != none.cfm_scale || lp.linear_damping != none.linear_damping ||
        lp.angular_damping != none.angular_damping ||
        lp.max_linear_velocity != none.max_linear_velocity ||
        lp.max_angular_velocity != none.max_angular_velocity)
      unsupported("link", m.links[static_cast<size_t>(i)].name,
                  "link parameters (cfm_scale, damping or velocity limits)");
  }
  for (int d = 0; d < m.nv; ++d) {
    const std::string& joint = m.links[static_cast<size_t>(m.dof_link[d])].joint_name;
    if (s.friction_coefficient(d) != 0.0)
      unsupported("joint", joint,
                  "friction_coefficient " + format_double(s.friction_coefficient(d)));
    if (s.actuator_envelope(d).active()) unsupported("joint", joint, "an actuator envelope");
    if (s.has_actuator(d))  // "an explicit actuator" or "an implicit actuator"
      unsupported("joint", joint,
                  std::string("an ") + to_string(s.actuator(d).integration) + " actuator");
    if (s.drive_delay(d) != 0)
      unsupported("joint", joint, "drive delay " + std::to_string(s.drive_delay(d)));
  }
  // Nor contact rows: the robot would pass through the ground.
  if (s.ground().enabled && !m.shapes.empty())
    unsupported("simulation", "settings", "a ground with the model's collision shapes");
  if (s.contact_options().self_collision && m.shapes.size() > 1)
    unsupported("simulation", "settings", "self-collision between the model's shapes");
  // The lane step has no mimic rows: a prototype with one would run uncoupled.
  for (const MimicJoint& mimic : s.mimic_joints())
    unsupported("joint", m.links[static_cast<size_t>(m.dof_link[mimic.dof_a])].joint_name,
                "a mimic row (" + describe(m, mimic) + ")");
}

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
    : model_(prototype.model_ptr()),
      options_(prototype.options()),
      count_(count),
      impl_(std::make_unique<Impl>()) {
  if (count < 1 || count > Batch::kMaxSize)
    throw std::invalid_argument("SimdBatch: count = " + std::to_string(count) + " must be in [1, " +
                                std::to_string(Batch::kMaxSize) + "]");
  check_supported(prototype);
  isa_ = isa ? *isa : default_simd_isa();
  // Without a choice (argument or FEATHERDRIVE_SIMD), a batch smaller than a block of the widest
  // width takes a narrower one: fewer padding lanes, the same bits.
  const char* forced = std::getenv("FEATHERDRIVE_SIMD");
  if (!isa && !(forced && *forced))
    while (isa_ != SimdIsa::sse2 && simd_width(isa_) * 2 > count)
      isa_ = isa_ == SimdIsa::avx512 ? SimdIsa::avx2 : SimdIsa::sse2;
  check_isa(isa_, "SimdBatch: isa");
  const Model& m = *model_;
  const int L = m.num_links(), nv = m.nv, nq = m.nq;
  // The topology and joint constants.
  Impl& im = *impl_;
  im.links.resize(static_cast<size_t>(L));
  std::vector<char> later(static_cast<size_t>(L), 0);
  for (int i = 0; i < L; ++i) {
    const Link& link = m.links[static_cast<size_t>(i)];
    simd::LinkConstants& k = im.links[static_cast<size_t>(i)];
    k.parent = link.parent;
    k.type = link.joint_type == JointType::revolute    ? 1
             : link.joint_type == JointType::prismatic ? 2
                                                       : 0;
    k.v_index = link.v_index;
    k.q_index = link.q_index;
    for (int a = 0; a < 3; ++a) {
      k.axis[a] = link.axis[a];
      k.r[a] = link.tree_transform.r[a];
      for (int b = 0; b < 3; ++b) k.E[3 * a + b] = link.tree_transform.E(a, b);
      if (std::abs(link.axis[a]) == 1.0) {
        k.unit_axis = a;
        k.axis_sign = link.axis[a];
      }
    }
    k.tree_rotation_identity = link.tree_transform.E == Mat3::Identity();
    const Mat3& Ic = link.inertia_com;
    k.diagonal_inertia = Ic(0, 1) == 0.0 && Ic(0, 2) == 0.0 && Ic(1, 2) == 0.0;
    if (link.parent >= 0) {
      const Link& parent = m.links[static_cast<size_t>(link.parent)];
      k.first_child = parent.children.front() == i;
      k.last_child = parent.children.back() == i;
      later[static_cast<size_t>(i)] = !k.last_child || later[static_cast<size_t>(link.parent)];
    }
    k.later = later[static_cast<size_t>(i)];
    k.leaf = link.children.empty();
    k.finish_on_leave = k.type != 0 && !k.later;
    if (!k.finish_on_leave && (k.type != 0 || k.later)) im.finish_after.push_back(i);
  }
  simd::Plan& p = im.plan;
  p.num_links = L, p.nq = nq, p.nv = nv;
  p.links = im.links.data();
  p.finish_after = im.finish_after.data();
  p.num_finish_after = static_cast<int>(im.finish_after.size());
  p.entries = nv * simd::kDofParameters + L * simd::kLinkParameters;
  for (int a = 0; a < 3; ++a) p.gravity[a] = m.gravity[a];
  p.dt = options_.dt;
  p.tgs = options_.solver == SolverType::tgs;
  p.position_iterations = options_.position_iterations;
  p.velocity_iterations = options_.velocity_iterations;
  p.limit_erp = p.tgs ? 2.0 * std::sqrt(1.0 / p.position_iterations) : 0.8;  // step.cpp
  p.layout = simd::make_layout(p);
  // Parameters, every environment (and the padding up to a whole group) the prototype's.
  // Whole blocks of the widest width and interleave: simd::kMaxInterleave groups each.
  constexpr int kBlockGroups = simd::kMaxInterleave;
  const int groups = (count + kGroup * kBlockGroups - 1) / (kGroup * kBlockGroups) * kBlockGroups;
  im.parameters.assign(static_cast<size_t>(groups) * p.entries * kGroup, 0.0);
  std::vector<double> one(static_cast<size_t>(p.entries));
  for (int d = 0; d < nv; ++d) {
    const Drive& drive = prototype.drive(d);
    double* x = &one[static_cast<size_t>(dof_index(d, 0))];
    x[simd::has_drive] = drive.type != DriveType::none;
    x[simd::acceleration] = drive.type == DriveType::acceleration;
    x[simd::stiffness] = drive.stiffness;
    x[simd::damping] = drive.damping;
    x[simd::max_force] = drive.max_force;
    x[simd::max_impulse] = drive.max_impulse;
    x[simd::target_position] = drive.target_position;
    x[simd::target_velocity] = drive.target_velocity;
    x[simd::lower] = prototype.lower_limit(d);
    x[simd::upper] = prototype.upper_limit(d);
    x[simd::armature] = m.armature[d];
    const JointFriction& f = prototype.joint_friction(d);
    x[simd::static_friction] = f.static_effort;
    x[simd::dynamic_friction] = f.dynamic_effort;
    x[simd::viscous_friction] = f.viscous;
    x[simd::max_velocity] = prototype.max_joint_velocity(d);
    x[simd::wrapped] = prototype.settings().revolute_wrap[static_cast<size_t>(d)] ==
                       RevoluteWrap::wrapped;
    p.any_velocity_limit = p.any_velocity_limit || x[simd::max_velocity] < DofRows::kNoVelocityLimit;
  }
  for (int i = 0; i < L; ++i) {
    const Link& link = m.links[static_cast<size_t>(i)];
    double* x = &one[static_cast<size_t>(nv * simd::kDofParameters + i * simd::kLinkParameters)];
    x[simd::mass] = link.mass;
    for (int a = 0; a < 3; ++a) x[simd::com_x + a] = link.com[a];
    const Mat3& I = link.inertia_com;
    x[simd::inertia_xx] = I(0, 0), x[simd::inertia_yy] = I(1, 1), x[simd::inertia_zz] = I(2, 2);
    x[simd::inertia_xy] = I(0, 1), x[simd::inertia_xz] = I(0, 2), x[simd::inertia_yz] = I(1, 2);
  }
  for (int e = 0; e < groups * kGroup; ++e)
    for (int k = 0; k < p.entries; ++k)
      im.parameters[static_cast<size_t>(((e / kGroup) * p.entries + k) * kGroup + e % kGroup)] =
          one[static_cast<size_t>(k)];
  // States.
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
  im.stops.resize(static_cast<size_t>(count));
  im.stopped_now = std::make_unique<bool[]>(static_cast<size_t>(count));
  im.prototype = std::make_unique<Simulation>(prototype);
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
  const int entries = impl_->plan.entries;
  return impl_
      ->parameters[static_cast<size_t>(((env / kGroup) * entries + index) * kGroup + env % kGroup)];
}

void SimdBatch::set_parameter(int env, int index, double value) {
  const int entries = impl_->plan.entries;
  impl_->parameters[static_cast<size_t>(((env / kGroup) * entries + index) * kGroup +
                                        env % kGroup)] = value;
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
  Simulation& check = *impl_->prototype;
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
    impl_->stops[static_cast<size_t>(e)] = simd::Stop{};
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
  Simulation sim = *impl_->prototype;
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
  Impl& im = *impl_;
  const int K = simd::interleave(width(), count_, effective_num_threads());
  const int W = width() * K;  // lanes of a block
  const int blocks = (count_ + W - 1) / W;
  const int threads = std::min(effective_num_threads(), blocks);
  const std::size_t doubles = simd::scratch_doubles(im.plan) + 8;
  if (static_cast<int>(im.scratch.size()) < threads)
    im.scratch.resize(static_cast<size_t>(threads));
  for (auto& s : im.scratch)
    if (s.size() < doubles) s.assign(doubles, 0.0);
  std::fill(im.stopped_now.get(), im.stopped_now.get() + count_, false);
  auto run = [&](int block, double* scratch) {
    simd::Block b;
    b.env0 = block * W;
    b.interleave = K;
    b.valid = std::min(W, count_ - b.env0);
    b.q = q_.data(), b.qd = qd_.data(), b.applied = applied_force_.data();
    b.drive_force = drive_force_.data(), b.limit_force = limit_force_.data();
    b.friction_force = friction_force_.data();
    b.velocity_limit_force = velocity_limit_force_.data();
    b.parameters = im.parameters.data();
    b.step_count = step_count_.data(), b.time = time_.data();
    b.stop = im.stops.data(), b.stopped_now = im.stopped_now.get();
    switch (isa_) {
      case SimdIsa::sse2:
        simd::run_block_sse2(im.plan, b, scratch, count);
        break;
      case SimdIsa::avx2:
        simd::run_block_avx2(im.plan, b, scratch, count);
        break;
      case SimdIsa::avx512:
        simd::run_block_avx512(im.plan, b, scratch, count);
        break;
    }
  };
  if (threads <= 1) {
    for (int block = 0; block < blocks; ++block) run(block, im.scratch_of(0));
  } else {
    if (!im.arena || im.arena_threads != threads) {
      im.arena = std::make_unique<tbb::task_arena>(threads);
      im.arena_threads = threads;
    }
    im.arena->execute([&] {
      tbb::parallel_for(tbb::blocked_range<int>(0, blocks), [&](const tbb::blocked_range<int>& r) {
        double* scratch = im.scratch_of(tbb::this_task_arena::current_thread_index());
        for (int block = r.begin(); block < r.end(); ++block) run(block, scratch);
      });
    });
  }
  // Messages for the environments that stopped in this call, as Simulation words them.
  int first = -1, stopped = 0;
  for (int e = 0; e < count_; ++e) {
    if (!im.stopped_now[static_cast<size_t>(e)]) continue;
    const simd::Stop& s = im.stops[static_cast<size_t>(e)];
    static const char* const kQuantity[] = {
        "",           "velocity qd",          "drive force", "limit force",
        "friction force", "velocity limit force", "position q"};
    std::ostringstream m;
    m.precision(6);
    m << "simulation diverged at step " << step_count_[static_cast<size_t>(e)] + 1
      << " (t = " << time_[static_cast<size_t>(e)] << " s): joint '"
      << model_->links[static_cast<size_t>(model_->dof_link[s.dof])].joint_name << "' "
      << kQuantity[s.quantity] << " = " << s.value
      << "; the state is left as it was before this step (lower dt or the gains)";
    diverged_[static_cast<size_t>(e)] =
        SimdDivergence{step_count_[static_cast<size_t>(e)] + 1, m.str()};
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
