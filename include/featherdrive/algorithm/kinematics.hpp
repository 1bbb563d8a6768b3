// Forward kinematics: link poses, spatial velocities and velocity-product accelerations, O(n).
#pragma once

#include "featherdrive/algorithm/data.hpp"

namespace featherdrive {

/// Fills data.parent_transform, world_rotation, world_position from q (nq).
void forward_kinematics(const Model& model, Data& data, const VecX& q);

/// data.world_rotation and world_position from q; data.parent_transform only where a joint is not
/// a revolute about a coordinate axis (what the step reads: rnea and crba fill their own).
void world_poses(const Model& model, Data& data, const VecX& q);

/// As forward_kinematics(model, data, q), and data.velocity and data.bias_acceleration from v (nv).
void forward_kinematics(const Model& model, Data& data, const VecX& q, const VecX& v);

}  // namespace featherdrive
