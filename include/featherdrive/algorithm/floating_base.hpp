// A floating root's pose and velocity in world axes (docs/conventions.md, "Floating"): what a
// scene's `initial.base` and Python's set_base_state give, converted to and from the root's q
// (position and orientation in its joint frame) and qd (the body-frame twist [w; v]).
#pragma once

#include "featherdrive/model/model.hpp"

namespace featherdrive {

/// The root link's pose and velocity, all in world axes.
struct BaseState {
  Vec3 position = Vec3::Zero();         ///< the root link's origin [m]
  Quat orientation = Quat::Identity();  ///< the root link's orientation
  Vec3 linear_velocity = Vec3::Zero();  ///< the velocity of the root link's origin [m/s]
  Vec3 angular_velocity = Vec3::Zero();  ///< [rad/s]
};

/// Writes the root's 7 entries of q and 6 of qd (the other entries untouched). A nonzero
/// orientation is normalised. Throws std::invalid_argument when the model has no floating root,
/// a value is not finite, the orientation is zero or q, qd have the wrong size.
void set_base_state(const Model& model, const BaseState& base, VecX& q, VecX& qd);

/// The root's pose and velocity in world axes (the inverse of set_base_state). Throws
/// std::invalid_argument when the model has no floating root or q, qd have the wrong size.
BaseState base_state(const Model& model, const VecX& q, const VecX& qd);

}  // namespace featherdrive
