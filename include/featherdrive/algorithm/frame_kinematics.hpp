// Poses and velocities of links and of frames fixed on links (Pinocchio's getFrameVelocity), on
// kinematics already in data: forward_kinematics(model, data, q) for positions,
// forward_kinematics(model, data, q, v) for velocities. Each is O(1) after it.
//
// A frame is a point fixed on a link (given in the link frame) with the link's axes; the link's
// own frame is the point 0. Spatial vectors are [angular; linear] (docs/conventions.md,
// "Kinematics and dynamics"), expressed in one of two frames:
//  - local: the frame's own axes, origin at the point (Pinocchio's LOCAL, MuJoCo's cvel is not);
//  - world_aligned: world axes, origin at the point (Pinocchio's LOCAL_WORLD_ALIGNED): the
//    angular velocity and the point's velocity in world coordinates, d/dt of its world position.
#pragma once

#include "featherdrive/algorithm/data.hpp"

namespace featherdrive {

enum class ReferenceFrame { local, world_aligned };

/// Throws std::invalid_argument naming the index when link is not a link of the model.
void check_link_index(const Model& model, int link);

/// World position of a point fixed on a link (point in link coordinates).
Vec3 frame_position(const Model& model, const Data& data, int link, const Vec3& point);

/// Spatial velocity [omega; velocity of the point] of the frame at `point` on `link`.
Vec6 frame_velocity(const Model& model, const Data& data, int link, const Vec3& point,
                    ReferenceFrame reference);

/// A point given in a named frame's coordinates (Model::frame), in its link's coordinates.
inline Vec3 point_on_link(const NamedFrame& frame, const Vec3& point) {
  return frame.position + frame.rotation * point;
}

/// World rotation and position of a named frame (a link's, or a merged link's fixed in it).
Mat3 frame_rotation(const Model& model, const Data& data, const NamedFrame& frame);
Vec3 frame_position(const Model& model, const Data& data, const NamedFrame& frame,
                    const Vec3& point = Vec3::Zero());
/// frame_velocity of the point (frame coordinates) on a named frame; local: the frame's axes.
Vec6 frame_velocity(const Model& model, const Data& data, const NamedFrame& frame,
                    const Vec3& point, ReferenceFrame reference);

/// The link frame's spatial velocity (the point 0). local is data.velocity[link].
inline Vec6 link_velocity(const Model& model, const Data& data, int link,
                          ReferenceFrame reference) {
  return frame_velocity(model, data, link, Vec3::Zero(), reference);
}

}  // namespace featherdrive
