// Jacobians of frames fixed on links and their time variation, on kinematics already in data
// (forward_kinematics; with velocities for jacobian_dot_times_v). O(d) in the depth d of the link.
// Columns are with respect to v (nv): for a floating base, the body-frame twist of the root
// (docs/conventions.md, "Kinematics and dynamics").
#pragma once

#include "featherdrive/algorithm/frame_kinematics.hpp"

namespace featherdrive {

/// J (6 x nv) with J v = frame_velocity(model, data, link, point, reference). J is resized to
/// 6 x nv if it has another size (the only allocation; reuse it).
void frame_jacobian(const Model& model, const Data& data, int link, const Vec3& point,
                    ReferenceFrame reference, MatX& J);

inline void link_jacobian(const Model& model, const Data& data, int link,
                          ReferenceFrame reference, MatX& J) {
  frame_jacobian(model, data, link, Vec3::Zero(), reference, J);
}

/// dJ/dt v for the frame_jacobian of the same arguments: the frame's acceleration at qdd = 0.
/// world_aligned: the classical acceleration d/dt [omega; point velocity] in world coordinates
/// (Pinocchio's getFrameClassicalAcceleration at a = 0, gravity excluded); local: the spatial
/// acceleration in the frame's own axes (d/dt of the local velocity, Pinocchio's
/// getFrameAcceleration in LOCAL at a = 0).
Vec6 jacobian_dot_times_v(const Model& model, const Data& data, int link, const Vec3& point,
                          ReferenceFrame reference);

}  // namespace featherdrive
