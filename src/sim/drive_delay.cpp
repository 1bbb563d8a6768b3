#include "featherdrive/sim/drive_delay.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace featherdrive {

DriveDelays::DriveDelays(int nv)
    : lines_(static_cast<size_t>(nv)), seen_(static_cast<size_t>(nv)) {}

void DriveDelays::set(int dof, int delay) {
  DelayLine<DriveTarget>& line = lines_[static_cast<size_t>(dof)];
  active_.erase(std::remove(active_.begin(), active_.end(), dof), active_.end());
  if (delay == 0) {
    line.clear();
    return;
  }
  line.set_delay(delay);
  active_.insert(std::upper_bound(active_.begin(), active_.end(), dof), dof);
}

void DriveDelays::push(const std::vector<Drive>& drives) {
  for (const int d : active_) {
    const Drive& drive = drives[static_cast<size_t>(d)];
    const DriveTarget& target =
        lines_[static_cast<size_t>(d)].push({drive.target_position, drive.target_velocity});
    Drive& seen = seen_[static_cast<size_t>(d)];
    seen = drive;
    seen.target_position = target.position;
    seen.target_velocity = target.velocity;
  }
}

void DriveDelays::undo_push() {
  for (const int d : active_) lines_[static_cast<size_t>(d)].undo_push();
}

void DriveDelays::reset_history() {
  for (const int d : active_) lines_[static_cast<size_t>(d)].reset();
}

void DriveDelays::restore_history(int dof, long pushes, const std::vector<DriveTarget>& ring) {
  const std::string what = "drive delay history of dof " + std::to_string(dof);
  for (const DriveTarget& t : ring)
    if (!std::isfinite(t.position) || !std::isfinite(t.velocity))
      throw std::invalid_argument(what + ": a target is not finite");
  lines_[static_cast<size_t>(dof)].restore(pushes, ring, what);
}

}  // namespace featherdrive
