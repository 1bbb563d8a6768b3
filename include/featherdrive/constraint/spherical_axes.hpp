// A spherical joint's three dofs as PhysX 5.6.1 has them (eTWIST, eSWING1, eSWING2 about the
// joint frame's x, y, z): the joint positions it reports and the drive error its rows use.
// docs/math/spherical_joints.md.
#pragma once

#include <array>

#include "featherdrive/spatial/types.hpp"

namespace featherdrive {

/// PhysX's joint positions (twist, swing1, swing2) of a spherical joint whose link frame has
/// orientation Q in the joint frame: the rotation vector angle * axis of Q, the angle in
/// [0, pi] (eq. S-2). Not a twist/swing decomposition: PhysX's articulation reports this.
Vec3 spherical_joint_positions(const Quat& Q);

/// PhysX's drive error (target - position per axis, eq. S-5): the targets of the driven axes
/// (driven[k]) make one target rotation T = exp(sum_k target_k e_k); the error is
/// -2 Im(T* Q), T taken in the hemisphere of Q. Zero when no axis is driven.
Vec3 spherical_drive_error(const Quat& Q, const Vec3& target, const std::array<bool, 3>& driven);

}  // namespace featherdrive
