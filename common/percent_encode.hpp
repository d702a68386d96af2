// RFC 3986 percent-encoding: every byte outside the unreserved set (letters, digits, '-', '.', '_',
// '~') and the characters of `keep` as %XX (upper-case hex). file:// URIs keep '/'
// (bench/io/recording_location.cpp); a libpq URI parameter keeps nothing (bench/console/server.cpp).
#pragma once
#include <string>
#include <string_view>

namespace calbench {

inline std::string percent_encode(std::string_view s, std::string_view keep = {}) {
  static const char* hex = "0123456789ABCDEF";
  std::string out;
  for (const unsigned char c : s) {
    const bool unreserved = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '-' ||
                            c == '.' || c == '_' || c == '~';
    if (unreserved || keep.find(static_cast<char>(c)) != std::string_view::npos) {
      out += static_cast<char>(c);
    } else {
      out += '%';
      out += hex[c >> 4];
      out += hex[c & 15];
    }
  }
  return out;
}

}  // namespace calbench
