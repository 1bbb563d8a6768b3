#include "lane_engine.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <sstream>

#include "featherdrive/constraint/dof_rows.hpp"
#include "featherdrive/constraint/spherical_axes.hpp"
#include "featherdrive/core/format.hpp"
#include "featherdrive/solver/sweep_walk.hpp"
#include "workspace.hpp"

namespace featherdrive::simd {

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
  l.old_lf = take(n), l.old_ff = take(n), l.old_vf = take(n), l.df = take(n), l.lf = take(n);
  l.ff = take(n), l.vf = take(n), l.cg = take(3 * L), l.cfm = take(L), l.row = take(Layout::kRowFields * n);
  l.jimp = take(n), l.entry = take(n), l.saved = take(n), l.saved_tgs = take(n);
  l.zero = take(21);
  l.chain_pS = take(L), l.chain_pi = take(L), l.chain_base = take(L);
  l.mimic_row = take(3 * p.num_mimic), l.mimic_change = take(p.num_mimic * p.num_mimic_dofs);
  l.mimic_velocity = take(p.num_mimic_dofs), l.given = take(n);
  l.af = take(n), l.before = take(n), l.change = take(n);
  const int physx =
      p.physx_prismatic || p.physx_floating || p.physx_spherical || p.physx_contacts ? 1 : 0;
  l.start_com = take(physx * 3 * L), l.com_velocity = take(physx * 3 * L);
  l.bias_w = take(physx * 3 * L), l.bias_v = take(physx * 3 * L), l.turn = take(physx * 3 * L);
  l.now_R = take(physx * 9 * L), l.now_pos = take(physx * 3 * L), l.row_bias = take(physx * n);
  const int floating = p.floating_base ? 1 : 0;
  l.root_R = take(floating * 9), l.root_Rq = take(floating * 9), l.root_U = take(floating * 36);
  l.root_D_inv = take(floating * 36);
  const int ball = p.any_spherical ? 1 : 0;
  l.ball_S = take(ball * 18 * L), l.ball_U = take(ball * 18 * L), l.ball_W = take(ball * 18 * L);
  l.ball_D_inv = take(ball * 9 * L), l.ball_response = take(ball * 9 * L);
  l.ball_w = take(p.physx_spherical ? 3 * L : 0);
  const int pf = p.physx_floating ? 1 : 0;
  l.start_R = take(pf * 9 * L), l.start_pos = take(pf * 3 * L), l.link_force = take(pf * 6 * L);
  l.targets = take(pf * 10), l.compound_inverse = take(pf * 9), l.vel_w = take(pf * 3 * L);
  l.vel_v = take(pf * 3 * L), l.now_com = take(pf * 3 * L), l.qd_position = take(pf * n);
  l.contact_vel = take(p.contacts ? 6 * L : 0);
  l.contact_bias = take(p.physx_contacts ? 6 * L : 0);
  l.contact_motion = take(p.physx_contacts ? 6 * L : 0);
  l.rk = take(RowKinds::size * n), l.old_rk = take(RowKinds::size * n);
  l.flags = take(16 * n);  // 16 doubles a dof (a one-lane block's vector is one double)
  l.size = at;
  return l;
}

namespace {

// LinkConstants::parent_one_dof, chain_in and chain_up, from the joint types, the links with
// contacts and the flags set before.
void set_chain_flags(std::vector<LinkConstants>& links) {
  auto one_dof = [](const LinkConstants& l) { return l.type == 1 || l.type == 2; };
  for (size_t i = 0; i < links.size(); ++i) {
    LinkConstants& k = links[i];
    const LinkConstants* parent = k.parent >= 0 ? &links[static_cast<size_t>(k.parent)] : nullptr;
    k.parent_one_dof = parent && one_dof(k) && one_dof(*parent);
    k.chain_in = k.parent_one_dof && k.parent + 1 == static_cast<int>(i) && !parent->contacts;
    k.chain_up = sweep_walk::chain_up<false>(k.finish_on_leave, k.parent, k.parent_one_dof,
                                             k.first_child, k.last_child);
  }
  // later_read, children first (they come after their parent): a child finished after the sweep
  // reads its parent's E where both have a later subtree (LaneStep::finish_link).
  for (LinkConstants& k : links) k.later_read = false, k.finish_down = false;
  for (size_t i = links.size(); i-- > 0;) {
    const LinkConstants& k = links[i];
    const bool finished_after = !k.finish_on_leave && (k.type != 0 || k.later);
    const bool reads = finished_after && k.type != 3 && (k.type != 0 || k.later_read);
    if (reads && k.later && k.parent >= 0 && links[static_cast<size_t>(k.parent)].later)
      links[static_cast<size_t>(k.parent)].later_read = true;
    if (k.parent < 0) continue;
    LinkConstants& p = links[static_cast<size_t>(k.parent)];
    p.finish_down = one_dof(k) && one_dof(p) && k.first_child && k.last_child && k.later &&
                    !k.finish_on_leave && !p.finish_on_leave && k.parent + 1 == static_cast<int>(i);
  }
}

}  // namespace

std::size_t scratch_doubles(const Plan& p) {
  return static_cast<std::size_t>(make_layout(p).size) * kGroup * kMaxInterleave;
}

// Groups of fewer environments step in one-lane blocks: one environment's one-lane block was
// 1.5 to 1.9 times as fast as an SSE2 block of two vectors, two environments' 0.66 to 0.92 times
// (docs/benchmarks.md, "One-lane blocks").
constexpr int kOneLaneBelow = 2;

SimdIsa lane_isa(int count) {
  SimdIsa isa = default_simd_isa();
  const char* forced = std::getenv("FEATHERDRIVE_SIMD");
  if (!(forced && *forced))
    while (isa != SimdIsa::sse2 && simd_width(isa) * 2 > count)
      isa = isa == SimdIsa::avx512 ? SimdIsa::avx2 : SimdIsa::sse2;
  return isa;
}

bool one_lane_blocks(int count) {
  const char* forced = std::getenv("FEATHERDRIVE_SIMD");
  if (forced && *forced) return std::strcmp(forced, "one") == 0;
  return count < kOneLaneBelow;
}

PlanKey::PlanKey(const SimulationOptions& o, const std::vector<MimicJoint>& mimic,
                 const std::vector<char>& shapes)
    : dt(o.dt),
      solver(o.solver),
      position_iterations(o.position_iterations),
      velocity_iterations(o.velocity_iterations),
      compat(o.compat),
      guarded(o.guard.enabled),
      mimic_joints(mimic),
      shape_links(shapes) {}

bool PlanKey::matches(const SimulationOptions& o, const std::vector<MimicJoint>& mimic,
                      const std::vector<char>& shapes) const {
  return o.dt == dt && o.solver == solver && o.position_iterations == position_iterations &&
         o.velocity_iterations == velocity_iterations && o.compat == compat &&
         o.guard.enabled == guarded && same_mimic_dofs(mimic, mimic_joints) &&
         shapes == shape_links;
}

LaneEngine::LaneEngine(const Simulation& prototype, int count) : count_(count) {
  const Model& m = prototype.model();
  const int L = m.num_links(), nv = m.nv;
  // The topology and joint constants.
  links_.resize(static_cast<size_t>(L));
  std::vector<char> later(static_cast<size_t>(L), 0);
  for (int i = 0; i < L; ++i) {
    const Link& link = m.links[static_cast<size_t>(i)];
    LinkConstants& k = links_[static_cast<size_t>(i)];
    k.parent = link.parent;
    k.type = link.joint_type == JointType::revolute    ? 1
             : link.joint_type == JointType::prismatic ? 2
             : link.joint_type == JointType::floating  ? 3
             : link.joint_type == JointType::spherical ? 4
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
    const Quat frame(Mat3(link.tree_transform.E.transpose()));  // as integrate_root_about_com's
    k.frame_q[0] = frame.w(), k.frame_q[1] = frame.x(), k.frame_q[2] = frame.y();
    k.frame_q[3] = frame.z();
    const Mat3& Ic = link.inertia_com;
    k.diagonal_inertia = Ic(0, 1) == 0.0 && Ic(0, 2) == 0.0 && Ic(1, 2) == 0.0;
    if (link.parent >= 0) {
      const Link& parent = m.links[static_cast<size_t>(link.parent)];
      k.first_child = parent.children.front() == i;
      k.last_child = parent.children.back() == i;
      later[static_cast<size_t>(i)] = !k.last_child || later[static_cast<size_t>(link.parent)];
    }
    k.later = later[static_cast<size_t>(i)];
    first_child_free_.push_back(k.first_child);
    k.leaf = link.children.empty();
    // A floating root's six dofs are finished after the sweep, as a multi-dof joint's.
    k.finish_on_leave = (k.type == 1 || k.type == 2) && !k.later;
    if (!k.finish_on_leave && (k.type != 0 || k.later)) finish_after_.push_back(i);
  }
  set_chain_flags(links_);
  // The mimic rows and the dofs they couple, in MimicSolver's order.
  mimic_joints_ = prototype.mimic_joints();
  for (const MimicJoint& mj : mimic_joints_) {
    auto slot = [&](int dof) {
      const auto it = std::find(mimic_dofs_.begin(), mimic_dofs_.end(), dof);
      if (it != mimic_dofs_.end()) return static_cast<int>(it - mimic_dofs_.begin());
      mimic_dofs_.push_back(dof);
      return static_cast<int>(mimic_dofs_.size()) - 1;
    };
    MimicConstants c;
    c.dof_a = mj.dof_a, c.dof_b = mj.dof_b;
    c.q_a = m.links[static_cast<size_t>(m.dof_link[mj.dof_a])].q_index;
    c.q_b = m.links[static_cast<size_t>(m.dof_link[mj.dof_b])].q_index;
    c.slot_a = slot(mj.dof_a);
    c.slot_b = slot(mj.dof_b);
    mimic_.push_back(c);
  }
  const SimulationOptions& o = prototype.options();
  Plan& p = plan_;
  p.num_mimic = static_cast<int>(mimic_.size());
  p.num_mimic_dofs = static_cast<int>(mimic_dofs_.size());
  p.mimic = mimic_.data();
  p.mimic_dofs = mimic_dofs_.data();
  p.num_links = L, p.nq = m.nq, p.nv = nv;
  p.floating_base = m.floating_base();
  for (const Link& link : m.links)
    p.any_spherical = p.any_spherical || link.joint_type == JointType::spherical;
  p.links = links_.data();
  p.finish_after = finish_after_.data();
  p.num_finish_after = static_cast<int>(finish_after_.size());
  p.entries =
      nv * kDofParameters + L * kLinkParameters + p.num_mimic * kMimicParameters + kEnvParameters;
  p.dt = o.dt;
  p.tgs = o.solver == SolverType::tgs;
  p.position_iterations = o.position_iterations;
  p.velocity_iterations = o.velocity_iterations;
  p.limit_erp = p.tgs ? 2.0 * std::sqrt(1.0 / p.position_iterations) : 0.8;  // step.cpp
  // compat physx's defaults are settings; on 1-dof joints its departures act at prismatic rows
  // (a revolute row's link bias is 0, PD-2) and at a floating root (its momentum and pose).
  if (o.compat == Compat::physx) {
    p.physx = true;
    for (const Link& link : m.links)
      p.physx_prismatic = p.physx_prismatic || link.joint_type == JointType::prismatic;
    p.physx_floating = p.floating_base;
    p.physx_spherical = p.any_spherical;
  }
  shape_links_.assign(static_cast<size_t>(L), 0);
  p.layout = make_layout(p);
  // Every environment (and the padding up to whole blocks of the widest width and interleave,
  // kMaxInterleave groups each) starts with the prototype's parameters.
  const int groups = (count + kGroup * kMaxInterleave - 1) / (kGroup * kMaxInterleave) *
                     kMaxInterleave;
  parameters_.assign(static_cast<size_t>(groups) * p.entries * kGroup, 0.0);
  tables_.nv = nv;
  tables_.lookup.resize(static_cast<size_t>(groups) * kGroup * static_cast<size_t>(nv));
  for (int e = 0; e < groups * kGroup; ++e) {
    pack_drives(e, prototype);
    pack_joints(e, prototype);
    pack_model(e, m);
  }
  stops_.resize(static_cast<size_t>(count));
  messages_.resize(static_cast<size_t>(count));
  stopped_now_ = std::make_unique<bool[]>(static_cast<size_t>(count));
}

void LaneEngine::set_contacts(bool on, const std::vector<char>& shape_links) {
  if (on == plan_.contacts && shape_links == shape_links_) return;
  plan_.contacts = on;
  plan_.physx_contacts = on && plan_.physx;
  shape_links_ = shape_links;
  for (size_t i = 0; i < links_.size(); ++i) {
    LinkConstants& k = links_[i];
    k.contacts = on && shape_links_[i];
    // gauss_seidel.cpp's set_contact_links: the first child of a link with contacts adds to the
    // pA they started.
    k.first_child = first_child_free_[i] && !(k.parent >= 0 && links_[static_cast<size_t>(k.parent)].contacts);
  }
  set_chain_flags(links_);
  plan_.layout = make_layout(plan_);
}

void LaneEngine::pack_drives(int env, const Simulation& sim) {
  for (int d = 0; d < plan_.nv; ++d) {
    const Drive& drive = sim.drive(d);
    const int x = d * kDofParameters;
    set_parameter(env, x + has_drive, drive.type != DriveType::none);
    set_parameter(env, x + acceleration, drive.type == DriveType::acceleration);
    set_parameter(env, x + stiffness, drive.stiffness);
    set_parameter(env, x + damping, drive.damping);
    set_parameter(env, x + max_force, drive.max_force);
    set_parameter(env, x + max_impulse, drive.max_impulse);
    set_parameter(env, x + target_position, drive.target_position);
    set_parameter(env, x + target_velocity, drive.target_velocity);
    // An implicit actuator: its law's row in the drive's place (a dof with one has no drive).
    const ExplicitActuators& actuators = sim.actuators();
    const bool implicit = actuators.implicit(d);
    static const ExplicitActuator kNone;  // (a reference: a copy would copy the table)
    const ExplicitActuator& a = implicit ? actuators.actuator(d) : kNone;
    set_parameter(env, x + implicit_actuator, implicit);
    const double kind = a.kind == ActuatorKind::dc_motor ? 1.0
                        : a.kind == ActuatorKind::remotized_pd ? 2.0
                                                               : 0.0;
    set_parameter(env, x + actuator_kind, kind);
    set_parameter(env, x + actuator_stiffness, a.stiffness);
    set_parameter(env, x + actuator_damping, a.damping);
    set_parameter(env, x + actuator_effort_limit, a.effort_limit);
    set_parameter(env, x + actuator_saturation, a.saturation_effort);
    set_parameter(env, x + actuator_velocity_limit, a.velocity_limit);
    set_command(env, d, implicit ? actuators.command_seen(d) : ActuatorCommand{});
    // Copied into room kept from before where it fits: a repack allocates nothing then.
    tables_.lookup[static_cast<size_t>(env) * plan_.nv + d] = a.lookup;
    // Set, never cleared, as any_velocity_limit: without one the outputs change no bit.
    plan_.any_implicit_actuator = plan_.any_implicit_actuator || implicit;
  }
}

void LaneEngine::set_command(int env, int dof, const ActuatorCommand& command) {
  const int x = dof * kDofParameters;
  set_parameter(env, x + command_position, command.position);
  set_parameter(env, x + command_velocity, command.velocity);
  set_parameter(env, x + command_effort, command.effort);
}

double table_effort_limit(const ActuatorTables& tables, int env, int dof, double x) {
  return lookup_effort_limit(tables.lookup[static_cast<size_t>(env) * tables.nv + dof], x);
}

void LaneEngine::pack_joints(int env, const Simulation& sim) {
  for (int d = 0; d < plan_.nv; ++d) {
    const int x = d * kDofParameters;
    set_parameter(env, x + lower, sim.lower_limit(d));
    set_parameter(env, x + upper, sim.upper_limit(d));
    const JointFriction& f = sim.joint_friction(d);
    set_parameter(env, x + static_friction, f.static_effort);
    set_parameter(env, x + dynamic_friction, f.dynamic_effort);
    set_parameter(env, x + viscous_friction, f.viscous);
    const double vmax = sim.max_joint_velocity(d);
    set_parameter(env, x + max_velocity, vmax);
    // Set, never cleared: with no velocity over its limit the scaling changes no bit.
    plan_.any_velocity_limit = plan_.any_velocity_limit || vmax < DofRows::kNoVelocityLimit;
    set_parameter(env, x + wrapped,
                  sim.settings().revolute_wrap[static_cast<size_t>(d)] == RevoluteWrap::wrapped);
    const ActuatorEnvelope& e = sim.actuator_envelope(d);
    set_parameter(env, x + envelope_max_effort, e.max_effort);
    set_parameter(env, x + envelope_max_velocity, e.max_actuator_velocity);
    set_parameter(env, x + envelope_gradient, e.speed_effort_gradient);
    set_parameter(env, x + envelope_resistance, e.velocity_dependent_resistance);
    const double coefficient = sim.friction_coefficient(d);
    set_parameter(env, x + friction_coefficient, coefficient);
    plan_.any_transmission_friction = plan_.any_transmission_friction || coefficient > 0.0;
    // The row kinds: whether the dof has each (K::active, here, not in the lane units), their
    // fields.
    const MatX& kinds = sim.settings().row_parameters;
    for (int f = 0; f < RowKinds::fields; ++f)
      set_parameter(env, x + row_kind_fields + f, kinds(d, f));
    for (const RowKindInfo& kind : row_kinds()) {
      std::array<double, RowKinds::fields> values{};
      for (size_t j = 0; j < kind.fields.size(); ++j)
        values[j] = kinds(d, kind.offset + static_cast<Eigen::Index>(j));
      const bool on = dof_has_rows(sim.model(), d) && kind.active({values.data(), kind.fields.size()});
      set_parameter(env, x + row_kind_on + kind.index, on);
      plan_.any_row_kinds = plan_.any_row_kinds || on;  // set, never cleared, as the others
    }
  }
  for (int i = 0; i < plan_.num_links; ++i) {
    const LinkParameters& lp = sim.link_parameters(i);
    const int x = plan_.nv * kDofParameters + i * kLinkParameters;
    set_parameter(env, x + link_cfm_scale, lp.cfm_scale);
    set_parameter(env, x + link_linear_damping, lp.linear_damping);
    set_parameter(env, x + link_angular_damping, lp.angular_damping);
    set_parameter(env, x + link_max_linear_velocity, lp.max_linear_velocity);
    set_parameter(env, x + link_max_angular_velocity, lp.max_angular_velocity);
    // Set, never cleared, as any_velocity_limit: zero damping and no limit change no bit.
    plan_.any_link_damping = plan_.any_link_damping || lp.linear_damping > 0.0 ||
                             lp.angular_damping > 0.0 || std::isfinite(lp.max_linear_velocity) ||
                             std::isfinite(lp.max_angular_velocity);
    plan_.any_cfm = plan_.any_cfm || lp.cfm_scale > 0.0;
  }
  // The mimic rows' dofs are the plan's (same_mimic_dofs); their parameters are the lane's.
  const std::vector<MimicJoint>& mimic = sim.mimic_joints();
  for (int j = 0; j < std::min(plan_.num_mimic, static_cast<int>(mimic.size())); ++j) {
    const MimicJoint& mj = mimic[static_cast<size_t>(j)];
    const int x = plan_.nv * kDofParameters + plan_.num_links * kLinkParameters +
                  j * kMimicParameters;
    set_parameter(env, x + mimic_gear_ratio, mj.gear_ratio);
    set_parameter(env, x + mimic_offset, mj.offset);
    set_parameter(env, x + mimic_natural_frequency, mj.natural_frequency);
    set_parameter(env, x + mimic_damping_ratio, mj.damping_ratio);
  }
}

void spherical_axes(const double* q, const double* target, const double* driven, double* position,
                    double* error) {
  const Quat Q = Quat(q[0], q[1], q[2], q[3]).normalized();  // as spherical_rows.cpp's
  const Vec3 x = spherical_joint_positions(Q);
  const Vec3 e = spherical_drive_error(Q, Vec3(target[0], target[1], target[2]),
                                       {driven[0] != 0.0, driven[1] != 0.0, driven[2] != 0.0});
  for (int k = 0; k < 3; ++k) position[k] = x[k], error[k] = e[k];
}

void rotation_quaternion(const double* m, double* q) {
  Mat3 M;
  M << m[0], m[1], m[2], m[3], m[4], m[5], m[6], m[7], m[8];
  Quat Q(M);
  Q.normalize();
  if (Q.coeffs().dot(Eigen::Vector4d(q[1], q[2], q[3], q[0])) < 0.0) Q.coeffs() = -Q.coeffs();
  q[0] = Q.w(), q[1] = Q.x(), q[2] = Q.y(), q[3] = Q.z();
}

void unpack_guard_rows(const double* rows, int nv, std::vector<GuardRow>& out) {
  for (int d = 0; d < nv; ++d) {
    const double* x = rows + static_cast<size_t>(d) * kGuardFields;
    GuardRow& g = out[static_cast<size_t>(d)];
    g.drive_impulse = x[guard_drive];
    g.low_impulse = x[guard_low];
    g.high_impulse = x[guard_high];
    g.friction_impulse = x[guard_friction];
    g.transmission_friction_applied = x[guard_transmission];
    g.velocity_limit_impulse = x[guard_velocity_limit];
    g.response = x[guard_response];
    g.max_impulse = x[guard_max_impulse];
    g.has_drive = x[guard_has_drive] != 0.0;
    g.has_envelope = x[guard_has_envelope] != 0.0;
    for (int k = 0; k < RowKinds::size; ++k) g.kind_impulse[static_cast<size_t>(k)] = x[guard_row_kinds + k];
  }
}

void LaneEngine::stop_with(int e, const std::string& message) {
  stops_[static_cast<size_t>(e)] = Stop{8, -1, 0.0};
  stopped_now_[static_cast<size_t>(e)] = true;
  messages_[static_cast<size_t>(e)] = message;
}

bool same_mimic_dofs(const std::vector<MimicJoint>& a, const std::vector<MimicJoint>& b) {
  if (a.size() != b.size()) return false;
  for (size_t j = 0; j < a.size(); ++j)
    if (a[j].dof_a != b[j].dof_a || a[j].dof_b != b[j].dof_b) return false;
  return true;
}

void LaneEngine::pack_model(int env, const Model& m) {
  for (int d = 0; d < plan_.nv; ++d) set_parameter(env, d * kDofParameters + armature, m.armature[d]);
  for (int i = 0; i < plan_.num_links; ++i) {
    const Link& link = m.links[static_cast<size_t>(i)];
    const int x = plan_.nv * kDofParameters + i * kLinkParameters;
    set_parameter(env, x + mass, link.mass);
    for (int a = 0; a < 3; ++a) set_parameter(env, x + com_x + a, link.com[a]);
    const Mat3& I = link.inertia_com;
    set_parameter(env, x + inertia_xx, I(0, 0));
    set_parameter(env, x + inertia_yy, I(1, 1));
    set_parameter(env, x + inertia_zz, I(2, 2));
    set_parameter(env, x + inertia_xy, I(0, 1));
    set_parameter(env, x + inertia_xz, I(0, 2));
    set_parameter(env, x + inertia_yz, I(1, 2));
    if (I(0, 1) != 0.0 || I(0, 2) != 0.0 || I(1, 2) != 0.0)
      links_[static_cast<size_t>(i)].diagonal_inertia = false;
  }
  const int x = plan_.nv * kDofParameters + plan_.num_links * kLinkParameters +
                plan_.num_mimic * kMimicParameters;
  for (int a = 0; a < 3; ++a) set_parameter(env, x + gravity_x + a, m.gravity[a]);
}

void LaneEngine::begin_run() {
  std::fill(stopped_now_.get(), stopped_now_.get() + count_, false);
}

int LaneEngine::blocks(SimdIsa isa, bool one_lane) const {
  if (one_lane) return count_;
  const int W = simd_width(isa) * interleave(simd_width(isa), count_);
  return (count_ + W - 1) / W;
}

void LaneEngine::run_block(const Block& arrays, int block, int steps, SimdIsa isa, bool one_lane,
                           double* scratch) {
  const int K = one_lane ? 1 : interleave(simd_width(isa), count_);
  const int W = one_lane ? 1 : simd_width(isa) * K;  // lanes of a block
  Block b = arrays;
  b.env0 = block * W;
  b.interleave = K;
  b.valid = std::min(W, count_ - b.env0);
  b.parameters = parameters_.data();
  b.stop = stops_.data(), b.stopped_now = stopped_now_.get();
  b.contacts = plan_.contacts ? &contacts_ : nullptr;
  b.tables = &tables_;
  if (one_lane) {
    run_block_one(plan_, b, scratch, steps);
    return;
  }
  switch (isa) {
    case SimdIsa::sse2:
      run_block_sse2(plan_, b, scratch, steps);
      break;
    case SimdIsa::avx2:
      run_block_avx2(plan_, b, scratch, steps);
      break;
    case SimdIsa::avx512:
      run_block_avx512(plan_, b, scratch, steps);
      break;
  }
}

double* LanePool::scratch_of(int thread) {
  auto address = reinterpret_cast<std::uintptr_t>(scratch_[static_cast<size_t>(thread)].data());
  return reinterpret_cast<double*>((address + 63) & ~std::uintptr_t{63});
}

void LanePool::run(const std::vector<LaneJob>& jobs, int steps, int threads_wanted) {
  work_.clear();
  std::size_t doubles = 0;
  for (size_t j = 0; j < jobs.size(); ++j) {
    LaneEngine& e = *jobs[j].engine;
    e.begin_run();
    doubles = std::max(doubles, scratch_doubles(e.plan()) + 8);
    const int blocks = e.blocks(jobs[j].isa, jobs[j].one_lane);
    for (int b = 0; b < blocks; ++b) work_.push_back({static_cast<int>(j), b});
  }
  const int n = static_cast<int>(work_.size());
  const int threads = std::max(1, std::min(threads_wanted, n));
  run_threads_ = threads;
  if (static_cast<int>(scratch_.size()) < threads) scratch_.resize(static_cast<size_t>(threads));
  for (auto& s : scratch_)
    if (s.size() < doubles) s.assign(doubles, 0.0);
  auto run_one = [&](int w, double* scratch) {
    const LaneJob& job = jobs[static_cast<size_t>(work_[static_cast<size_t>(w)].first)];
    job.engine->run_block(job.arrays, work_[static_cast<size_t>(w)].second, steps, job.isa,
                          job.one_lane, scratch);
  };
  if (threads <= 1) {
    for (int w = 0; w < n; ++w) run_one(w, scratch_of(0));
    return;
  }
  if (!arena_ || arena_threads_ != threads) {
    arena_ = std::make_unique<tbb::task_arena>(threads);
    arena_threads_ = threads;
  }
  arena_->execute([&] {
    tbb::parallel_for(tbb::blocked_range<int>(0, n), [&](const tbb::blocked_range<int>& r) {
      double* scratch = scratch_of(tbb::this_task_arena::current_thread_index());
      for (int w = r.begin(); w < r.end(); ++w) run_one(w, scratch);
    });
  });
}

std::string LaneEngine::divergence_message(int e, const Model& model, long step_count,
                                           double time) const {
  const Stop& s = stop(e);
  if (s.quantity == 8) return messages_[static_cast<size_t>(e)];
  static const char* const kQuantity[] = {
      "",           "velocity qd",          "drive force", "limit force",
      "friction force", "velocity limit force", "position q"};
  std::ostringstream m;
  m.precision(6);
  m << "simulation diverged at step " << step_count + 1 << " (t = " << time << " s): ";
  if (s.quantity >= 10)  // a row kind's force, as Stepper::check_finite_or_throw words it
    m << "joint '" << model.links[static_cast<size_t>(model.dof_link[s.dof])].joint_name << "' "
      << row_kinds()[static_cast<size_t>(s.quantity - 10)].name << " force = ";
  else if (s.quantity == 7)  // as Stepper::check_finite_or_throw words it
    m << "link '" << model.links[static_cast<size_t>(s.dof / 3)].name << "' contact force f"
      << "xyz"[s.dof % 3] << " = ";
  else
    m << "joint '" << model.links[static_cast<size_t>(model.dof_link[s.dof])].joint_name << "' "
      << kQuantity[s.quantity] << " = ";
  if (std::isnan(s.value)) m << "nan";  // as Simulation's: a NaN's sign is the operation order's
  else m << s.value;
  m << "; the state is left as it was before this step (lower dt or the gains)";
  return m.str();
}

}  // namespace featherdrive::simd
