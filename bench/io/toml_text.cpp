#include "bench/io/toml_text.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

#include "common/input_error.hpp"

namespace calbench {
namespace {
std::string code_point_name(unsigned cp) {
  char b[16];
  std::snprintf(b, sizeof b, "U+%04X", cp);
  return b;
}

// Unicode white space and separators other than ASCII space (category Zs, Zl, Zp, and NEL).
bool unicode_space(unsigned cp) {
  return cp == 0x85 || cp == 0xA0 || cp == 0x1680 || (cp >= 0x2000 && cp <= 0x200A) || cp == 0x2028 || cp == 0x2029 ||
         cp == 0x202F || cp == 0x205F || cp == 0x3000 || cp == 0xFEFF;
}
}  // namespace

void check_toml_text(const std::string& text, const std::string& file) {
  std::size_t line = 1;
  const auto* s = reinterpret_cast<const unsigned char*>(text.data());
  const std::size_t n = text.size();
  std::size_t i = 0;
  if (n >= 3 && s[0] == 0xEF && s[1] == 0xBB && s[2] == 0xBF) i = 3;  // a leading byte-order mark is allowed
  for (; i < n; ++i) {
    const unsigned c = s[i];
    if (c == '\n') {
      ++line;
      continue;
    }
    if (c < 0x80) {
      if ((c < 0x20 && c != '\t' && c != '\r') || c == 0x7F)
        throw InputError(file, line, "", "control character " + code_point_name(c) + " is not allowed in a TOML file");
      continue;
    }
    // UTF-8 sequence: length from the lead byte, continuation bytes 10xxxxxx, shortest form.
    std::size_t len = c >= 0xF0 && c <= 0xF4 ? 4 : c >= 0xE0 ? 3 : c >= 0xC2 && c <= 0xDF ? 2 : 0;
    if (c >= 0xF5) len = 0;
    if (len == 0 || i + len > n) throw InputError(file, line, "", "not valid UTF-8 (byte " + std::to_string(i + 1) + ")");
    unsigned cp = len == 2 ? (c & 0x1F) : len == 3 ? (c & 0x0F) : (c & 0x07);
    for (std::size_t k = 1; k < len; ++k) {
      if ((s[i + k] & 0xC0) != 0x80) throw InputError(file, line, "", "not valid UTF-8 (byte " + std::to_string(i + k + 1) + ")");
      cp = (cp << 6) | (s[i + k] & 0x3F);
    }
    if ((len == 3 && cp < 0x800) || (len == 4 && (cp < 0x10000 || cp > 0x10FFFF)) || (cp >= 0xD800 && cp <= 0xDFFF))
      throw InputError(file, line, "", "not valid UTF-8 (byte " + std::to_string(i + 1) + ")");
    if (unicode_space(cp))
      throw InputError(file, line, "", "the Unicode space " + code_point_name(cp) + " is not allowed; use an ASCII space");
    i += len - 1;
  }
}

std::string read_toml_text(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file.string(), 0, "", std::string("cannot open: ") + std::strerror(errno));
  std::ostringstream ss;
  ss << in.rdbuf();
  std::string text = ss.str();
  check_toml_text(text, file.string());
  return text;
}

namespace {
// Text already checked by check_toml_text.
toml::table parse_checked(const std::string& text, const std::string& file) {
  try {
    return toml::parse(text, file);
  } catch (const toml::parse_error& e) {
    throw InputError(file, e.source().begin.line, "", std::string("invalid TOML: ") + std::string(e.description()));
  }
}
}  // namespace

toml::table parse_toml_text(const std::string& text, const std::string& file) {
  check_toml_text(text, file);
  return parse_checked(text, file);
}

toml::table parse_toml_file(const std::filesystem::path& file) { return parse_checked(read_toml_text(file), file.string()); }

}  // namespace calbench
