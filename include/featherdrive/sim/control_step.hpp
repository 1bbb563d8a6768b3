// A control step: k physics steps of dt with the drive targets given once (Isaac Lab's
// `decimation`), held or interpolated from the previous ones. docs/math/control_step.md.
#pragma once

#include <functional>

#include "featherdrive/sim/batch.hpp"
#include "featherdrive/sim/simulation.hpp"

namespace featherdrive {

/// How a control step's targets reach its k physics steps (docs/math/control_step.md, eq. 1-2).
enum class TargetInterpolation {
  hold,    ///< every sub-step uses the new targets
  linear,  ///< sub-step j (1..k) uses prev + j/k (new - prev); sub-step k the new targets exactly
};
const char* to_string(TargetInterpolation interpolation);

/// The most physics steps of one control step: a call returns only after all of them, so a larger
/// k is a mistake rather than a setting (10^6 steps of the 7-dof arm take about a second).
inline constexpr int kMaxSubsteps = 1'000'000;

struct ControlStep {
  int substeps = 1;  ///< k, physics steps per control step, in [1, kMaxSubsteps]
  TargetInterpolation targets = TargetInterpolation::hold;
};

/// Throws std::invalid_argument naming the field and value for substeps outside [1, kMaxSubsteps]
/// or an unknown interpolation.
void validate_control_step(const ControlStep& control);

/// The target of sub-step j (1..k) between `prev` and `next` (eq. 2): `next` itself for hold and
/// for j = k, so that a control step ends on the targets it was given.
inline double substep_target(double prev, double next, int j, int k, TargetInterpolation mode) {
  if (mode == TargetInterpolation::hold || j == k) return next;
  return prev + (static_cast<double>(j) / static_cast<double>(k)) * (next - prev);
}

/// Called after each sub-step j (1..k) with the simulation; for observation (e.g. one CSV row per
/// physics step), not for changing it.
using SubstepObserver = std::function<void(const Simulation&, int)>;

/// One control step: k = control.substeps steps of sim.options().dt with the drive targets of
/// every dof (nv each) held or interpolated from those the drives had before the call. Everything
/// is checked before anything changes: sizes, finite targets, (new - prev) finite for linear.
/// A sub-step that diverges throws DivergenceError ("step_control: sub-step j of k: ...") and
/// leaves the state of sub-step j - 1 with sub-step j's targets set; step_count() tells how far it
/// got. Allocates nothing once a first call has sized its scratch on this thread.
void step_control(Simulation& sim, const VecX& target_position, const VecX& target_velocity,
                  const ControlStep& control, const SubstepObserver& on_substep = {});

/// The same for every copy of a batch, (N, nv) targets, through Batch's public API
/// (set_drive_targets, step). Divergence as Batch::step: a copy that diverges stops at the
/// sub-step that diverged with the state it had before it; every other copy makes all k sub-steps;
/// then DivergenceError names the first sub-step where a copy diverged, Batch::step's message and
/// how many copies diverged in all.
void step_control(Batch& batch, const RowMatrix& target_position,
                  const RowMatrix& target_velocity, const ControlStep& control);

}  // namespace featherdrive
