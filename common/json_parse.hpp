// Parse JSON text from a file; a syntax error, a duplicate key or a number out of range becomes an
// InputError naming the file and the line.
// Header-only, in the common base below calibration, devices, db and bench (all of them use it).
#pragma once
#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <set>
#include <sstream>
#include <vector>
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

namespace json_detail {
// Where the parser is (object keys and array indices), and the keys each open object has had: a
// key seen twice in one object is refused (nlohmann keeps the last silently, so a second
// "gyro": 1000 would loosen a limit the first set).
class KeyTracker {
 public:
  explicit KeyTracker(std::string file) : file_(std::move(file)) {}
  bool operator()(int, nlohmann::json::parse_event_t event, nlohmann::json& parsed) {
    using E = nlohmann::json::parse_event_t;
    switch (event) {
      case E::object_start: stack_.push_back({true, {}, {}, 0}); break;
      case E::array_start: stack_.push_back({false, {}, {}, 0}); break;
      case E::key: {
        Frame& f = stack_.back();
        f.key = parsed.get<std::string>();
        if (!f.keys.insert(f.key).second)
          throw InputError(file_, 0, path(), "duplicate key '" + f.key + "' in one JSON object (each key once)");
        break;
      }
      case E::object_end:
      case E::array_end:
        stack_.pop_back();
        element_done();
        break;
      case E::value: element_done(); break;
    }
    return true;
  }
  // "bench.max_chi2_dof.gyro", "runs[2].rms": the value being parsed.
  std::string path() const {
    std::string p;
    for (const Frame& f : stack_) {  // append(): GCC 12 warns falsely (-Wrestrict) on chained operator+
      if (f.object && !f.key.empty()) p.append(p.empty() ? "" : ".").append(f.key);
      if (!f.object) p.append("[").append(std::to_string(f.index)).append("]");
    }
    return p;
  }

 private:
  struct Frame {
    bool object;
    std::set<std::string> keys;
    std::string key;
    std::size_t index;
  };
  void element_done() {
    if (!stack_.empty() && !stack_.back().object) ++stack_.back().index;
  }
  std::string file_;
  std::vector<Frame> stack_;
};
}  // namespace json_detail

// Parses `text` (named `file` in messages): syntax errors, a key twice in one object, and numbers
// beyond a double become InputError with the line and, where known, the key path.
inline nlohmann::json parse_json_text(const std::string& text, const std::string& file) {
  check_json_depth(text, file);
  json_detail::KeyTracker tracker(file);
  try {
    return nlohmann::json::parse(text, std::ref(tracker));
  } catch (const nlohmann::json::parse_error& e) {
    const std::size_t upto = std::min<std::size_t>(e.byte, text.size());
    const std::size_t line = 1 + static_cast<std::size_t>(std::count(text.begin(), text.begin() + upto, '\n'));
    throw InputError(file, line, "", std::string("invalid JSON (truncated or malformed): ") + e.what());
  } catch (const nlohmann::json::out_of_range& e) {  // a number too large for a double: 1e999
    // The parser names the token but not its place: the line of its first occurrence.
    const std::string w = e.what();
    const std::size_t a = w.find('\''), b = w.rfind('\'');
    std::size_t line = 0;
    if (a != std::string::npos && b > a) {
      const std::size_t at = text.find(w.substr(a + 1, b - a - 1));
      if (at != std::string::npos) line = 1 + static_cast<std::size_t>(std::count(text.begin(), text.begin() + at, '\n'));
    }
    throw InputError(file, line, tracker.path(),
                     "number out of range (beyond a double)" + (b > a && a != std::string::npos ? ": " + w.substr(a, b - a + 1) : std::string()));
  } catch (const nlohmann::json::exception& e) {
    throw InputError(file, 0, tracker.path(), std::string("invalid JSON: ") + e.what());
  }
}

// The text of a JSON input file: InputError when it is a folder, cannot be opened or is empty.
inline std::string read_json_text(const std::filesystem::path& file) {
  if (std::filesystem::is_directory(file)) throw InputError(file.string(), 0, "", "is a folder, not a JSON file");
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file.string(), 0, "", std::string("cannot open: ") + std::strerror(errno));
  std::stringstream ss;
  ss << in.rdbuf();
  std::string text = ss.str();
  if (text.find_first_not_of(" \t\r\n") == std::string::npos) throw InputError(file.string(), 1, "", "empty file");
  return text;
}

}  // namespace calbench
