// Errors in user input (files, options). The CLI prints them and exits with status 2.
#pragma once
#include <stdexcept>
#include <string>

namespace calbench {

class InputError : public std::runtime_error {
 public:
  // file: path as given; line: 1-based, 0 when not applicable; field: column or key name, may be empty.
  InputError(std::string file, std::size_t line, std::string field, const std::string& message)
      : std::runtime_error(format(file, line, field, message)),
        file_(std::move(file)), line_(line), field_(std::move(field)), message_(message) {}
  explicit InputError(const std::string& message) : std::runtime_error(message), message_(message) {}

  const std::string& file() const { return file_; }
  std::size_t line() const { return line_; }
  const std::string& field() const { return field_; }
  const std::string& message() const { return message_; }  // without file, line and field

 private:
  static std::string format(const std::string& file, std::size_t line, const std::string& field,
                            const std::string& message) {
    // Built with append(): GCC 12 warns falsely (-Wrestrict) on chained operator+ here.
    std::string s;
    s.reserve(file.size() + field.size() + message.size() + 32);
    s.append(file);
    if (line > 0) s.append(":").append(std::to_string(line));
    s.append(": ");
    if (!field.empty()) s.append("'").append(field).append("': ");
    s.append(message);
    return s;
  }
  std::string file_;
  std::size_t line_ = 0;
  std::string field_;
  std::string message_;
};

}  // namespace calbench
