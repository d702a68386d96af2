#include "bench/io/toml_text.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

#include "common/input_error.hpp"
#include "common/utf8.hpp"

namespace calbench {
namespace {
using utf8::code_point_name;
// Unicode white space and separators other than ASCII space (category Zs, Zl, Zp, NEL, and the BOM).
bool unicode_space(unsigned cp) { return utf8::space_like(cp) || cp == 0x85 || cp == 0x2028 || cp == 0x2029 || cp == 0xFEFF; }
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
    unsigned cp = 0;
    const std::size_t len = utf8::decode(text, i, cp);
    if (len == 0) throw InputError(file, line, "", "not valid UTF-8 (byte " + std::to_string(i + 1) + ")");
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
