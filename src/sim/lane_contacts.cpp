// Contacts in Batch's lanes: each environment's own ContactRows and SelfContacts (Simulation's, in
// its workspace) on its lane's entries of a block's scratch, one lane at a time, out of line, so
// the contact laws are the scalar step's (docs/simd_batch.md, "Contacts"; docs/math/contact.md).
#include <algorithm>
#include <cmath>

#include "featherdrive/algorithm/inverse_mass_diagonal.hpp"
#include "featherdrive/sim/link_laws.hpp"

#include "lane_engine.hpp"
#include "workspace.hpp"

namespace featherdrive::simd {
namespace {


// A lane's entries of the scratch.
struct LaneEntries {
  const double* s;
  int width, lane;
  double operator()(int k) const { return s[static_cast<long>(k) * width + lane]; }
  Vec6 six(int k) const {
    Vec6 v;
    for (int r = 0; r < 6; ++r) v[r] = (*this)(k + r);
    return v;
  }
};

ContactPhase phase_of(const LaneContactPhase& p) {
  ContactPhase c;
  c.dt = p.dt, c.h = p.h, c.tgs = p.tgs, c.velocity_iteration = p.velocity_iteration;
  c.elapsed = p.elapsed;
  return c;
}

}  // namespace

bool contacts_active(const ContactLanes& c, int env) {
  const Workspace& ws = *c.envs[static_cast<size_t>(env)].ws;
  return ws.contacts_active || ws.self_contacts_active;
}

bool ground_active(const ContactLanes& c, int env) {
  return c.envs[static_cast<size_t>(env)].ws->contacts_active;
}

bool self_contacts_active(const ContactLanes& c, int env) {
  return c.envs[static_cast<size_t>(env)].ws->self_contacts_active;
}

void contact_poses(ContactLanes& c, const Plan& p, int env, const double* s, int width, int lane) {
  const ContactLanes::Env& e = c.envs[static_cast<size_t>(env)];
  Data& data = e.ws->data;
  const Layout& l = p.layout;
  const LaneEntries x{s, width, lane};
  // Frame 0's origin, the root link's origin in the world, from the step-start q.
  const LinkConstants& root = p.links[0];
  // kinematics.cpp: r + E^T (axis q) for a prismatic root, r + E^T q for a floating one.
  Vec3 origin(root.r[0], root.r[1], root.r[2]);
  const Mat3 E = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(root.E);
  if (root.type == 3) {
    const Vec3 at(x(l.q + root.q_index), x(l.q + root.q_index + 1), x(l.q + root.q_index + 2));
    origin += root.tree_rotation_identity ? at : Vec3(E.transpose() * at);
  } else if (root.type == 2) {
    origin += E.transpose() * (Vec3(root.axis[0], root.axis[1], root.axis[2]) *
                               x(l.q + root.q_index));
  }
  data.frame_origin = origin;
  const std::vector<char>& shaped = e.ws->contact_rows.links_with_shapes();
  for (int L = 0; L < p.num_links; ++L) {
    if (!shaped[static_cast<size_t>(L)]) continue;
    for (int r = 0; r < 3; ++r) {
      for (int col = 0; col < 3; ++col) data.world_rotation[L](r, col) = x(l.R + 9 * L + 3 * r + col);
      data.world_position[L][r] = x(l.pos + 3 * L + r) + origin[r];
    }
  }
}

void contact_setup(ContactLanes& c, const Plan& p, int env, const double* s, int width, int lane) {
  const ContactLanes::Env& e = c.envs[static_cast<size_t>(env)];
  Workspace& ws = *e.ws;
  const Layout& l = p.layout;
  const LaneEntries x{s, width, lane};
  const std::vector<char>& shaped = ws.contact_rows.links_with_shapes();
  for (int L = 0; L < p.num_links; ++L) {
    if (!shaped[static_cast<size_t>(L)]) continue;
    double* response = ws.data.response[L].data();
    for (int c = 0; c < 6; ++c)  // column by column (Mat6's order) from the packed layout
      for (int r = 0; r < 6; ++r)
        response[6 * c + r] = x(l.Lambda + 21 * L + link_law::kPacked[r][c]);
    ws.link_cfm[L] = p.any_cfm ? x(l.cfm + L) : 0.0;
    ws.contact_link_velocity[static_cast<size_t>(L)] = x.six(l.contact_vel + 6 * L);
  }
  ContactPhase phase;  // Stepper::setup_contacts
  phase.dt = p.dt;
  phase.h = p.tgs ? p.dt / p.position_iterations : p.dt;
  phase.tgs = p.tgs;
  const Model& model = e.sim->model();
  ws.num_ground_contacts =
      ws.contacts_active
          ? ws.contact_rows.setup(model, ws.data, e.sim->ground(), e.sim->contact_options(),
                                  ws.contact_link_velocity, ws.link_cfm, p.position_iterations,
                                  phase, ws.contacts)
          : 0;
  ws.num_contacts = ws.num_ground_contacts;
  const ContactOptions& options = e.sim->contact_options();
  if (!ws.self_contacts_active || ws.self_contacts.find(model, ws.data, options) == 0) return;
  // The self rows' responses between two links are sweeps of the scalar step's articulated
  // quantities (contact.md, C30, C31): where this lane's pairs touch, its Data gets them from the
  // step-start q, as Simulation's step computes them (their poses and response its own, within
  // rounding of the lane's).
  for (int k = 0; k < p.nq; ++k) ws.q[k] = x(l.q + k);
  inverse_mass_diagonal(model, ws.data, ws.q);
  ws.num_contacts += ws.self_contacts.setup_rows(model, ws.data, options, ws.contact_link_velocity,
                                                 ws.link_cfm, p.position_iterations, phase,
                                                 ws.contacts, ws.num_ground_contacts);
}

void contact_self_solve(ContactLanes& c, const Plan& p, int env, const LaneContactPhase& phase,
                        double* s, int width, int lane) {
  const ContactLanes::Env& e = c.envs[static_cast<size_t>(env)];
  Workspace& ws = *e.ws;
  const LaneEntries x{s, width, lane};
  for (int d = 0; d < p.nv; ++d) ws.qd[d] = x(p.layout.qd + d);
  ws.self_contacts.solve(e.sim->model(), ws.data, phase_of(phase), ws.qd);
  for (int d = 0; d < p.nv; ++d) s[static_cast<long>(p.layout.qd + d) * width + lane] = ws.qd[d];
}

void contact_solve(ContactLanes& c, const Plan& p, int env, int link, const LaneContactPhase& phase,
                   double* s, int width, int lane) {
  const Workspace& ws = *c.envs[static_cast<size_t>(env)].ws;
  ContactRows& rows = c.envs[static_cast<size_t>(env)].ws->contact_rows;
  // The lane step wrote its subtree impulse 0.
  if (!ws.contacts_active || !rows.link_has_rows(link)) return;
  const Layout& l = p.layout;
  const LaneEntries x{s, width, lane};
  Vec6 dv = x.six(l.dv + 6 * link);
  const Vec6 impulse =
      rows.solve_link(link, x.six(l.contact_vel + 6 * link), dv, phase_of(phase));
  for (int r = 0; r < 6; ++r) {
    s[static_cast<long>(l.dv + 6 * link + r) * width + lane] = dv[r];
    s[static_cast<long>(l.subtree + 6 * link + r) * width + lane] = -impulse[r];
  }
}

void contact_track(ContactLanes& c, const Plan& p, int env, double h, const double* s, int width,
                   int lane) {
  const ContactLanes::Env& e = c.envs[static_cast<size_t>(env)];
  const LaneEntries x{s, width, lane};
  const std::vector<char>& shaped = e.ws->contact_rows.links_with_shapes();
  for (int L = 0; L < p.num_links; ++L)
    if (shaped[static_cast<size_t>(L)])
      e.ws->contact_link_velocity[static_cast<size_t>(L)] = x.six(p.layout.contact_vel + 6 * L);
  if (e.ws->contacts_active) e.ws->contact_rows.track(e.ws->contact_link_velocity, h);
  if (e.ws->self_contacts_active) e.ws->self_contacts.track(e.ws->contact_link_velocity, h);
}

Stop contact_report(ContactLanes& c, const Plan& p, int env) {
  Workspace& ws = *c.envs[static_cast<size_t>(env)].ws;
  // Stepper::contact_forces, and check_finite_or_throw's order: a contact force is a culprit of
  // its own only with the ground on.
  if (ws.contacts_active) ws.contact_rows.report(p.dt, ws.contacts, ws.link_contact_force);
  else std::fill(ws.link_contact_force.begin(), ws.link_contact_force.end(), Vec3::Zero());
  if (ws.self_contacts_active)
    ws.self_contacts.report(p.dt, ws.contacts, ws.num_ground_contacts, ws.link_contact_force);
  if (!ws.contacts_active) return Stop{};
  for (size_t i = 0; i < ws.link_contact_force.size(); ++i)
    for (int k = 0; k < 3; ++k)
      if (!std::isfinite(ws.link_contact_force[i][k]))
        return Stop{7, static_cast<int>(3 * i) + k, ws.link_contact_force[i][k]};
  return Stop{};
}

void contact_conclude(ContactLanes& c, int env, bool kept) {
  const ContactLanes::Env& e = c.envs[static_cast<size_t>(env)];
  Workspace& ws = *e.ws;
  if (kept) {
    // A guarded environment's anchors once its guard keeps the step (lane_guard.cpp).
    if (ws.contacts_active && !e.guarded) ws.contact_rows.conclude();
    return;
  }
  // Stepper::check_finite_or_throw: a diverged step reports no contacts.
  ws.num_contacts = 0;
  std::fill(ws.link_contact_force.begin(), ws.link_contact_force.end(), Vec3::Zero());
}

}  // namespace featherdrive::simd
