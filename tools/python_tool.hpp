// Subcommands written in Python (`featherdrive sweep`, `featherdrive fit`): the command becomes
// `python3 -m MODULE ARGS...` with the build's python folder on PYTHONPATH.
#pragma once

#include <CLI/CLI.hpp>

#include <string>

/// Adds subcommand `name` to `app`: once parsed it replaces this process (execv) by
/// $FEATHERDRIVE_PYTHON (default /usr/bin/python3) `-m module` with argv[2..] as given, so the
/// module parses its own options (--help included) and its exit code (2: bad input), output and
/// signals are the command's. Returns the subcommand.
CLI::App* add_python_tool(CLI::App& app, int argc, char** argv, const std::string& name,
                          const std::string& module, const std::string& description);
