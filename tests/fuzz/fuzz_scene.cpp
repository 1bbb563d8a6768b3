// libFuzzer: scene files from fuzzed YAML text, read as if they were tests/fuzz/scene.yaml, so
// that `model: robot.urdf` finds the small URDF beside it. Bad input must end in InputError (or
// another std::invalid_argument); a scene that loads runs up to 20 steps with a finite state or a
// DivergenceError.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <string>

#include "check.hpp"
#include "featherdrive/io/scene.hpp"

using namespace featherdrive;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size > 8000) return -1;
  const std::string text(reinterpret_cast<const char*>(data), size);
  Scene scene;
  try {
    scene = parse_scene(text, std::string(FEATHERDRIVE_FUZZ_DIR) + "/scene.yaml");
  } catch (const std::invalid_argument&) {
    return 0;
  }
  if (scene.steps < 0) fuzz::bug("negative steps");
  Simulation sim = make_simulation(scene);
  fuzz::check_finite(sim);
  const int steps = std::min(scene.steps, 20);
  for (int k = 0; k < steps; ++k) {
    try {
      apply_targets(scene, sim, k);
    } catch (const std::invalid_argument&) {
      break;  // a sine target that overflows at this time
    }
    if (!fuzz::checked_step(sim)) break;
  }
  return 0;
}
