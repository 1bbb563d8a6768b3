// The step guard on Batch's lanes (docs/simd_batch.md, "The step guard"): the lanes advance
// every environment; each guarded one's advance is then tested by its own Stepper's guard
// (step_guard.cpp, docs/math/step_guard.md) on the lanes' end and rows, kept as a Simulation
// keeps it, or redone from its start by the Simulation's scalar sub-steps.
#include "featherdrive/sim/batch.hpp"
#include "lane_engine.hpp"
#include "workspace.hpp"

namespace featherdrive {

namespace {

// Environment i's lane: its group's engine and its lane there (null: it steps as a Simulation).
struct Lane {
  simd::LaneEngine* engine = nullptr;
  int lane = -1;
};
Lane lane_of(simd::LaneGroups& l, size_t i) {
  const int g = l.group_of[i];
  if (g < 0) return {};
  return {l.groups[static_cast<size_t>(g)].engine.get(), l.lane_of[i]};
}

}  // namespace

// Each guarded environment still stepping: its start loaded, its energies taken, its outputs
// and clock kept for a redo (the lanes write over the storage).
void Batch::lane_guard_start() {
  const auto n = sims_.size();
  guard_live_.resize(n);
  guard_redone_.resize(n);
  guard_steps_.resize(n);
  guard_time_.resize(n);
  for (size_t i = 0; i < n; ++i) {
    Simulation& s = sims_[i];
    guard_redone_[i] = 0;
    const Lane lane = lane_of(*lanes_, i);
    guard_live_[i] = lane.engine && s.options().guard.enabled &&
                     lane.engine->stop(lane.lane).quantity == 0;
    if (!guard_live_[i]) continue;
    Workspace& ws = *s.ws_;
    Stepper stepper(*s.model_, s.settings_, s.state_, lane_time_[i], lane_steps_[i], ws);
    stepper.load_state();
    stepper.guard_start();
    ws.drive_force = s.state_[StateStorage::drive_force];
    ws.limit_force = s.state_[StateStorage::limit_force];
    ws.friction_force = s.state_[StateStorage::friction_force];
    ws.velocity_limit_force = s.state_[StateStorage::velocity_limit_force];
    ws.row_force = s.state_[StateStorage::row_force];
    guard_steps_[i] = lane_steps_[i];
    guard_time_[i] = lane_time_[i];
  }
}

// The guard on each guarded environment's lane step: a step that passes is kept with its
// account; one that fails goes back to its start and is redone by the environment's scalar
// sub-steps, one the lanes stopped (not finite) by its whole scalar guarded advance; either may
// diverge as a Simulation's would.
void Batch::lane_guard_finish(RowMatrix* drive_change) {
  const int nv = model().nv;
  // Each environment on its own (its Simulation, its rows of the arrays): any thread order.
  lanes_->pool.each(size(), [&](int e) {
    const auto i = static_cast<size_t>(e);
    if (!guard_live_[i]) return;
    const Lane lane = lane_of(*lanes_, i);
    Simulation& s = sims_[i];
    Workspace& ws = *s.ws_;
    Stepper stepper(*s.model_, s.settings_, s.state_, lane_time_[i], lane_steps_[i], ws);
    // The joint force the lanes used: control_stages's (applied force + explicit efforts).
    const VecX& tau = ws.actuators.any() ? ws.joint_force : ws.applied_force;
    const bool stopped = lane.engine->stopped_now(lane.lane);
    if (!stopped) {
      stepper.load_state();  // the lanes' end
      simd::unpack_guard_rows(lane_guard_rows_.row(e).data(), nv, ws.guard_rows);
      if (stepper.guard_first_passes(tau)) {
        stepper.commit_guard_account();
        if (ws.contacts_active) ws.contact_rows.conclude();  // as Stepper::contact_forces
        return;
      }
    }
    guard_redone_[i] = 1;
    lane.engine->resume(lane.lane);
    s.state_[StateStorage::q] = ws.guard_q0;
    s.state_[StateStorage::qd] = ws.guard_qd0;
    s.state_[StateStorage::drive_force] = ws.drive_force;
    s.state_[StateStorage::limit_force] = ws.limit_force;
    s.state_[StateStorage::friction_force] = ws.friction_force;
    s.state_[StateStorage::velocity_limit_force] = ws.velocity_limit_force;
    s.state_[StateStorage::row_force] = ws.row_force;
    lane_steps_[i] = guard_steps_[i];
    lane_time_[i] = guard_time_[i];
    // The redo reports its contacts and keeps its anchors (Stepper::guard_redo) from the start's
    // anchors, which contact_conclude left to the guard.
    stepper.load_state();
    try {
      // A step the lanes stopped (not finite) left no end to test: the Simulation's whole guarded
      // advance, which tests its own (and may find a contact force overflowed where the state did
      // not, and stop as the Simulation stops).
      if (stopped) stepper.guarded_advance(tau);
      else stepper.guard_redo();
      stepper.end_step();
    } catch (const DivergenceError& error) {  // the state and the pushes as they were
      lane.engine->stop_with(lane.lane, error.what());
    }
    if (drive_change) drive_change->row(e) = ws.last_drive_change.transpose();
  });
}

}  // namespace featherdrive
