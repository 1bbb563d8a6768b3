// `featherdrive compare-mujoco SCENE` (compare_mujoco.cpp): the scene in featherdrive and in
// MuJoCo 2.2.2 through the exported MJCF, per joint the largest differences of q, qd and force,
// with translated and with literal gains. `featherdrive translate SCENE --to mujoco --out X.xml`
// (translate.cpp): the MJCF with translated drives and the match per joint.
#pragma once

#include <CLI/CLI.hpp>

#include <stdexcept>
#include <string>
#include <vector>

#include "featherdrive/sim/simulation.hpp"
#include "scene_overrides.hpp"

struct CompareMujocoArgs {
  std::string scene;
  std::string plot;
  std::string integrator = "euler";
  bool translate_only = false, literal_only = false;
  SceneOverrides overrides;
};

struct TranslateArgs {
  std::string scene;
  std::string to;
  std::string out;
  std::string integrator = "euler";
  bool keep_timestep = false;
  SceneOverrides overrides;
  std::vector<std::string> packages;  ///< --package NAME=DIR, for the URDF's package:// meshes
};

/// Both return the exit code; throw std::invalid_argument for bad input, other exceptions for
/// runtime failures (MuJoCo refusing the export, files that cannot be written, the plot).
int compare_mujoco(const CompareMujocoArgs& args);
int translate(const TranslateArgs& args);

/// The two subcommands on `app`; run() runs the one the command line chose.
class MujocoCommands {
 public:
  explicit MujocoCommands(CLI::App& app);
  bool selected() const { return *compare_ || *translate_; }
  int run();

 private:
  CompareMujocoArgs compare_args_;
  TranslateArgs translate_args_;
  CLI::App* compare_;
  CLI::App* translate_;
};
