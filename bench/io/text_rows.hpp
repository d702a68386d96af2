// Whitespace- (or comma-) separated numeric text rows, as peer tools write them (KF-GINS, IMU-TK):
// '#' and '%' start comments, blank lines are skipped; every field must be a finite number; a last
// line without its line end is dropped with a warning (cut while being written).
// Errors name the file, line and column.
#pragma once
#include <algorithm>
#include <cmath>
#include <fstream>
#include <string>
#include <string_view>
#include <vector>

#include "bench/io/input_warning.hpp"
#include "bench/io/message_text.hpp"
#include "common/input_error.hpp"
#include "common/number_parse.hpp"
#include "bench/io/plausible.hpp"

namespace calbench {

class TextRows {
 public:
  // Rows of min_cols to max_cols numbers (max_cols 0: no upper bound).
  TextRows(std::string path, std::size_t min_cols, std::size_t max_cols = 0)
      : path_(std::move(path)), in_(path_), min_(min_cols), max_(max_cols) {
    if (!in_) throw InputError(path_, 0, "", "cannot open file");
  }
  // True once a last line without its line end was dropped.
  bool truncated() const { return truncated_; }
  bool next(std::vector<double>& v) {
    std::string s;
    while (std::getline(in_, s)) {
      ++line_;
      const auto p = s.find_first_not_of(" \t\r");
      if (p == std::string::npos || s[p] == '#' || s[p] == '%') continue;
      // A last line without its line end was cut while being written (as bench/io/csv.cpp): its
      // last number may be cut too ("12.3" of "12.345"). Dropped with a warning, never used.
      if (in_.eof()) {
        input_warning(path_, line_, "last line has no line end: treated as truncated and not used ('" +
                                        field_text(std::string_view(s).substr(p), 40) +
                                        "'); the rows before it are used: if the file was cut short by a copy, copy it again");
        truncated_ = true;
        return false;
      }
      v.clear();
      const char* c = s.data();
      const char* e = c + s.size();
      while (c < e) {
        while (c < e && (*c == ' ' || *c == '\t' || *c == '\r' || *c == ',')) ++c;
        if (c >= e) break;
        double x = 0;
        const char* start = c;
        const char* end = parse_number(c, e, x);
        if (!end || (end < e && !(*end == ' ' || *end == '\t' || *end == '\r' || *end == ',')))
          throw InputError(path_, line_, "column " + std::to_string(v.size() + 1),
                           "not a number: '" + field_text(std::string_view(start, static_cast<std::size_t>(e - start)), 20) + "'");
        if (!std::isfinite(x)) throw InputError(path_, line_, "column " + std::to_string(v.size() + 1), "NaN or infinity");
        v.push_back(x);
        c = end;
      }
      if (v.size() < min_)
        throw InputError(path_, line_, "", "expected at least " + std::to_string(min_) + " columns, found " + std::to_string(v.size()));
      if (max_ > 0 && v.size() > max_)
        throw InputError(path_, line_, "", "expected " + (max_ == min_ ? std::to_string(max_) : "at most " + std::to_string(max_)) +
                                               " columns, found " + std::to_string(v.size()));
      return true;
    }
    return false;
  }
  std::size_t line() const { return line_; }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::ifstream in_;
  std::size_t min_, max_;
  std::size_t line_ = 0;
  bool truncated_ = false;
};

// Range checks before a value reaches the recording (a latitude of 1e308 is a number, not a place).
// Reader: TextRows or CsvReader (anything with path() and line()); col is 0-based.
template <class Reader>
void check_range(const Reader& r, std::size_t col, double v, double lo, double hi, const char* what) {
  if (!(v >= lo && v <= hi))
    throw InputError(r.path(), r.line(), "column " + std::to_string(col + 1),
                     std::string(what) + " " + number_text(v) + " outside [" + number_text(lo) + ", " + number_text(hi) + "]");
}

template <class Reader>
void check_time(const Reader& r, double t, double& last, bool& first,
                double max_gap = plausible::kMaxImuInterval_s) {
  if (!(std::abs(t) <= plausible::kMaxAbsTime_s))  // the bound every reader of the recording applies
    throw InputError(r.path(), r.line(), "time",
                     "time " + number_text(t) + " s is not plausible (at most " + number_text(plausible::kMaxAbsTime_s) + " s)");
  if (!first && !(t > last)) throw InputError(r.path(), r.line(), "time", "time does not increase");
  if (!first && !(t - last <= max_gap))  // IMU rows: the recording reader's bound (recording.cpp)
    throw InputError(r.path(), r.line(), "time",
                     number_text(t - last) + " s after the row before: not an IMU interval (at most " +
                         number_text(max_gap) + " s; split the recording at the gap)");
  first = false;
  last = t;
}

// The nominal rate of a text file's rows: 1 / the median interval between time stamps.
inline double rate_from_intervals(std::vector<double>& dts) {
  std::nth_element(dts.begin(), dts.begin() + static_cast<long>(dts.size() / 2), dts.end());
  return 1.0 / dts[dts.size() / 2];
}

}  // namespace calbench
