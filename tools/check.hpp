// `featherdrive check SCENE` (check.cpp): will the scene's run stay bounded? Per joint the
// one-joint step map, for the robot a trial run, the smallest fixes, and a last line
// `verdict: stable` or `verdict: unstable: ...` (docs/stability_check.md).
#pragma once

#include <CLI/CLI.hpp>

#include <optional>
#include <string>

#include "scene_overrides.hpp"

struct CheckArgs {
  std::string scene;
  SceneOverrides overrides;
  std::optional<std::string> trial_steps;  ///< --trial-steps as typed
};

/// The subcommand on `app`.
CLI::App* add_check_command(CLI::App& app, CheckArgs& args);

/// Prints the report; 0 for both verdicts. Throws std::invalid_argument for bad input.
int check_scene_command(const CheckArgs& args);
