#include "featherdrive/sim/control_step.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "featherdrive/core/format.hpp"

namespace featherdrive {
namespace {

std::string joint_of(const Model& model, Eigen::Index d) {
  return "dof " + std::to_string(d) + " (joint '" + model.links[model.dof_link[d]].joint_name +
         "')";
}

void check_size(const VecX& x, int nv, const char* what) {
  if (x.size() != nv)
    throw std::invalid_argument(std::string("step_control: ") + what + " has " +
                                std::to_string(x.size()) + " values, expected nv = " +
                                std::to_string(nv));
}

/// Finite targets, and for linear a finite difference new - prev, so that no sub-step can fail
/// on its targets after an earlier one has run. `where` names the copy of a batch.
void check_targets(const Model& model, double position, double velocity, double prev_position,
                   double prev_velocity, Eigen::Index d, TargetInterpolation mode,
                   const std::string& where) {
  const char* names[2] = {"target_position", "target_velocity"};
  const double next[2] = {position, velocity}, prev[2] = {prev_position, prev_velocity};
  for (int w = 0; w < 2; ++w) {
    if (!std::isfinite(next[w]))
      throw std::invalid_argument("step_control: " + where + names[w] + " of " +
                                  joint_of(model, d) + " = " + format_double(next[w]) +
                                  " is not finite");
    if (mode == TargetInterpolation::linear && !std::isfinite(next[w] - prev[w]))
      throw std::invalid_argument("step_control: " + where + names[w] + " of " +
                                  joint_of(model, d) + " = " + format_double(next[w]) +
                                  " minus the previous target " + format_double(prev[w]) +
                                  " overflows");
  }
}

std::string substep_of(int j, int k) {
  return "step_control: sub-step " + std::to_string(j) + " of " + std::to_string(k) + ": ";
}

}  // namespace

const char* to_string(TargetInterpolation interpolation) {
  return interpolation == TargetInterpolation::linear ? "linear" : "hold";
}

void validate_control_step(const ControlStep& control) {
  if (control.substeps < 1 || control.substeps > kMaxSubsteps)
    throw std::invalid_argument("control step: substeps = " + std::to_string(control.substeps) +
                                " must be in [1, " + std::to_string(kMaxSubsteps) + "]");
  if (control.targets != TargetInterpolation::hold &&
      control.targets != TargetInterpolation::linear)
    throw std::invalid_argument("control step: targets = " +
                                std::to_string(static_cast<int>(control.targets)) +
                                " must be hold or linear");
}

void step_control(Simulation& sim, const VecX& target_position, const VecX& target_velocity,
                  const ControlStep& control, const SubstepObserver& on_substep) {
  validate_control_step(control);
  const Model& model = sim.model();
  const int nv = model.nv;
  check_size(target_position, nv, "target_position");
  check_size(target_velocity, nv, "target_velocity");
  // The targets before the call, kept on this thread: sub-step 1 overwrites the drives' own.
  thread_local std::vector<double> prev;
  prev.resize(2 * static_cast<size_t>(nv));
  for (int d = 0; d < nv; ++d) {
    const Drive& drive = sim.drive(d);
    prev[2 * static_cast<size_t>(d)] = drive.target_position;
    prev[2 * static_cast<size_t>(d) + 1] = drive.target_velocity;
    check_targets(model, target_position[d], target_velocity[d], drive.target_position,
                  drive.target_velocity, d, control.targets, "");
  }
  try {
    sim.check_targets_have_drives(target_position, target_velocity);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("step_control: ") + e.what());
  }
  const int k = control.substeps;
  for (int j = 1; j <= k; ++j) {
    // Nothing left to fail here: the gains were valid and the targets are finite. Through
    // set_drive, which keeps the zero targets of undriven dofs (set_drive_target refuses them).
    for (int d = 0; d < nv; ++d) {
      const size_t i = 2 * static_cast<size_t>(d);
      Drive drive = sim.drive(d);
      drive.target_position = substep_target(prev[i], target_position[d], j, k, control.targets);
      drive.target_velocity = substep_target(prev[i + 1], target_velocity[d], j, k, control.targets);
      sim.set_drive(d, drive);
    }
    try {
      sim.step();
    } catch (const DivergenceError& e) {
      throw DivergenceError(substep_of(j, k) + e.what());
    }
    if (on_substep) on_substep(sim, j);
  }
}

void step_control(Batch& batch, const RowMatrix& target_position,
                  const RowMatrix& target_velocity, const ControlStep& control) {
  validate_control_step(control);
  const Model& model = batch.model();
  const int n = batch.size(), nv = model.nv, k = control.substeps;
  for (const RowMatrix* m : {&target_position, &target_velocity})
    if (m->rows() != n || m->cols() != nv)
      throw std::invalid_argument(
          std::string("step_control: ") +
          (m == &target_position ? "target_position" : "target_velocity") + " has shape (" +
          std::to_string(m->rows()) + ", " + std::to_string(m->cols()) + "), expected (" +
          std::to_string(n) + ", " + std::to_string(nv) + ")");
  RowMatrix prev_position(n, nv), prev_velocity(n, nv);
  std::vector<long> start(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) {
    const Simulation& sim = batch.sim(i);
    start[static_cast<size_t>(i)] = sim.step_count();
    for (int d = 0; d < nv; ++d) {
      prev_position(i, d) = sim.drive(d).target_position;
      prev_velocity(i, d) = sim.drive(d).target_velocity;
      check_targets(model, target_position(i, d), target_velocity(i, d), prev_position(i, d),
                    prev_velocity(i, d), d, control.targets,
                    "copy " + std::to_string(i) + ": ");
    }
  }
  // The copies that have made every sub-step so far.
  auto alive = [&](int i, int j) {
    return batch.sim(i).step_count() == start[static_cast<size_t>(i)] + j;
  };
  std::string first_error;
  int first_j = 0;
  if (control.targets == TargetInterpolation::hold) {
    batch.set_drive_targets(target_position, target_velocity);
    try {
      batch.step(k);
    } catch (const DivergenceError& e) {
      first_error = e.what();
      first_j = k;
      for (int i = 0; i < n; ++i)
        first_j = std::min(first_j, static_cast<int>(batch.sim(i).step_count() -
                                                     start[static_cast<size_t>(i)]) + 1);
    }
  } else {
    RowMatrix position(n, nv), velocity(n, nv);
    for (int j = 1; j <= k; ++j) {
      for (int i = 0; i < n; ++i)
        for (int d = 0; d < nv; ++d) {
          position(i, d) = substep_target(prev_position(i, d), target_position(i, d), j, k,
                                          control.targets);
          velocity(i, d) = substep_target(prev_velocity(i, d), target_velocity(i, d), j, k,
                                          control.targets);
        }
      if (first_j == 0) {
        batch.set_drive_targets(position, velocity);
        try {
          batch.step(1);
        } catch (const DivergenceError& e) {
          first_error = e.what();
          first_j = j;
        }
        continue;
      }
      // After a divergence the other copies go on one by one, as Batch::step lets them.
      for (int i = 0; i < n; ++i) {
        if (!alive(i, j - 1)) continue;
        Simulation& sim = batch.sim(i);
        set_drive_targets(sim, position.row(i).transpose(), velocity.row(i).transpose());
        try {
          sim.step();
        } catch (const DivergenceError&) {
          // Counted below by its step count.
        }
      }
    }
  }
  if (first_j == 0) return;
  int diverged = 0;
  for (int i = 0; i < n; ++i) diverged += alive(i, k) ? 0 : 1;
  throw DivergenceError(substep_of(first_j, k) + first_error + "; " + std::to_string(diverged) +
                        " of " + std::to_string(n) + " copies diverged in the control step");
}

}  // namespace featherdrive
