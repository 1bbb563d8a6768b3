// The source tree's folders, for tests compiled with FEATHERDRIVE_SOURCE_DIR.
#pragma once

#include <string>

namespace featherdrive::test {

inline const std::string kSourceDir = FEATHERDRIVE_SOURCE_DIR;
inline const std::string kExamples = kSourceDir + "/examples/";

}  // namespace featherdrive::test
