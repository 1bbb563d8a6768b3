// The range of drive targets whose impulses a double still resolves (docs/math/implicit_drives.md,
// "The range of targets", eq. T1-T3): validate_drive and the scene reader refuse targets beyond it.
#pragma once

namespace featherdrive {

/// The largest |target_position| (m or rad) of a drive with stiffness > 0: the step's drive impulse moves the velocity by up to
/// |x_T - x_0| / dt, and its rounding, eps |x_T - x_0| / dt, must stay far below what the other
/// impulses of a step change (gravity's g dt, 1e-2 m/s at 1 ms).
inline constexpr double kMaxDriveTargetPosition = 1e6;
/// The largest |target_velocity| (m/s or rad/s) of a drive with damping > 0, for the same reason (rounding eps |v_T|).
inline constexpr double kMaxDriveTargetVelocity = 1e6;

}  // namespace featherdrive
