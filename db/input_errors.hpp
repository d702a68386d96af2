// Input errors that concern an argument or a record rather than a file: "what: message".
#pragma once
#include <string>

#include "common/input_error.hpp"

namespace calbench::db {
inline InputError arg_error(const std::string& what, const std::string& message) {
  return InputError(what + ": " + message);
}
}  // namespace calbench::db
