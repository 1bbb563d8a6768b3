// Drive gains between featherdrive (PhysX) and MuJoCo 2.2.2 for one joint of effective inertia
// m = 1 / (M^-1)_jj: both engines' per-step linear maps on (q, qd) and the translation that
// matches their discrete poles and steady state. Engine-free math; docs/mujoco_bridge.md has the
// derivation (eq. B1-B12). The MuJoCo file and run are in io (mjcf_export.hpp, mujoco_run.hpp).
#pragma once

#include <string>
#include <utility>

#include "featherdrive/constraint/drive.hpp"
#include "featherdrive/model/model.hpp"
#include "featherdrive/sim/simulation.hpp"

namespace featherdrive {

/// One step of a joint as an affine map: [q1; qd1] = A [q0; qd0] + B [x_T; v_T; f], f a constant
/// generalised force on the dof (gravity, applied force) over the step.
struct DriveStepMap {
  Eigen::Matrix2d A;
  Eigen::Matrix<double, 2, 3> B;
};

/// featherdrive's (PhysX's) step for a lone drive on a dof of effective inertia m (armature
/// included), eq. B1-B4: PGS is one implicit step of dt for any iteration count, TGS n implicit
/// sub-steps of dt / n with the interpolated target (spec eq. 41-44). Force and acceleration
/// drives; max_force is ignored (the map is the unsaturated one).
DriveStepMap physx_step_map(double m, const Drive& drive, const SimulationOptions& options);

enum class MujocoIntegrator { euler, implicit };
const char* to_string(MujocoIntegrator integrator);

/// A MuJoCo 2.2.2 setting for one joint: a position actuator (kp, ctrl = the target), a velocity
/// actuator (kv, ctrl = the target velocity), joint damping and armature, stepped `substeps`
/// times per featherdrive step of dt (timestep dt / substeps).
struct MujocoDrive {
  double kp = 0.0;        ///< position actuator gain [N/m, Nm/rad]
  double kv = 0.0;        ///< velocity actuator gain [Ns/m, Nms/rad]
  double damping = 0.0;   ///< joint damping (dof_damping)
  double armature = 0.0;  ///< added to featherdrive's own armature
  /// The position actuator's ctrl is x_T + ctrl_velocity_gain * v_T: the velocity target's share
  /// of a damping term that MuJoCo only knows as damping towards 0 (eq. B7).
  double ctrl_velocity_gain = 0.0;
  int substeps = 1;
  /// With substeps > 1: the ctrl of sub-step i is that of TGS's interpolated target
  /// x_T - (dt - i dt / n) v_T (spec eq. 41), else the ctrl is held for the step.
  bool interpolate_target = false;
  MujocoIntegrator integrator = MujocoIntegrator::euler;
};

/// Throws std::invalid_argument naming the field and value for a gain, damping or armature that
/// is negative or not finite, a non-finite ctrl_velocity_gain or substeps outside
/// [1, kMaxSubsteps].
void validate_mujoco_drive(const MujocoDrive& drive);

/// MuJoCo's step of the joint over dt (`substeps` MuJoCo steps), eq. B5-B6. Semi-implicit
/// Euler: explicit in kp and kv, implicit in joint damping (dof_damping > 0); the implicit
/// integrator is implicit in kv and damping too.
DriveStepMap mujoco_step_map(double m, const MujocoDrive& drive, double dt);

/// MuJoCo's ctrl of the position actuator and of the velocity actuator in sub-step i (1-based)
/// of a step whose drive targets are x_T, v_T.
std::pair<double, double> mujoco_ctrl(const MujocoDrive& drive, double x_target, double v_target,
                                      double dt, int substep);

/// How close two steps are: the largest |q| difference of their responses to a unit step of x_T
/// from rest, over `steps` steps (relative to the step size), and the largest distance between
/// their poles (the eigenvalues of A).
struct MapDistance {
  double step_response = 0.0;
  double poles = 0.0;
  int steps = 0;
};
MapDistance map_distance(const DriveStepMap& a, const DriveStepMap& b, int steps = 0);

/// The largest |eigenvalue| of a step map's A (its poles).
double step_spectral_radius(const Eigen::Matrix2d& A);

/// Whether a step is stable: both poles strictly inside the unit circle (or on it only at 1 for
/// a drive without stiffness).
bool stable(const DriveStepMap& map);

/// A translation and how well it reproduces the source: `exact` where the maps agree to
/// rounding, else `note` says why not (one line) and `distance` how far the best setting is.
struct MujocoTranslation {
  MujocoDrive mujoco;
  bool exact = false;
  bool reproducible = true;
  MapDistance distance;
  std::string note;
};

struct TranslationOptions {
  MujocoIntegrator integrator = MujocoIntegrator::euler;
  /// Keep MuJoCo's timestep at dt for TGS drives (no sub-steps): the poles are matched with
  /// extra armature and damping, which TGS with n > 1 needs negative (eq. B10).
  bool keep_timestep = false;
};

/// featherdrive's drive on a dof of effective inertia m -> the MuJoCo setting closest to it
/// (eq. B7-B10). Throws std::invalid_argument for m <= 0 or a drive of type none.
MujocoTranslation translate_to_mujoco(double m, const Drive& drive,
                                      const SimulationOptions& options,
                                      const TranslationOptions& translation = {});

/// The literal setting: the same kp and kd as MuJoCo position and velocity actuators, one MuJoCo
/// step per step (what a user gets by copying the numbers); acceleration gains times m.
MujocoDrive literal_mujoco_drive(double m, const Drive& drive, MujocoIntegrator integrator);

struct PhysxTranslation {
  Drive drive;  ///< a force drive; targets 0
  bool exact = false;
  bool reproducible = true;
  MapDistance distance;
  std::string note;
};

/// A MuJoCo setting on a dof of effective inertia m (featherdrive's, without the setting's
/// armature: that becomes featherdrive's armature) -> featherdrive's force drive under
/// options (solver, iterations, dt) closest to it (eq. B11, B12). substeps must be 1.
PhysxTranslation translate_to_physx(double m, const MujocoDrive& mujoco,
                                    const SimulationOptions& options);

/// 1 / (M(q)^-1)_jj for every dof (armature included): the inertia a drive on dof j sees with
/// the rest of the articulation free (spec ERRATA 6). std::invalid_argument for a q of the
/// wrong size or with a non-finite entry, or a dof whose inertia is not finite and > 0.
VecX effective_inertia(const Model& model, const VecX& q);

}  // namespace featherdrive
