// What `simulate` and `compare-physx` share beyond their options: signals, a private temporary
// folder, the checks on output paths and the plot scripts.
#pragma once

#include <filesystem>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "featherdrive/sim/simulation.hpp"

// Failures that are not the input's fault (files that cannot be written, the plot script).
struct RunError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// SIGINT and SIGTERM only set a flag from here on; the step loops poll it between whole steps.
void install_interrupt_handlers();
/// The signal received (SIGINT, SIGTERM) or 0.
int interrupted();
/// "SIGINT", "SIGTERM".
const char* signal_name(int signal);

/// A folder only this user can enter (mkdtemp under $TMPDIR), removed with all it holds when
/// this goes out of scope: on return, on an exception and after an interrupt.
class PrivateTempDir {
 public:
  PrivateTempDir();
  ~PrivateTempDir();
  PrivateTempDir(const PrivateTempDir&) = delete;
  PrivateTempDir& operator=(const PrivateTempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

/// An output of the run: its option and path.
using Output = std::pair<std::string, std::filesystem::path>;
/// An input of the run: what it is ("the scene") and its path.
using Input = std::pair<std::string, std::filesystem::path>;

/// Before anything runs: refuses (std::invalid_argument, one line) an output that is one of the
/// inputs, one of `model_files` (what the robot's loader read: UrdfRobot::input_files, an MJCF's
/// includes and meshes) or another output (by file identity, so links and other spellings are
/// caught) or that exists and is not a regular file. Outputs with an empty path are skipped.
void check_outputs(const std::vector<Output>& outputs, const std::vector<Input>& inputs,
                   const std::vector<std::filesystem::path>& model_files = {});

/// "--plot out.jpg: the plot must be a .png file" for any other extension.
void check_plot_path(const std::string& option, const std::filesystem::path& png);

/// Creates the folders an output will be written into (failures show when it is written).
void make_parent_folders(const std::filesystem::path& path);

/// Runs $FEATHERDRIVE_PYTHON (default /usr/bin/python3) on `script` with --title and the
/// `inputs` after `--` (so a path beginning with '-' is a path), writing the PNG to a temporary
/// file that replaces `png` only when the script succeeds. Throws RunError with the script's
/// last line on stderr when it fails (no traceback).
void run_plot_script(const std::string& script, const std::vector<std::string>& inputs,
                     const std::filesystem::path& png, const std::string& title,
                     const PrivateTempDir& tmp);

/// Sets dof d's row kinds (constraint/row_kinds.hpp) to their defaults, for a peer that has
/// none; returns whether the dof had one.
bool clear_row_kinds(featherdrive::Simulation& sim, int d);

