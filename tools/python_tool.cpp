#include "python_tool.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <vector>

CLI::App* add_python_tool(CLI::App& app, int argc, char** argv, const std::string& name,
                          const std::string& module, const std::string& description) {
  CLI::App* cmd = app.add_subcommand(name, description + " (featherdrive " + name + " --help)");
  // The module sees every argument: CLI11 neither parses nor answers --help here.
  cmd->prefix_command();
  cmd->allow_extras();
  cmd->set_help_flag();
  cmd->callback([argc, argv, name, module] {
    const char* python_env = std::getenv("FEATHERDRIVE_PYTHON");
    const std::string python = python_env && *python_env ? python_env : "/usr/bin/python3";
    const char* old = std::getenv("PYTHONPATH");
    const std::string path =
        std::string(FEATHERDRIVE_PYTHON_DIR) + (old && *old ? ":" + std::string(old) : "");
    ::setenv("PYTHONPATH", path.c_str(), 1);
    std::vector<std::string> args = {python, "-m", module};
    int first = 1;  // the subcommand's name: featherdrive takes no options before it
    while (first < argc && argv[first] != std::string(name)) ++first;
    for (int i = first + 1; i < argc; ++i) args.emplace_back(argv[i]);
    std::vector<char*> ptrs;
    for (std::string& a : args) ptrs.push_back(a.data());
    ptrs.push_back(nullptr);
    std::cout.flush();
    ::execv(python.c_str(), ptrs.data());
    std::cerr << "featherdrive: cannot run " << python << " -m " << module << ": "
              << std::strerror(errno) << "\n";
    std::exit(1);
  });
  return cmd;
}
