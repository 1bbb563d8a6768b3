// Errors of the io stage: bad input files. The message names the file, the element or key path
// and the value, so a person can fix the file from the message alone.
#pragma once

#include <stdexcept>

namespace featherdrive {

class InputError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

}  // namespace featherdrive
