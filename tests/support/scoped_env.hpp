// An environment variable set, or unset, for one scope.
#pragma once

#include <cstdlib>
#include <string>

namespace featherdrive::test {

class ScopedEnv {
 public:
  /// value nullptr: unset for the scope.
  ScopedEnv(const char* name, const char* value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old, had_ = true;
    if (value)
      ::setenv(name, value, 1);
    else
      ::unsetenv(name);
  }
  ScopedEnv(const char* name, const std::string& value) : ScopedEnv(name, value.c_str()) {}
  ScopedEnv(const ScopedEnv&) = delete;
  ScopedEnv& operator=(const ScopedEnv&) = delete;
  ~ScopedEnv() {
    if (had_)
      ::setenv(name_, old_.c_str(), 1);
    else
      ::unsetenv(name_);
  }

 private:
  const char* name_;
  std::string old_;
  bool had_ = false;
};

/// The lanes' automatic choice of width and one-lane blocks, whatever FEATHERDRIVE_SIMD the
/// suite runs under (a forced width steps every group at it: docs/simd_batch.md).
struct AutomaticSimd {
  ScopedEnv env{"FEATHERDRIVE_SIMD", nullptr};
};

}  // namespace featherdrive::test
