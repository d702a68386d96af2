// Reading and writing JSON files; the typed getters for their values are in common/json_fields.hpp.
#pragma once
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "bench/io/input_warning.hpp"
#include "common/json_fields.hpp"  // the typed getters, for the many readers that include this header

namespace calbench {

// The input warnings this process said (a cut last line dropped, …) for a command's --json:
// [{file, line, message}], so that a script sees what the standard error said.
inline nlohmann::json input_warnings_json() {
  nlohmann::json a = nlohmann::json::array();
  for (const auto& w : input_warnings())
    a.push_back({{"file", w.file}, {"line", w.line > 0 ? nlohmann::json(w.line) : nlohmann::json()}, {"message", w.message}});
  return a;
}

// Parse a JSON file; syntax errors become InputError with the line and column.
nlohmann::json read_json_file(const std::filesystem::path& file);
// Atomic write: temporary file in the same folder, fsync, read back and compared with `text`
// (verify_written_text), rename.
// An output file can be written there: not a folder, its folder exists and takes new files (InputError
// naming it).
// Commands call it before long work so that a typo costs nothing.
void check_output_path(const std::filesystem::path& file);
// An output folder can be made or written there: not a file, and the nearest existing folder on its
// path takes new entries (InputError naming it otherwise).
void check_output_folder(const std::filesystem::path& dir);
void write_text_atomic(const std::filesystem::path& file, const std::string& text);

}  // namespace calbench
