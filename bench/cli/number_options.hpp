// Checks for the numbers of command-line options (every numeric option of every command uses one):
// decimal, finite, in range. NaN, inf, 1e999, hex and out-of-range values are bad input (exit 2),
// named by the option. CLI11's own PositiveNumber, NonNegativeNumber and Range let "nan" through,
// and its integer conversion reads "-1" into an unsigned option as 18446744073709551615 and "010"
// as 8: whole numbers are rewritten to plain decimal before CLI11 converts them.
#pragma once
#include <CLI/CLI.hpp>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <limits>
#include <optional>
#include <sstream>
#include <string>

#include "common/number_parse.hpp"

namespace calbench::cli {

namespace number_detail {
inline std::string show(double v) {
  std::ostringstream o;
  o << v;
  return o.str();
}
}  // namespace number_detail

// A finite decimal number x with lo <= x <= hi, or lo < x when lo_open.
inline CLI::Validator finite_number(double lo = -std::numeric_limits<double>::infinity(),
                                    double hi = std::numeric_limits<double>::infinity(), bool lo_open = false) {
  using number_detail::show;
  std::string want, desc;
  if (std::isfinite(lo) && std::isfinite(hi)) {
    want = "from " + show(lo) + " to " + show(hi);
    desc = "NUMBER in [" + show(lo) + ", " + show(hi) + "]";
  } else if (std::isfinite(lo)) {
    want = (lo_open ? "> " : ">= ") + show(lo);
    desc = "NUMBER" + std::string(lo_open ? ">" : ">=") + show(lo);
  } else {
    desc = "NUMBER";
  }
  return CLI::Validator(
      [lo, hi, lo_open, want](std::string& v) -> std::string {
        double x = 0;
        if (parse_finite_number(v, x) && (lo_open ? x > lo : x >= lo) && x <= hi)
          return {};
        return "expected a finite number" + (want.empty() ? std::string() : " " + want) + ", got '" + v + "'";
      },
      desc);
}
inline CLI::Validator finite_positive() { return finite_number(0, std::numeric_limits<double>::infinity(), true); }
inline CLI::Validator finite_non_negative() { return finite_number(0); }

// A whole number in decimal digits, lo <= n <= hi (for unsigned and signed integer options alike;
// signed ones give hi <= INT64_MAX).
inline CLI::Validator whole_number(std::uint64_t lo, std::uint64_t hi) {
  const bool open = hi == std::numeric_limits<std::uint64_t>::max() ||
                    hi == static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max());
  const std::string want = open ? ">= " + std::to_string(lo) : "from " + std::to_string(lo) + " to " + std::to_string(hi);
  return CLI::Validator(
      [lo, hi, want](std::string& v) -> std::string {
        std::uint64_t n = 0;
        const auto r = std::from_chars(v.data(), v.data() + v.size(), n, 10);
        if (!v.empty() && r.ec == std::errc() && r.ptr == v.data() + v.size() && n >= lo && n <= hi) {
          v = std::to_string(n);  // no leading zeros: CLI11 would read "010" as octal
          return {};
        }
        return "expected a whole number " + want + ", got '" + v + "'";
      },
      "INTEGER " + want);
}
inline CLI::Validator set_id() { return whole_number(1, std::numeric_limits<std::int64_t>::max()); }

// A UTC time in ISO 8601: YYYY-MM-DDTHH:MM:SS[.fff]Z (or +00:00), a real calendar date and time.
// Its seconds since 1970 (fraction included), or nullopt for anything else.
inline std::optional<double> iso8601_utc_seconds(const std::string& v) {
  int Y = 0, M = 0, D = 0, h = 0, m = 0, sec = 0, n = 0;
  const char* p = v.c_str();
  const bool shape = v.size() >= 20 && std::sscanf(p, "%4d-%2d-%2dT%2d:%2d:%2d%n", &Y, &M, &D, &h, &m, &sec, &n) == 6 &&
                     n == 19 && p[4] == '-' && p[7] == '-' && p[10] == 'T' && p[13] == ':' && p[16] == ':';
  std::size_t i = 19;
  if (shape && i < v.size() && v[i] == '.') {
    ++i;
    while (i < v.size() && v[i] >= '0' && v[i] <= '9') ++i;
  }
  const std::string zone = shape ? v.substr(std::min(i, v.size())) : "";
  static const int mdays[12] = {31, 29, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
  const bool leap = (Y % 4 == 0 && Y % 100 != 0) || Y % 400 == 0;
  const bool ok = shape && (zone == "Z" || zone == "+00:00") && Y >= 1970 && Y <= 9999 && M >= 1 && M <= 12 &&
                  D >= 1 && D <= mdays[M - 1] - (M == 2 && !leap ? 1 : 0) && h <= 23 && m <= 59 && sec <= 60;
  if (!ok) return std::nullopt;
  std::tm tm{};
  tm.tm_year = Y - 1900, tm.tm_mon = M - 1, tm.tm_mday = D, tm.tm_hour = h, tm.tm_min = m, tm.tm_sec = sec;
  return static_cast<double>(timegm(&tm)) + (i > 20 ? std::atof(v.substr(19, i - 19).c_str()) : 0.0);
}
inline CLI::Validator iso8601_utc() {
  return CLI::Validator(
      [](std::string& v) -> std::string {
        return iso8601_utc_seconds(v) ? std::string()
                                      : "expected a UTC time in ISO 8601 (e.g. 2026-11-27T08:30:00Z), got '" + v + "'";
      },
      "ISO8601-UTC");
}

// A name or path that must not be empty (an empty --device-class was taken as "not given").
inline CLI::Validator non_empty() {
  return CLI::Validator(
      [](std::string& v) -> std::string {
        return v.find_first_not_of(" \t") == std::string::npos ? "expected a value, got an empty one" : std::string();
      },
      "");
}

}  // namespace calbench::cli
