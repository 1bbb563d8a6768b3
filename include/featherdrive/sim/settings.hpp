// Everything a user sets on one simulation of a Model, as one value: the solver options and, per
// dof, joint and link, the drives, limits, friction, envelopes, actuators, delays, wrap and mimic
// rows (docs/architecture.md, "Model, Settings, State, Workspace"). A Simulation holds one; its
// setters change one field each and throw the messages of the checks below.
#pragma once

#include <array>
#include <limits>
#include <string>
#include <vector>

#include "featherdrive/constraint/contact.hpp"
#include "featherdrive/constraint/drive.hpp"
#include "featherdrive/constraint/joint_constraints.hpp"
#include "featherdrive/constraint/mimic_row.hpp"
#include "featherdrive/constraint/row_kinds.hpp"
#include "featherdrive/model/model.hpp"
#include "featherdrive/sim/explicit_actuator.hpp"
#include "featherdrive/sim/link_parameters.hpp"
#include "featherdrive/sim/revolute_wrap.hpp"

namespace featherdrive {

enum class SolverType { pgs, tgs };
const char* to_string(SolverType type);

/// Whose defaults and step details a simulation follows. physx: PhysX 5.6.1's defaults for the
/// per-link and per-joint parameters nobody set, and its two departures from textbook Gauss-Seidel
/// (../shared/physx/NOTES.md; docs/physx_parity.md). Chosen at construction.
enum class Compat { none, physx };
const char* to_string(Compat compat);

/// The step guard (docs/math/step_guard.md): a step in which a joint moves more than
/// max_joint_step, or the kinetic + gravity energy grows more than the joint forces' work, is
/// redone as 2, 4, ... sub-steps of dt / n (at most max_substeps). Off by default; a step it
/// does not redo is the unguarded step, bit for bit.
struct StepGuard {
  bool enabled = false;
  double max_joint_step = 0.25;  ///< rad or m per (sub-)step; a spherical joint's rotation angle
  int max_substeps = 64;         ///< in [2, kMaxGuardSubsteps]
  /// Test (ii)'s share of the step's energy scale that may appear from nowhere; in (0, 1].
  double energy_tolerance = 0.02;
  /// Test (iii)'s share of the energy the dampers dissipated that the step may create over the
  /// run (eq. G-9); in (0, 100].
  double dissipation_share = 0.15;
};

inline constexpr int kMaxGuardSubsteps = 4096;

struct SimulationOptions {
  double dt = 1.0 / 60.0;           ///< time step tau [s]
  SolverType solver = SolverType::pgs;
  int position_iterations = 4;      ///< >= 1
  int velocity_iterations = 1;      ///< >= 0
  Compat compat = Compat::none;
  StepGuard guard;
};

/// dt must be a normal double (no subnormal: 1 / dt and impulse / dt stay finite) up to kMaxDt, so
/// that kMaxStepCount steps keep the clock finite.
inline constexpr double kMinDt = std::numeric_limits<double>::min();
inline constexpr double kMaxDt = 1e3;
inline constexpr int kMaxIterations = 1'000'000;  ///< per step, position and velocity each
/// The most steps a clock may count: 2^53, beyond which neither the count nor t = sum dt is exact
/// (and no run gets there: 2^53 steps at 1 ns each take 104 days).
inline constexpr long kMaxStepCount = 1L << 53;

/// Throws std::invalid_argument naming the field and value for dt outside [kMinDt, kMaxDt] or
/// non-finite, position_iterations outside [1, kMaxIterations], velocity_iterations outside
/// [0, kMaxIterations], guard.max_joint_step not finite and > 0, guard.max_substeps outside
/// [2, kMaxGuardSubsteps], guard.energy_tolerance outside (0, 1],
/// guard.dissipation_share outside (0, 100].
void validate_options(const SimulationOptions& options);

struct Settings {
  SimulationOptions options;

  // Per dof (nv each). The per-joint rows act on revolute, prismatic and spherical joints (a
  // spherical joint per axis); the other dofs keep the defaults.
  std::vector<Drive> drives;
  VecX lower_limit, upper_limit;  ///< enforced where finite
  VecX max_joint_velocity;        ///< largest |qd|; +inf for none
  std::vector<JointFriction> friction;
  std::vector<ActuatorEnvelope> envelopes;
  VecX friction_coefficient;      ///< PhysX's older joint friction (docs/math/joint_constraints.md)
  std::vector<RevoluteWrap> revolute_wrap;  ///< revolute dofs only (docs/math/revolute_wrap.md)
  std::vector<int> drive_delay;   ///< steps, [0, kMaxDelay]; > 0 only on an implicit drive
  std::vector<ExplicitActuator> actuators;  ///< kind none: no actuator (explicit_actuator.hpp)
  VecX actuator_feedforward;      ///< the feed-forward effort of the dof's actuator; 0 without one
  /// The row kinds' fields (constraint/row_kinds.hpp), nv x RowKinds::fields: row d holds dof
  /// d's, kind after kind (RowKindInfo::offset); each kind's defaults leave its row off.
  MatX row_parameters;

  std::vector<LinkParameters> link_parameters;  ///< per link (num_links)
  std::vector<MimicJoint> mimic_joints;         ///< docs/math/mimic_joints.md

  Ground ground;                  ///< contacts with the model's shapes when enabled
  ContactOptions contact;         ///< docs/math/contact.md, section 8

  /// What a new Simulation of `model` starts with: limits, friction (static = dynamic =
  /// model.friction, viscous = model.damping) and velocity limits from the model; with
  /// Compat::physx, PhysX 5.6.1's defaults for what the model leaves unset (wrapped revolute
  /// joints, link parameters, friction coefficient, max joint velocity 100).
  static Settings defaults(const Model& model, const SimulationOptions& options = {});

  /// Throws std::invalid_argument with the one-line message of the first setting the
  /// corresponding Simulation setter would refuse (same text), or naming the field whose size is
  /// not the model's. A setting of a dof or link that no setter can change must keep its default.
  void validate(const Model& model) const;
};

/// Row kind K's fields on dof d (its columns of row_parameters from `field`, RowKindList's offset).
template <class K>
std::array<double, K::fields.size()> row_values(const Settings& settings, int d, int field) {
  std::array<double, K::fields.size()> values;
  for (size_t j = 0; j < values.size(); ++j)
    values[j] = settings.row_parameters(d, field + static_cast<Eigen::Index>(j));
  return values;
}

// The checks of one setting, shared by Settings::validate and the Simulation setters: each throws
// std::invalid_argument naming the joint (or link), the field and the value.

/// dof in [0, nv).
int check_dof_index(const Model& model, int dof);
/// The dof a joint name means for the per-dof settings: a revolute or prismatic joint's, or a
/// spherical joint's axis named "J:twist", "J:swing1" or "J:swing2".
int setting_dof(const Model& model, const std::string& joint);
/// Whether a dof carries rows: revolute, prismatic, or a spherical joint's axis.
bool dof_has_rows(const Model& model, int dof);
/// `actuator_kind` is the dof's actuator (a drive of type != none cannot act beside one).
void check_drive(const Model& model, int dof, const Drive& drive, ActuatorKind actuator_kind);
void check_joint_limits(const Model& model, int dof, double lower, double upper);
void check_joint_friction(const Model& model, int dof, const JointFriction& friction);
void check_max_joint_velocity(const Model& model, int dof, double max_velocity);
void check_friction_coefficient(const Model& model, int dof, double coefficient);
void check_actuator_envelope(const Model& model, int dof, const ActuatorEnvelope& envelope);
void check_revolute_wrap(const Model& model, int dof, RevoluteWrap wrap);
/// `drive` is the dof's implicit drive (an actuator cannot act beside one of type != none).
void check_actuator(const Model& model, int dof, const ExplicitActuator& actuator,
                    const Drive& drive);
/// A delay needs an implicit drive (type != none) and no actuator on the dof.
void check_drive_delay(const Model& model, int dof, int delay, const Drive& drive,
                       ActuatorKind actuator_kind);
/// A row kind's fields on a dof (values: the kind's fields, in order): a dof with rows, and the
/// kind's own check.
void check_row_parameters(const Model& model, int dof, const RowKindInfo& kind,
                          std::span<const double> values);
/// An actuator's feed-forward effort: finite, on a dof with an actuator.
void check_actuator_feedforward(const Model& model, int dof, double effort,
                                ActuatorKind actuator_kind);
/// The ground: finite height, a normal of finite non-zero length, a valid material.
void check_ground(const Ground& ground);
/// An enabled ground needs every shape of the model to be one contacts support: throws
/// std::invalid_argument naming the first of Model::unsupported_shapes.
void check_ground_supported(const Model& model, const Ground& ground);
/// Offsets finite, 0 <= rest_offset < contact_offset; bounce_threshold finite and >= 0.
void check_contact_options(const ContactOptions& options);
void check_link_parameters_of(const Model& model, int link, const LinkParameters& parameters);
/// The message of a target on a dof that neither a drive nor an actuator reads.
std::string no_drive_message(const Model& model, int dof);

}  // namespace featherdrive
