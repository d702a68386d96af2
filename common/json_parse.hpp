// Parse JSON text from a file; a syntax error becomes an InputError naming the file and the line.
// Header-only, in the common base below calibration, devices, db and bench (all of them use it).
#pragma once
#include <algorithm>
#include <nlohmann/json.hpp>
#include <string>

#include "common/input_error.hpp"

namespace calbench {

// Deepest nesting of arrays and objects any input may have. Real files need a handful of levels;
// the limit keeps the recursive copies and dumps of nlohmann::json far from the stack's end (a value
// nested 200,000 deep crashed them).
inline constexpr int kMaxJsonDepth = 64;

// Throws an InputError naming the line where the nesting first exceeds kMaxJsonDepth. Brackets
// inside strings do not count.
inline void check_json_depth(const std::string& text, const std::string& file) {
  int depth = 0;
  std::size_t line = 1;
  bool in_string = false, escape = false;
  for (const char c : text) {
    if (c == '\n') ++line;
    if (in_string) {
      if (escape) escape = false;
      else if (c == '\\') escape = true;
      else if (c == '"') in_string = false;
      continue;
    }
    if (c == '"') in_string = true;
    else if (c == '[' || c == '{') {
      if (++depth > kMaxJsonDepth)
        throw InputError(file, line, "", "JSON nested deeper than " + std::to_string(kMaxJsonDepth) + " levels");
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
}

inline nlohmann::json parse_json_text(const std::string& text, const std::string& file) {
  check_json_depth(text, file);
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    const std::size_t upto = std::min<std::size_t>(e.byte, text.size());
    const std::size_t line = 1 + static_cast<std::size_t>(std::count(text.begin(), text.begin() + upto, '\n'));
    throw InputError(file, line, "", std::string("invalid JSON (truncated or malformed): ") + e.what());
  } catch (const nlohmann::json::exception& e) {  // e.g. a number too large for a double
    throw InputError(file, 0, "", std::string("invalid JSON: ") + e.what());
  }
}

}  // namespace calbench
