// The options `simulate` and `compare-physx` share: a scene file's steps and solver settings,
// overridden from the command line.
#pragma once

#include <CLI/CLI.hpp>

#include <iostream>
#include <optional>
#include <string>

#include "featherdrive/io/scene.hpp"

struct SceneOverrides {
  std::optional<int> steps;
  std::string solver;
  std::optional<int> position_iterations;
  std::optional<int> velocity_iterations;

  /// The notes are appended to the iteration options' help (e.g. PhysX's range).
  void add_options(CLI::App* cmd, const std::string& position_note = "",
                   const std::string& velocity_note = "") {
    cmd->add_option("--steps", steps, "Number of steps (overrides the scene)")
        ->check(CLI::NonNegativeNumber);
    cmd->add_option("--solver", solver, "pgs or tgs (overrides the scene)")
        ->check(CLI::IsMember({"pgs", "tgs"}));
    cmd->add_option("--position-iterations", position_iterations, "Overrides the scene" + position_note)
        ->check(CLI::Range(1, 1000000));
    cmd->add_option("--velocity-iterations", velocity_iterations, "Overrides the scene" + velocity_note)
        ->check(CLI::Range(0, 1000000));
  }

  /// The solver settings given on the command line, over `options`.
  void apply(featherdrive::SimulationOptions& options) const {
    if (!solver.empty())
      options.solver = solver == "tgs" ? featherdrive::SolverType::tgs : featherdrive::SolverType::pgs;
    if (position_iterations) options.position_iterations = *position_iterations;
    if (velocity_iterations) options.velocity_iterations = *velocity_iterations;
  }

  /// The scene file with its warnings printed and the overrides applied (options validated).
  featherdrive::Scene load(const std::string& path) const {
    featherdrive::Scene scene = featherdrive::load_scene(path);
    for (const std::string& w : scene.robot.warnings)
      std::cerr << "featherdrive: warning: " << w << "\n";
    if (steps) scene.steps = *steps;
    apply(scene.options);
    featherdrive::validate_options(scene.options);
    return scene;
  }
};
