// Warnings about user input that the reader could handle but the user should know of (standard
// error, one line, naming the file and line like an InputError). A command that reads a file twice
// (a fit, then its QC) says each warning once. A command's --json gives them too (input_warnings()),
// so that a script sees, e.g., that a cut last line was not used.
#pragma once
#include <iostream>
#include <mutex>
#include <set>
#include <string>
#include <vector>

namespace calbench {

struct InputWarning {
  std::string file;
  std::size_t line = 0;
  std::string message;
};

namespace detail {
struct InputWarnings {
  std::mutex m;
  std::set<std::string> said;
  std::vector<InputWarning> in_order;
};
inline InputWarnings& input_warnings_state() {
  static InputWarnings w;
  return w;
}
}  // namespace detail

inline void input_warning(const std::string& file, std::size_t line, const std::string& message) {
  std::string text = "calbench: warning: " + file;
  if (line > 0) text.append(":").append(std::to_string(line));
  text.append(": ").append(message);
  auto& w = detail::input_warnings_state();
  std::lock_guard<std::mutex> lk(w.m);
  if (!w.said.insert(text).second) return;
  w.in_order.push_back({file, line, message});
  std::cerr << text << std::endl;
}

// Every warning said so far by this process, in order.
inline std::vector<InputWarning> input_warnings() {
  auto& w = detail::input_warnings_state();
  std::lock_guard<std::mutex> lk(w.m);
  return w.in_order;
}

}  // namespace calbench
