// PhysX 5.6.1's per-link and per-joint articulation parameters (../shared/physx/NOTES.md,
// "Parameters"; docs/physx_parity.md): their featherdrive defaults (inert) and PhysX's.
#pragma once

#include <limits>
#include <string>

namespace featherdrive {

/// One link's PhysX parameters. All may change between steps.
struct LinkParameters {
  /// cfm = cfm_scale x the largest diagonal entry of the link's linear whole-articulation
  /// response; acceleration drives, friction, limits and velocity limits of its joints use
  /// 1 / (r + cfm) (docs/math/joint_constraints.md, "Constraint force mixing"). In [0, 1].
  double cfm_scale = 0.0;
  double linear_damping = 0.0;   ///< [1/s]: force -m c v_com on the centre of mass, c = min(d, 1/dt)
  double angular_damping = 0.0;  ///< [1/s]: torque -I_w c omega
  /// Largest speed of the centre of mass [m/s] and largest |omega| [rad/s]; +inf for none. Past it
  /// the free velocity gets the force that would bring an isolated link back to it in one step.
  double max_linear_velocity = std::numeric_limits<double>::infinity();
  double max_angular_velocity = std::numeric_limits<double>::infinity();
};

/// Throws std::invalid_argument naming the link, the field and the value: cfm_scale outside
/// [0, 1], damping negative or not finite, a max velocity negative or NaN.
void validate_link_parameters(const LinkParameters& parameters, const std::string& link);
/// The joint friction coefficient must be finite and >= 0 (names the joint and the value).
void validate_friction_coefficient(double coefficient, const std::string& joint);

/// PhysX 5.6.1's defaults, which Compat::physx gives every parameter nobody set (sources:
/// PxvDynamics.h for cfmScale, ScBodyCore.cpp for an articulation link's damping and velocity
/// limits, DyArticulationJointCore.h for the joint's friction coefficient and max velocity).
namespace physx_default {
inline constexpr double cfm_scale = 0.025;
inline constexpr double linear_damping = 0.05;
inline constexpr double angular_damping = 0.05;
inline constexpr double max_linear_velocity = 100.0;  ///< 100 x PxTolerancesScale::length (1)
inline constexpr double max_angular_velocity = 50.0;
inline constexpr double friction_coefficient = 0.05;
inline constexpr double max_joint_velocity = 100.0;

inline LinkParameters link() {
  return {cfm_scale, linear_damping, angular_damping, max_linear_velocity, max_angular_velocity};
}
}  // namespace physx_default

}  // namespace featherdrive
