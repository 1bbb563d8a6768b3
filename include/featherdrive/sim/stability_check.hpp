// Will a run stay bounded? Per dof the one-joint step map of its drive or explicit actuator at
// the initial state, for the whole robot a linearisation of the step and a short trial run, and
// the smallest changes that make an unstable joint stable. docs/stability_check.md has the
// equations (S1-S9) and the measured accuracy.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "featherdrive/sim/gain_translation.hpp"
#include "featherdrive/sim/simulation.hpp"

namespace featherdrive {

/// What acts on a dof in the one-joint map.
enum class JointLaw {
  none,          ///< no drive, no actuator: a free dof (map [[1, dt], [0, 1]])
  drive,         ///< PhysX's implicit drive (physx_step_map)
  explicit_pd,   ///< an explicit actuator's PD law, semi-implicit Euler (eq. S3)
  implicit_pd,   ///< an implicit actuator's PD law: a force drive's map with its gains
};
const char* to_string(JointLaw law);

/// The gains a one-joint map is built from: a drive's (force or acceleration), or an explicit
/// actuator's kp, kd (force units).
struct JointGains {
  JointLaw law = JointLaw::none;
  Drive drive;            ///< law drive: the drive (targets ignored)
  double stiffness = 0.0; ///< laws explicit_pd and implicit_pd
  double damping = 0.0;
};

/// The gains of dof `dof` of `sim` (the one place that decides which law a dof follows).
JointGains joint_gains(const Simulation& sim, int dof);

/// One physics step of dt for a dof of effective inertia m under `gains` (eq. S1-S3): the
/// homogeneous part A of the step's affine map (targets and loads do not change stability).
Eigen::Matrix2d joint_step_matrix(double m, const JointGains& gains,
                                  const SimulationOptions& options);

/// The explicit PD law's semi-implicit Euler step (eq. S3): v1 = v0 + h (-kp q0 - kd v0) / m,
/// q1 = q0 + h v1.
Eigen::Matrix2d explicit_pd_step_matrix(double m, double kp, double kd, double h);

/// step_spectral_radius (gain_translation.hpp) gives the largest |eigenvalue| of a map.

/// Stable: spectral radius <= 1 + kStableTolerance (a free or undamped dof sits on the circle).
inline constexpr double kStableTolerance = 1e-9;

struct JointStability {
  std::string joint;
  int dof = 0;
  int axis = -1;  ///< a spherical joint's axis 0, 1, 2; -1 for revolute and prismatic
  JointLaw law = JointLaw::none;
  double mass = 0.0;         ///< m = 1 / (M^-1)_jj, armature included
  double stiffness_ratio = 0.0;  ///< kp dt^2 / m (acceleration drives: kp dt^2)
  double damping_ratio = 0.0;    ///< zeta = kd / (2 sqrt(kp m)) (acceleration: kd / (2 sqrt(kp))); NaN without kp
  double rho = 1.0;          ///< spectral radius of the one-joint map of one physics step
  bool stable = true;
  // The smallest fixes for an unstable joint (eq. S7-S9); 0 / -1 where none works.
  int substeps = 0;          ///< physics steps per step of dt (dt / substeps each); 0: none up to 1024
  double armature = -1.0;    ///< armature to add; < 0: none
  double damping = -1.0;     ///< damping to add to kd (force units; acceleration drives: their own); < 0: none
};

/// The longest trial run check_stability accepts (its robot fix may run 504 times as many steps).
inline constexpr int kMaxTrialSteps = 100'000;

struct StabilityCheckOptions {
  /// The trial run: this many seconds of simulated time, but at least min_trial_steps and at
  /// most max_trial_steps steps; max_trial_steps 0 skips it.
  double trial_seconds = 2.0;
  int min_trial_steps = 500;
  int max_trial_steps = 1000;
  /// The trial diverges when the energy (eq. S5) exceeds its initial value by this many times
  /// the energy scale E_ref (eq. S6), or a step throws DivergenceError.
  double energy_factor = 1000.0;
  /// The whole robot's linearised step (eq. S4), reported; its spectral radius above
  /// 1 + linear_tolerance makes the verdict unstable only when there is no trial run (the trial
  /// is the more accurate: docs/stability_check.md, "Accuracy").
  bool linearise = true;
  double linear_tolerance = 1e-3;
  /// For an unstable robot whose joints are all stable: the sub-steps tried on the trial run
  /// (2, 4, ... up to this).
  int max_robot_substeps = 64;
  /// ... on a trial this many times longer (in simulated time) than the check's own: a trial as
  /// long as the check's accepted sub-steps whose long runs still diverged (docs, "Fixes").
  int robot_fix_length = 4;
  /// Search the fixes of unstable joints (eq. S7-S9) and of an unstable robot (the trial's
  /// sub-steps); off, only the verdict and the table.
  bool find_fixes = true;
  /// Called before each physics step of a trial run with the simulation, the step's index (from
  /// 0) and the sub-steps the run makes per step of the original dt (1, or the robot fix's 2, 4,
  /// ...; the simulation's dt is then dt / substeps): a scene sets its time-varying targets there
  /// (apply_targets with control.substeps times that many). Empty: the targets stay as they are.
  std::function<void(Simulation&, int, int)> before_step;
};

struct RobotStability {
  double linear_rho = 0.0;   ///< spectral radius of the linearised step (eq. S4); NaN if skipped
  int linear_dofs = 0;       ///< the revolute and prismatic dofs it covers
  bool linear_stable = true;
  int trial_steps = 0;       ///< steps of the trial run (0: skipped)
  bool trial_bounded = true;
  std::string trial_note;    ///< how the trial diverged, or its largest energy ratio
  int substeps = 0;          ///< for a diverging trial: the sub-steps that keep it bounded; 0: none
};

struct StabilityReport {
  std::vector<JointStability> joints;  ///< every revolute, prismatic and spherical dof
  RobotStability robot;
  bool stable = true;
  std::string verdict;  ///< "stable" or "unstable: <joints and why>"
};

/// The check at sim's current state (not changed: the trial and the linearisation run copies).
/// std::invalid_argument naming the field and value for trial steps outside [0, kMaxTrialSteps],
/// a non-finite trial_seconds or energy_factor <= 0, or max_robot_substeps / robot_fix_length < 1.
StabilityReport check_stability(const Simulation& sim, const StabilityCheckOptions& options = {});

/// The energy of eq. S5 (kinetic + gravity + the drives' and actuators' springs towards their
/// current targets, revolute and prismatic dofs) and the scale E_ref of eq. S6.
double check_energy(const Simulation& sim);
double check_energy_scale(const Simulation& sim);

}  // namespace featherdrive
