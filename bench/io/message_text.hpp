// Text of values inside messages.
#pragma once
#include <cstdio>
#include <sstream>
#include <string>
#include <string_view>

namespace calbench {

// A number: at most 10 significant digits, so that a computed value shows without float noise
// (99.9, not 99.90000000000055) and a huge one in exponent form (1.7e+308, not the 309 digits
// std::to_string prints), while a time such as 1234.5678 s stays distinguishable.
inline std::string number_text(double v) {
  std::ostringstream s;
  s.precision(10);
  s << v;
  return s.str();
}

// A field as read from a file, to quote in a message: at most `max` bytes, printable ASCII as is,
// any other byte as \xNN (binary garbage must not reach the terminal as raw bytes).
inline std::string field_text(std::string_view f, std::size_t max = 40) {
  std::string out;
  for (std::size_t i = 0; i < f.size() && i < max; ++i) {
    const auto c = static_cast<unsigned char>(f[i]);
    if (c >= 0x20 && c < 0x7f) {
      out += static_cast<char>(c);
    } else {
      char b[5];
      std::snprintf(b, sizeof b, "\\x%02X", c);
      out += b;
    }
  }
  if (f.size() > max) out += "...";
  return out;
}

}  // namespace calbench
