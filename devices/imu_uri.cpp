#include "devices/imu_uri.hpp"

#include <cctype>
#include <charconv>
#include <stdexcept>

namespace calbench::devices {

int chip_selects(const std::string& kind) {
  if (kind == "ft232h") return 4;
  if (kind == "mcp2210") return 9;
  return 0;
}

std::string ImuUri::text() const { return kind + (serial.empty() ? "" : ":" + serial) + (cs ? "#cs" + std::to_string(cs) : ""); }

ImuUri parse_imu_uri(const std::string& uri) {
  ImuUri u;
  std::string rest = uri;
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
  const auto colon = rest.find(':');
  u.kind = rest.substr(0, colon);
  if (colon != std::string::npos) u.serial = rest.substr(colon + 1);
  if (u.serial.rfind("//", 0) == 0) u.serial = u.serial.substr(2);
  if (u.kind != "ft232h" && u.kind != "mcp2210")
    throw std::invalid_argument("'" + uri + "': expected ft232h[:SERIAL][#csN] or mcp2210[:SERIAL][#csN]");
  for (const char ch : u.serial)
    if (!(std::isalnum(static_cast<unsigned char>(ch)) || ch == '-' || ch == '_' || ch == '.'))
      throw std::invalid_argument("'" + uri + "': a bridge serial number is letters, digits, '-', '_' or '.'");
  if (u.cs >= chip_selects(u.kind))
    throw std::invalid_argument("'" + uri + "': " + u.kind + " has chip selects cs0 to cs" +
                                std::to_string(chip_selects(u.kind) - 1));
  return u;
}

}  // namespace calbench::devices
