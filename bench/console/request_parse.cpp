#include "bench/console/request_parse.hpp"

#include "common/input_error.hpp"

namespace calbench::console {
namespace {

int hex(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

std::string decode(std::string_view s, const std::string& field) {
  std::string out;
  out.reserve(s.size());
  for (std::size_t i = 0; i < s.size(); ++i) {
    char c = s[i];
    if (c == '+') {
      c = ' ';
    } else if (c == '%') {
      const int h = i + 2 < s.size() ? hex(s[i + 1]) : -1;
      const int l = i + 2 < s.size() ? hex(s[i + 2]) : -1;
      if (h < 0 || l < 0) throw InputError("form field '" + field + "': malformed %-escape");
      c = static_cast<char>(h * 16 + l);
      i += 2;
    }
    const auto u = static_cast<unsigned char>(c);
    if ((u < 0x20 && c != '\t' && c != '\r' && c != '\n') || u == 0x7f)
      throw InputError("form field '" + field + "': contains control characters");
    out += c;
    if (out.size() > kMaxValueBytes)
      throw InputError("form field '" + field + "': longer than " + std::to_string(kMaxValueBytes) + " bytes");
  }
  return out;
}

}  // namespace

std::map<std::string, std::string> parse_form(std::string_view text) {
  std::map<std::string, std::string> out;
  std::size_t i = 0;
  while (i < text.size()) {
    std::size_t amp = text.find('&', i);
    if (amp == std::string_view::npos) amp = text.size();
    const std::string_view pair = text.substr(i, amp - i);
    i = amp + 1;
    if (pair.empty()) continue;
    const std::size_t eq = pair.find('=');
    const std::string name = decode(pair.substr(0, eq), "(name)");
    if (name.empty() || name.size() > 64) throw InputError("form: a field name is empty or longer than 64 bytes");
    const std::string value = eq == std::string_view::npos ? std::string() : decode(pair.substr(eq + 1), name);
    if (out.count(name)) throw InputError("form field '" + name + "': given twice");
    if (out.size() == kMaxFields) throw InputError("form: more than " + std::to_string(kMaxFields) + " fields");
    out.emplace(name, value);
  }
  return out;
}

std::map<std::string, std::string> parse_cookies(std::string_view header) {
  std::map<std::string, std::string> out;
  std::size_t i = 0;
  const auto trim = [](std::string_view s) {
    while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
    while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
    return s;
  };
  while (i < header.size() && out.size() < kMaxFields) {
    std::size_t semi = header.find(';', i);
    if (semi == std::string_view::npos) semi = header.size();
    const std::string_view pair = trim(header.substr(i, semi - i));
    i = semi + 1;
    const std::size_t eq = pair.find('=');
    if (eq == std::string_view::npos || eq == 0 || pair.size() - eq - 1 > kMaxValueBytes) continue;
    out.emplace(std::string(trim(pair.substr(0, eq))), std::string(trim(pair.substr(eq + 1))));
  }
  return out;
}

}  // namespace calbench::console
