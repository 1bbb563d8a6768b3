// A scene's stability check: the trial run follows the scene's time-varying targets.
#include "featherdrive/io/scene_check.hpp"

#include <memory>

namespace featherdrive {

StabilityReport check_scene(const Scene& scene, StabilityCheckOptions options) {
  const Simulation sim = make_simulation(scene);
  // A trial at dt / k is the scene with k times the control sub-steps: its targets change at
  // the same times (docs/math/control_step.md).
  auto work = std::make_shared<Scene>(scene);
  const int control = scene.control.substeps;
  options.before_step = [work, control](Simulation& s, int step, int substeps) {
    work->control.substeps = control * substeps;
    apply_targets(*work, s, step);
  };
  return check_stability(sim, options);
}

}  // namespace featherdrive
