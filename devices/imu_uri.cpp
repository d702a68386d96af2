#include "devices/imu_uri.hpp"

#include <cctype>
#include <charconv>
#include <sstream>
#include <stdexcept>

namespace calbench::devices {
namespace {

// A whole number, decimal or 0x… hexadecimal, nothing after it.
std::optional<unsigned long> whole(const std::string& s) {
  std::size_t used = 0;
  try {
    if (s.empty() || s[0] == '-' || s[0] == '+' || std::isspace(static_cast<unsigned char>(s[0]))) return std::nullopt;
    const unsigned long v = std::stoul(s, &used, 0);
    if (used == s.size()) return v;
  } catch (const std::exception&) {
  }
  return std::nullopt;
}

std::uint16_t u16(const std::string& uri, const std::string& what, const std::string& v) {
  const auto n = whole(v);
  if (!n) throw std::invalid_argument("'" + uri + "': " + what + " '" + v + "' is not an integer");
  if (*n > 0xFFFF) throw std::invalid_argument("'" + uri + "': " + what + " is 16-bit (0..65535)");
  return static_cast<std::uint16_t>(*n);
}

}  // namespace

int chip_selects(const std::string& kind) {
  if (kind == "ft232h") return 4;
  if (kind == "mcp2210") return 9;
  if (kind == "emu") return 1;
  return 0;
}

std::string ImuUri::text() const {
  if (emulated()) return "emu://" + serial;
  return kind + (serial.empty() ? "" : ":" + serial) + (cs ? "#cs" + std::to_string(cs) : "");
}

ImuUri parse_imu_uri(const std::string& uri) {
  ImuUri u;
  std::string rest = uri, query;
  const auto sep = rest.find("://");
  const auto colon = rest.find(':');
  u.kind = sep != std::string::npos ? rest.substr(0, sep) : rest.substr(0, std::min(colon, rest.find('#')));
  if (sep == std::string::npos && u.kind != "ft232h" && u.kind != "mcp2210")
    throw std::invalid_argument("'" + uri + "': expected ft232h[:USB-SERIAL][#csN] or mcp2210[:USB-SERIAL][#csN] "
                                "(a bridge; N: the unit's chip select), or emu://SERIAL (an emulated unit)");
  if (u.kind != "ft232h" && u.kind != "mcp2210" && u.kind != "emu")
    throw std::invalid_argument("'" + uri + "': unknown IMU URI scheme '" + u.kind + "' (emu, mcp2210, ft232h)");
  rest = sep != std::string::npos ? rest.substr(sep + 3) : colon == std::string::npos ? rest.substr(u.kind.size())
                                                                                        : rest.substr(colon + 1);
  if (const auto q = rest.find('?'); q != std::string::npos) {
    query = rest.substr(q + 1);
    rest = rest.substr(0, q);
    if (!u.emulated()) throw std::invalid_argument("'" + uri + "': options after '?' are for an emulated unit (emu://) only");
  }
  if (const auto hash = rest.find('#'); hash != std::string::npos) {
    const std::string c = rest.substr(hash + 1);
    rest = rest.substr(0, hash);
    int n = -1;
    const char* b = c.data() + 2;
    const char* e = c.data() + c.size();
    if (c.size() < 3 || c.compare(0, 2, "cs") != 0 || std::from_chars(b, e, n).ptr != e || n < 0)
      throw std::invalid_argument("'" + uri + "': after '#' expected a chip select csN (N = 0, 1, ...), not '#" + c + "'");
    u.cs = n;
  }
  u.serial = rest;
  if (u.emulated()) {
    u.emu_serial = u16(uri, "emulated SERIAL_NUM", u.serial);
    std::stringstream qs(query);
    for (std::string kv; std::getline(qs, kv, '&');) {
      const auto eq = kv.find('=');
      const std::string k = kv.substr(0, eq), v = eq == std::string::npos ? "" : kv.substr(eq + 1);
      if (k == "prod_id") u.emu_prod_id = u16(uri, "prod_id", v);
      else if (k == "flash_fails") u.emu_flash_fails = v == "1" || v == "true";
      else if (!k.empty()) throw std::invalid_argument("'" + uri + "': unknown emulator option '" + k + "' (prod_id, flash_fails)");
    }
  } else {
    for (const char ch : u.serial)
      if (!(std::isalnum(static_cast<unsigned char>(ch)) || ch == '-' || ch == '_' || ch == '.'))
        throw std::invalid_argument("'" + uri + "': a bridge serial number is letters, digits, '-', '_' or '.'");
  }
  if (u.cs >= chip_selects(u.kind))
    throw std::invalid_argument("'" + uri + "': " + u.kind + " has chip selects cs0 to cs" +
                                std::to_string(chip_selects(u.kind) - 1));
  return u;
}

}  // namespace calbench::devices
