// The ground-contact cases of issue 34 as docs/math/contact.md, section 11 describes them and
// bench/physx_contact_reference.js builds them in PhysX: a box resting or sliding on the ground and
// a capsule-legged quadruped standing or dropped, built with ModelBuilder and add_shape, and
// simulations set up as the bench sets PhysX up.
#pragma once

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "featherdrive/model/model_builder.hpp"
#include "featherdrive/sim/simulation.hpp"

namespace featherdrive::test {

inline constexpr double kContactGravity = 9.81;
inline constexpr double kContactDt = 0.01;

/// The box of cases a and b: 1 kg, a 0.2 m cube, the one link ("box") of a floating root, one box
/// shape with static = dynamic friction `mu`.
std::shared_ptr<const Model> make_ground_box(double mu = 0.5);

/// The quadruped of cases d and e. Base "base": a 0.4 x 0.2 x 0.1 m box of 4 kg, its centre of
/// mass at its frame's origin. Legs fl, fr, hl, hr at (+-0.15, +-0.12, -0.05) in the base frame,
/// each a hip joint "<leg>_hip" (revolute about y) to link "<leg>_thigh" (0.5 kg) and a knee joint
/// "<leg>_knee" (revolute about y, 0.2 m below the hip) to link "<leg>_shin" (0.3 kg); link frames
/// at the joints, centres of mass 0.1 m below them, solid-cylinder inertias (r 0.025 m, 0.2 m).
/// Without shapes: tests/data/quadruped.urdf is the same robot.
ModelBuilder quadruped_builder();
/// The quadruped's collision shapes (link name, shape): the base's box and a capsule of radius
/// 0.025 m along each thigh and shin (its segment from the joint 0.2 m down the link's -z), all of
/// friction `mu`.
std::vector<std::pair<std::string, CollisionShape>> quadruped_shapes(double mu = 1.0);
/// quadruped_builder() with quadruped_shapes(mu) added.
std::shared_ptr<const Model> make_quadruped(double mu = 1.0);

inline constexpr double kQuadrupedHip = 0.5;    ///< the drives' targets and the initial pose [rad]
inline constexpr double kQuadrupedKnee = -1.0;
/// The base height at which the initial pose's feet touch the ground (0.426033 m).
double quadruped_standing_height();

/// A simulation as the bench runs PhysX: `compat: physx` (PhysX's link and joint defaults) with
/// zero link damping, 4/1 iterations, dt 0.01, gravity -9.81 z, the ground z = 0 with static =
/// dynamic friction `mu` and restitution 0, the contact options' defaults.
Simulation contact_reference_simulation(std::shared_ptr<const Model> model, SolverType solver,
                                        double mu);

/// Case a (v0 = 0) or b: the box touching the ground, moving along x at v0.
Simulation ground_box_simulation(SolverType solver, double v0);
/// Case d (lift 0) or e (lift 0.2 m): the quadruped at rest in its initial pose, its feet `lift`
/// above the ground, its drives PD (kp 300, kd 10, force) to the pose.
Simulation quadruped_simulation(SolverType solver, double lift);

}  // namespace featherdrive::test
