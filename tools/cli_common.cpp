#include "cli_common.hpp"

#include <signal.h>
#include <stdlib.h>

#include <algorithm>
#include <cctype>
#include <csignal>
#include <cstdlib>
#include <fstream>

#include "featherdrive/io/files.hpp"
#include "featherdrive/io/physx_runner.hpp"

namespace fs = std::filesystem;
using namespace featherdrive;

namespace {

volatile std::sig_atomic_t g_signal = 0;

extern "C" void on_signal(int signal) { g_signal = signal; }

}  // namespace

void install_interrupt_handlers() {
  struct sigaction action {};
  action.sa_handler = on_signal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESTART;  // a blocking write or waitpid goes on; the loop decides
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

int interrupted() { return g_signal; }

const char* signal_name(int signal) {
  return signal == SIGINT ? "SIGINT" : signal == SIGTERM ? "SIGTERM" : "a signal";
}

PrivateTempDir::PrivateTempDir() {
  std::string name = (fs::temp_directory_path() / "featherdrive-XXXXXX").string();
  if (::mkdtemp(name.data()) == nullptr)
    throw RunError("cannot make a temporary folder " + name);
  path_ = name;
}

PrivateTempDir::~PrivateTempDir() {
  std::error_code ec;
  fs::remove_all(path_, ec);
}

void check_outputs(const std::vector<Output>& outputs, const std::vector<Input>& inputs,
                   const std::vector<fs::path>& model_files) {
  std::vector<Input> all = inputs;
  for (const fs::path& file : model_files) all.emplace_back("a file the model reads", file);
  for (size_t i = 0; i < outputs.size(); ++i) {
    const auto& [option, path] = outputs[i];
    if (path.empty()) continue;
    check_replaceable(path);
    const FileIdentity id = file_identity(path);
    for (const auto& [what, input] : all)
      if (!input.empty() && file_identity(input) == id)
        throw std::invalid_argument(option + " " + path.string() + ": is " + what +
                                    " (an input of this run); refusing to overwrite it");
    for (size_t j = 0; j < i; ++j)
      if (!outputs[j].second.empty() && file_identity(outputs[j].second) == id)
        throw std::invalid_argument(option + " " + path.string() + ": is also " +
                                    outputs[j].first + "; two outputs cannot share a file");
  }
}

void check_plot_path(const std::string& option, const fs::path& png) {
  std::string ext = png.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext != ".png")
    throw std::invalid_argument(option + " " + png.string() + ": the plot must be a .png file");
}

void make_parent_folders(const fs::path& path) {
  if (!path.has_parent_path()) return;
  std::error_code ec;
  fs::create_directories(path.parent_path(), ec);
}

void run_plot_script(const std::string& script, const std::vector<std::string>& inputs,
                     const fs::path& png, const std::string& title, const PrivateTempDir& tmp) {
  const char* python_env = std::getenv("FEATHERDRIVE_PYTHON");
  const std::string python = python_env && *python_env ? python_env : "/usr/bin/python3";
  make_parent_folders(png);
  AtomicFile out(png, "the plot");
  std::vector<std::string> argv = {python, script, "--title=" + title, "--"};
  argv.insert(argv.end(), inputs.begin(), inputs.end());
  argv.push_back(out.temp_path().string());
  const fs::path log = tmp.path() / "plot-stderr.txt";
  const int rc = run_program(argv, log);
  if (rc != 0) {
    std::ifstream in(log);
    std::string line, last;
    while (std::getline(in, line))
      if (line.find_first_not_of(" \t\r") != std::string::npos) last = line;
    std::string m = "plotting " + png.string() + " failed: ";
    if (!last.empty())
      m += last;
    else
      m += python + (rc < 0 ? " could not be run" : " exited with " + std::to_string(rc));
    throw RunError(m);
  }
  out.commit();
}

bool clear_row_kinds(Simulation& sim, int d) {
  bool had = false;
  for (const RowKindInfo& kind : row_kinds()) {
    if (!kind.active(sim.row_parameters(kind.name, d))) continue;
    std::vector<double> defaults;
    for (const RowField& f : kind.fields) defaults.push_back(f.default_value);
    sim.set_row_parameters(kind.name, d, defaults);
    had = true;
  }
  return had;
}
