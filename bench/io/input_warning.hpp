// Warnings about user input that the reader could handle but the user should know of (standard
// error, one line, naming the file and line like an InputError).
#pragma once
#include <iostream>
#include <string>

namespace calbench {

inline void input_warning(const std::string& file, std::size_t line, const std::string& message) {
  std::cerr << "calbench: warning: " << file;
  if (line > 0) std::cerr << ':' << line;
  std::cerr << ": " << message << std::endl;
}

}  // namespace calbench
