// `featherdrive compare-physx SCENE`: the scene in featherdrive and in PhysX 5.6.1 (the harness of
// tests/physx/ under node), and per joint the largest differences of q, qd and force.
#pragma once

#include <string>

#include "scene_overrides.hpp"

struct ComparePhysxArgs {
  std::string scene;
  std::string plot;
  SceneOverrides overrides;
};

/// Returns the exit code; throws std::invalid_argument for bad input, other exceptions for
/// runtime failures (node or the PhysX package missing, the harness failing, plotting).
int compare_physx(const ComparePhysxArgs& args);
