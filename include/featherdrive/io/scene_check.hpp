// The stability check (sim/stability_check.hpp) of a scene: its simulation at the initial state,
// its trial run following the scene's targets and applied forces (apply_targets).
#pragma once

#include "featherdrive/io/scene.hpp"
#include "featherdrive/sim/stability_check.hpp"

namespace featherdrive {

/// check_stability of make_simulation(scene), the trial run setting the scene's targets of each
/// step (options.before_step is replaced).
StabilityReport check_scene(const Scene& scene, StabilityCheckOptions options = {});

}  // namespace featherdrive
