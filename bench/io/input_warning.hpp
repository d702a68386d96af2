// Warnings about user input that the reader could handle but the user should know of (standard
// error, one line, naming the file and line like an InputError). A command that reads a file twice
// (a fit, then its QC) says each warning once.
#pragma once
#include <iostream>
#include <mutex>
#include <set>
#include <string>

namespace calbench {

inline void input_warning(const std::string& file, std::size_t line, const std::string& message) {
  std::string text = "calbench: warning: " + file;
  if (line > 0) text.append(":").append(std::to_string(line));
  text.append(": ").append(message);
  static std::mutex m;
  static std::set<std::string> said;
  std::lock_guard<std::mutex> lk(m);
  if (!said.insert(text).second) return;
  std::cerr << text << std::endl;
}

}  // namespace calbench
