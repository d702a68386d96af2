// Parse JSON text from a file; a syntax error becomes an InputError naming the file and the line.
// Header-only so that db/ (which does not link bench/) shares it with bench/io.
#pragma once
#include <algorithm>
#include <nlohmann/json.hpp>
#include <string>

#include "bench/io/input_error.hpp"

namespace calbench {

inline nlohmann::json parse_json_text(const std::string& text, const std::string& file) {
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
