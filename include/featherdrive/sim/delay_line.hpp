// A fixed delay of d steps on one dof's commands (Isaac Lab's DelayBuffer with one delay): the
// ring of the last d + 1 samples, sized when the delay is set, so a push allocates nothing.
// Used by the explicit actuators and the implicit drives' delay (docs/math/explicit_actuators.md,
// eq. 8-9).
#pragma once

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

namespace featherdrive {

/// The most steps a command may be delayed (a ring of delay + 1 samples per dof).
inline constexpr int kMaxDelay = 100'000;

template <class Sample>
class DelayLine {
 public:
  /// Sets the delay (in [0, kMaxDelay], checked by the caller) and empties the history.
  void set_delay(int delay) {
    ring_.assign(static_cast<size_t>(delay) + 1, Sample{});
    pushes_ = 0;
  }
  /// Removes the ring (no delay line on this dof).
  void clear() {
    ring_.clear();
    pushes_ = 0;
  }
  int delay() const { return ring_.empty() ? 0 : static_cast<int>(ring_.size()) - 1; }
  /// Stores this step's sample and returns the one of `delay` pushes ago, eq. (8), or the oldest
  /// there is while fewer have been made since set_delay or reset, eq. (9).
  const Sample& push(const Sample& sample) {
    const long n = static_cast<long>(ring_.size());
    ring_[static_cast<size_t>(pushes_ % n)] = sample;
    const long lag = std::min<long>(n - 1, pushes_);
    const Sample& seen = ring_[static_cast<size_t>((pushes_ - lag) % n)];
    ++pushes_;
    return seen;
  }
  /// The sample the last push returned (push must have been called since set_delay or reset).
  const Sample& last_seen() const {
    const long n = static_cast<long>(ring_.size());
    const long last = pushes_ - 1;
    return ring_[static_cast<size_t>((last - std::min<long>(n - 1, last)) % n)];
  }
  /// Takes back the last push (a step that diverged): it overwrote the sample delay + 1 pushes
  /// old, which no step reads again.
  void undo_push() {
    if (pushes_ > 0) --pushes_;
  }
  /// Empties the history: the next push starts over with eq. (9).
  void reset() { pushes_ = 0; }

  /// For checkpoints: pushes since set_delay (or reset) and the ring (delay + 1 samples).
  long pushes() const { return pushes_; }
  const std::vector<Sample>& ring() const { return ring_; }
  /// Throws std::invalid_argument starting with `what` for pushes outside [0, 2^53] (no run
  /// makes more steps; more could overflow) or a ring of another size.
  void restore(long pushes, const std::vector<Sample>& ring, const std::string& what) {
    if (pushes < 0 || pushes > (1L << 53))
      throw std::invalid_argument(what + ": pushes = " + std::to_string(pushes) +
                                  " must be in [0, 2^53]");
    if (ring.size() != ring_.size())
      throw std::invalid_argument(what + ": " + std::to_string(ring.size()) +
                                  " samples, expected " + std::to_string(ring_.size()) +
                                  " (delay + 1)");
    pushes_ = pushes;
    ring_ = ring;
  }

 private:
  std::vector<Sample> ring_;
  long pushes_ = 0;
};

}  // namespace featherdrive
