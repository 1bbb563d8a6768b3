#include "mujoco_calls.hpp"

#include <array>
#include <mutex>

#include "mjcf_document.hpp"

namespace featherdrive::mujoco_calls {
namespace {

thread_local std::vector<std::string>* collector = nullptr;

void route(const char* text) {
  if (collector) collector->push_back("MuJoCo: " + one_line(text));
}

// MuJoCo's own compiler throws from this hook (it swaps in its handler while it compiles), so an
// exception through its frames is a path it takes itself.
[[noreturn]] void raise(const char* text) { throw MujocoError("MuJoCo: " + one_line(text)); }

}  // namespace

std::string one_line(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (c == '\n' || c == '\r') {
      if (!out.empty() && out.back() != ' ') out += out.back() == ':' ? " " : "; ";
    } else {
      out += c;
    }
  }
  while (!out.empty() && (out.back() == ' ' || out.back() == ';')) out.pop_back();
  return out;
}

void route_warnings() {
  static std::once_flag installed;
  std::call_once(installed, [] {
    mju_user_warning = route;
    mju_user_error = raise;
  });
}

ModelPtr load_xml(const char* filename, const mjVFS* vfs, std::string& error,
                  std::vector<std::string>& warnings, std::vector<std::filesystem::path>* files) {
  route_warnings();
  if (!vfs) {
    std::vector<std::filesystem::path> read = mjcf_document::check(filename, nullptr, filename);
    if (files) files->insert(files->end(), read.begin(), read.end());
  }
  static std::mutex loading;
  const std::lock_guard<std::mutex> lock(loading);
  std::array<char, 1024> message{};
  struct Collect {  // reset on every way out, an exception from the error hook included
    explicit Collect(std::vector<std::string>& w) { collector = &w; }
    ~Collect() { collector = nullptr; }
  } collect(warnings);
  ModelPtr m(mj_loadXML(filename, vfs, message.data(), static_cast<int>(message.size())));
  if (!m)
    error = one_line(message[0] ? message.data() : "unknown error");
  else if (message[0])
    warnings.push_back("MuJoCo: " + one_line(message.data()));
  return m;
}

}  // namespace featherdrive::mujoco_calls
