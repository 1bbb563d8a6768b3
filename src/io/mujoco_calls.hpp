// featherdrive_io's calls into MuJoCo's compiler. MuJoCo 2.2.2 reports warnings and errors through
// two process-wide hooks (mju_user_warning, mju_user_error), so every load goes through here: the
// hooks are installed once; a warning goes to the collector of the thread that caused it (or is
// dropped: a step's warnings are read from mjData's counters); an error, whose default handler
// prints, waits for Enter and exits the process, throws MujocoError instead. Loads take one
// lock, so threads that load models or run MuJoCo side by side never see each other's warnings.
#pragma once

#include <mujoco/mujoco.h>

#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace featherdrive::mujoco_calls {

/// What a MuJoCo fatal error (mju_error) becomes: "MuJoCo: <its message on one line>".
struct MujocoError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct ModelDeleter {
  void operator()(mjModel* m) const { mj_deleteModel(m); }
};
using ModelPtr = std::unique_ptr<mjModel, ModelDeleter>;
struct DataDeleter {
  void operator()(mjData* d) const { mj_deleteData(d); }
};
using DataPtr = std::unique_ptr<mjData, DataDeleter>;

/// MuJoCo's multi-line messages as one line ("Error: ...; Element 'body', line 3").
std::string one_line(const std::string& text);

/// Installs both hooks (once; later calls do nothing). Call before any MuJoCo function.
void route_warnings();

/// mj_loadXML(filename, vfs) under the load lock. Null with `error` set (one line) when MuJoCo
/// refuses the file; its warnings, "MuJoCo: ..." one line each, are appended to `warnings`. A
/// file on disk (vfs null) is checked first (mjcf_document::check: InputError naming it), and
/// the files it reads are appended to `files` when given; text in a VFS is the caller's to check.
ModelPtr load_xml(const char* filename, const mjVFS* vfs, std::string& error,
                  std::vector<std::string>& warnings,
                  std::vector<std::filesystem::path>* files = nullptr);

}  // namespace featherdrive::mujoco_calls
