// Actuator delay of the implicit drives (Isaac Lab's DelayedPDActuator, with PhysX's implicit
// drive instead of an explicit PD): a delayed dof's drive row uses the targets commanded `delay`
// steps earlier. A stage at the start of the step; docs/math/implicit_drives.md, "Delay".
#pragma once

#include <vector>

#include "featherdrive/constraint/drive.hpp"
#include "featherdrive/sim/delay_line.hpp"

namespace featherdrive {

/// What a delayed drive is told: its target position and velocity.
struct DriveTarget {
  double position = 0.0;
  double velocity = 0.0;
};

/// The drive delays of one simulation: per dof a delay line (none while the delay is 0, so an
/// undelayed drive costs nothing) and the drive with the targets the step's row uses.
class DriveDelays {
 public:
  explicit DriveDelays(int nv = 0);

  /// Sets dof's delay (0 removes it; [0, kMaxDelay], checked by the caller) and empties its
  /// history.
  void set(int dof, int delay);
  int delay(int dof) const { return lines_[static_cast<size_t>(dof)].delay(); }
  bool delayed(int dof) const { return delay(dof) > 0; }
  bool any() const { return !active_.empty(); }
  /// Once per step: pushes every delayed dof's targets (drives' current ones) and keeps the drive
  /// with the delayed targets, eq. (8)-(9), for drive_seen().
  void push(const std::vector<Drive>& drives);
  /// A delayed dof's drive as the last push() left it: its settings, the delayed targets.
  const Drive& drive_seen(int dof) const { return seen_[static_cast<size_t>(dof)]; }
  /// Takes back the last push() (a step that diverged).
  void undo_push();
  /// Empties every history (an episode starting over, Batch::reset).
  void reset_history();

  /// For checkpoints: a dof's pushes and ring (delay + 1 targets).
  long pushes(int dof) const { return lines_[static_cast<size_t>(dof)].pushes(); }
  const std::vector<DriveTarget>& ring(int dof) const {
    return lines_[static_cast<size_t>(dof)].ring();
  }
  /// Throws std::invalid_argument for pushes < 0, a ring of another size than delay + 1 or a
  /// target that is not finite.
  void restore_history(int dof, long pushes, const std::vector<DriveTarget>& ring);

 private:
  std::vector<DelayLine<DriveTarget>> lines_;
  std::vector<Drive> seen_;
  std::vector<int> active_;  ///< delayed dofs, ascending
};

}  // namespace featherdrive
