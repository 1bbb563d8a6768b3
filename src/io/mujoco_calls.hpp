// featherdrive_io's calls into MuJoCo's compiler. MuJoCo 2.2.2 reports warnings through one
// process-wide hook (mju_user_warning), so every load goes through here: the hook is installed
// once and sends a warning to the collector of the thread that caused it (or drops it: a step's
// warnings are read from mjData's counters), and loads take one lock, so threads that load
// models or run MuJoCo side by side never see each other's warnings.
#pragma once

#include <mujoco/mujoco.h>

#include <memory>
#include <string>
#include <vector>

namespace featherdrive::mujoco_calls {

struct ModelDeleter {
  void operator()(mjModel* m) const { mj_deleteModel(m); }
};
using ModelPtr = std::unique_ptr<mjModel, ModelDeleter>;

/// MuJoCo's multi-line messages as one line ("Error: ...; Element 'body', line 3").
std::string one_line(const std::string& text);

/// Installs the routing hook (once; later calls do nothing).
void route_warnings();

/// mj_loadXML(filename, vfs) under the load lock. Null with `error` set (one line) when MuJoCo
/// refuses the file; its warnings, "MuJoCo: ..." one line each, are appended to `warnings`.
ModelPtr load_xml(const char* filename, const mjVFS* vfs, std::string& error,
                  std::vector<std::string>& warnings);

}  // namespace featherdrive::mujoco_calls
