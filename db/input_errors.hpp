// Input errors that concern an argument or a record rather than a file: "what: message".
#pragma once
#include <string>

#include "common/input_error.hpp"

namespace calbench::db {
inline InputError arg_error(const std::string& what, const std::string& message) {
  return InputError(what + ": " + message);
}
// A text field the store keeps: bounded, on one line (tabs allowed), and not empty if required.
inline void check_text(const std::string& v, const char* field, bool required) {
  if (required && v.empty()) throw arg_error(field, "must not be empty");
  if (v.size() > 4096) throw arg_error(field, "longer than 4096 characters");
  for (unsigned char c : v)
    if (c < 0x20 && c != '\t') throw arg_error(field, "contains control characters");
}
}  // namespace calbench::db
