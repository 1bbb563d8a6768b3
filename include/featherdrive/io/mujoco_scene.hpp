// `translate --to physx`: an MJCF robot's MuJoCo drives (position and velocity actuators, joint
// damping, its timestep and integrator) as featherdrive force drives in a scene file that reads
// the MJCF itself (docs/mujoco_bridge.md, eq. B11-B12).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "featherdrive/sim/gain_translation.hpp"

namespace featherdrive {

struct TranslatedJoint {
  std::string joint;
  double effective_inertia = 0.0;  ///< at MuJoCo's qpos0, armature included
  MujocoDrive mujoco;              ///< as the MJCF has it (armature: in the model already)
  PhysxTranslation physx;
};

struct SceneTranslation {
  std::string yaml;  ///< the scene file's text
  double dt = 0.0;   ///< MuJoCo's timestep
  MujocoIntegrator integrator = MujocoIntegrator::euler;
  std::vector<TranslatedJoint> joints;
  std::vector<std::string> notes;  ///< one line each: what is not carried
  /// yaml is the scene an export kept in the MJCF (kMjcfSceneText), its model the MJCF; joints
  /// still holds the translation of the MJCF's drives.
  bool restored = false;
};

/// Reads the MJCF (load_mjcf, and MuJoCo's compiler for its options) and translates every joint
/// with a position or velocity actuator to a featherdrive force drive under `options` (solver
/// and iterations; dt is MuJoCo's timestep). The scene's `model` is the MJCF's path relative to
/// scene_path's folder; its joint damping moves into the drives (the joints' viscous friction is
/// set to 0 there). Throws InputError naming the file for an MJCF MuJoCo or load_mjcf refuses, the
/// RK4 integrator, or no actuator to translate.
SceneTranslation translate_mjcf_to_scene(const std::filesystem::path& mjcf,
                                         const std::filesystem::path& scene_path,
                                         const SimulationOptions& options, int steps);

}  // namespace featherdrive
