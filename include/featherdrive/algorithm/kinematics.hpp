// Forward kinematics: link poses, spatial velocities and velocity-product accelerations, O(n).
#pragma once

#include "featherdrive/algorithm/data.hpp"

namespace featherdrive {

/// Fills data.parent_transform, world_rotation, frame_position and world_position from q (nq).
void forward_kinematics(const Model& model, Data& data, const VecX& q);

/// data.world_rotation, frame_position and world_position from q; data.parent_transform only where
/// a joint is not a revolute about a coordinate axis (what the step reads: rnea and crba fill their
/// own).
void world_poses(const Model& model, Data& data, const VecX& q);

/// The links' world rotations R and positions p (num_links each, the caller's) from q by
/// world_poses's operations (docs/math/joint_transform.md, JT-3 to JT-9), reading only data's
/// constants: compat physx's poses of a sub-step (sim/link_bias.cpp's world_pose).
void world_poses(const Data& data, const VecX& q, Mat3* R, Vec3* p);

/// As forward_kinematics(model, data, q), and data.velocity and data.bias_acceleration from v (nv).
void forward_kinematics(const Model& model, Data& data, const VecX& q, const VecX& v);

}  // namespace featherdrive
