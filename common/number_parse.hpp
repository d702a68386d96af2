// The one reader of a decimal number in calbench (CSV tables, KF-GINS text files, numeric options,
// --inject values, threshold keys):
// at most one sign ('+' or '-'), then digits with an optional '.' and exponent, rounded exactly
// (fast_float, Debian libfast-float-dev: as strtod in the C locale). "+-1", "-+1", "++1" and "--1"
// are not numbers (a mutation run found "+-1" read as −1, issue 35). "inf" and "nan" are parsed
// (as strtod does) so that the caller can name them; the caller refuses non-finite values.
#pragma once
#include <cmath>
#include <string_view>
#include <system_error>

#include <fast_float/fast_float.h>

namespace calbench {

// Parses a number at the start of [first, last) into v. Returns the end of the number, or nullptr
// if the text does not start with one (v is then unspecified).
inline const char* parse_number(const char* first, const char* last, double& v) {
  const char* p = first;
  if (p < last && *p == '+') {  // fast_float takes '-' only; one '+' is allowed, not before another sign
    ++p;
    if (p == last || *p == '+' || *p == '-') return nullptr;
  }
  const auto r = fast_float::from_chars(p, last, v);
  if (r.ec != std::errc() || r.ptr == p) return nullptr;
  return r.ptr;
}

// The whole of `text` one finite number (no blanks, nothing after it).
inline bool parse_finite_number(std::string_view text, double& v) {
  const char* e = text.data() + text.size();
  const char* end = parse_number(text.data(), e, v);
  return end == e && !text.empty() && std::isfinite(v);
}

}  // namespace calbench
