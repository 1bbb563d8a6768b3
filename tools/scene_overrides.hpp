// The options `simulate` and `compare-physx` share: a scene file's steps and solver settings,
// overridden from the command line.
#pragma once

#include <CLI/CLI.hpp>

#include <charconv>
#include <climits>
#include <iostream>
#include <optional>
#include <stdexcept>
#include <string>

#include "featherdrive/io/scene.hpp"

/// An integer option's text range-checked in 64 bits before it is narrowed to int (CLI11 would
/// wrap 4294967297 to 1 or print its check with DBL_MAX). Throws std::invalid_argument
/// "--steps = -5: must be between 0 and 2147483647".
inline int integer_option(const char* option, const std::string& text, long long lowest,
                          long long highest) {
  const std::string shown = text.size() > 40 ? text.substr(0, 40) + "..." : text;
  const std::string range =
      "between " + std::to_string(lowest) + " and " + std::to_string(highest);
  const char* begin = text.data() + (!text.empty() && text[0] == '+');
  const char* end = text.data() + text.size();
  long long value = 0;
  const auto [stop, ec] = std::from_chars(begin, end, value);
  if (stop != end || begin == end || (ec != std::errc() && ec != std::errc::result_out_of_range))
    throw std::invalid_argument(std::string(option) + " = " + shown + ": must be an integer " +
                                range);
  if (ec == std::errc::result_out_of_range || value < lowest || value > highest)
    throw std::invalid_argument(std::string(option) + " = " + shown + ": must be " + range);
  return static_cast<int>(value);
}

struct SceneOverrides {
  std::optional<int> steps;
  std::string solver;
  std::optional<int> position_iterations;
  std::optional<int> velocity_iterations;
  std::optional<int> substeps;
  // The integer options as typed, checked by parse().
  std::optional<std::string> steps_text, position_text, velocity_text, substeps_text;

  /// The notes are appended to the iteration options' help (e.g. PhysX's range).
  void add_options(CLI::App* cmd, const std::string& position_note = "",
                   const std::string& velocity_note = "") {
    // Read as text for their range messages (parse), shown as the integers they are.
    cmd->add_option("--steps", steps_text,
                    "Number of steps, 0 to 2147483647 (overrides the scene)")
        ->type_name("INT");
    cmd->add_option("--solver", solver, "pgs or tgs (overrides the scene)")
        ->check(CLI::IsMember({"pgs", "tgs"}));
    const std::string most = std::to_string(featherdrive::kMaxIterations);
    cmd->add_option("--position-iterations", position_text,
                    "1 to " + most + ", overrides the scene" + position_note)
        ->type_name("INT");
    cmd->add_option("--velocity-iterations", velocity_text,
                    "0 to " + most + ", overrides the scene" + velocity_note)
        ->type_name("INT");
    cmd->add_option("--substeps", substeps_text,
                    "Physics steps per control step (the scene's control.substeps), 1 to " +
                        std::to_string(featherdrive::kMaxSubsteps))
        ->type_name("INT");
  }

  /// The integer options from their text; throws std::invalid_argument naming the option and
  /// the value when one is not an integer in its range.
  void parse() {
    if (steps_text) steps = integer_option("--steps", *steps_text, 0, INT_MAX);
    if (position_text)
      position_iterations = integer_option("--position-iterations", *position_text, 1,
                                           featherdrive::kMaxIterations);
    if (velocity_text)
      velocity_iterations = integer_option("--velocity-iterations", *velocity_text, 0,
                                           featherdrive::kMaxIterations);
    if (substeps_text)
      substeps = integer_option("--substeps", *substeps_text, 1, featherdrive::kMaxSubsteps);
  }

  /// The solver settings given on the command line, over `options`.
  void apply(featherdrive::SimulationOptions& options) const {
    if (!solver.empty())
      options.solver =
          solver == "tgs" ? featherdrive::SolverType::tgs : featherdrive::SolverType::pgs;
    if (position_iterations) options.position_iterations = *position_iterations;
    if (velocity_iterations) options.velocity_iterations = *velocity_iterations;
  }

  /// The scene file with its warnings printed and the overrides applied (options validated).
  featherdrive::Scene load(const std::string& path) const {
    featherdrive::Scene scene = featherdrive::load_scene(path);
    for (const std::string& w : scene.robot.warnings)
      std::cerr << "featherdrive: warning: " << w << "\n";
    if (steps) scene.steps = *steps;
    if (substeps) scene.control.substeps = *substeps;
    apply(scene.options);
    featherdrive::validate_options(scene.options);
    return scene;
  }
};
