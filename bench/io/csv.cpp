#include "bench/io/csv.hpp"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>


#include "common/input_error.hpp"
#include "bench/io/message_text.hpp"
#include "bench/io/input_warning.hpp"
#include "common/number_parse.hpp"
#include "bench/io/plausible.hpp"

namespace calbench {
namespace {
// Read buffer of CsvReader, flush threshold of CsvWriter. Sanitizer and fuzz builds make it small
// (CMakeLists.txt): fuzz inputs then cross buffer refills, and an execution does not allocate and
// clear a megabyte per file.
#ifndef CALBENCH_CSV_BUFFER_BYTES
#define CALBENCH_CSV_BUFFER_BYTES (1 << 20)
#endif
constexpr std::size_t kBufSize = CALBENCH_CSV_BUFFER_BYTES;

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}
}  // namespace

CsvReader::CsvReader(std::string path, bool digest, char delim) : delim_(delim), path_(std::move(path)), buf_(kBufSize) {
  if (!(delim == 0 || delim == ',' || delim == ';' || delim == ' '))
    throw InputError(path_, 0, "", "delimiter must be ',', ';' or blanks");
  file_.reset(std::fopen(path_.c_str(), "rb"));
  if (!file_) throw InputError(path_, 0, "", std::string("cannot open: ") + std::strerror(errno));
  if (digest) digest_ = std::make_unique<Sha256>();
  std::string_view line;
  while (read_line(line)) {
    const auto t = trim(line);
    if (t.empty()) continue;
    if (t.front() == '#') {
      std::string_view c = t.substr(1);
      if (!c.empty() && c.front() == ' ') c.remove_prefix(1);
      comments_.emplace_back(c);
      continue;
    }
    if (delim_ == 0) {
      const auto n = [&](char c) { return std::count(t.begin(), t.end(), c); };
      delim_ = n(';') > n(',') ? ';' : n(',') > 0 ? ',' : ' ';
    }
    const char* const e = t.data() + t.size();
    for (const char* p = t.data();;) {
      const char* c = field_end(p, e);
      header_.emplace_back(trim(std::string_view(p, static_cast<std::size_t>(c - p))));
      if (c == e) break;
      p = c + 1;
      if (delim_ == ' ')
        while (p < e && (*p == ' ' || *p == '\t')) ++p;
    }
    slot_of_field_.assign(header_.size(), -1);
    return;
  }
  fail("", "empty file: no header line");
}

CsvReader::~CsvReader() = default;

const char* CsvReader::field_end(const char* p, const char* e) const {
  if (delim_ != ' ') {
    const void* c = std::memchr(p, delim_, static_cast<std::size_t>(e - p));
    return c ? static_cast<const char*>(c) : e;
  }
  while (p < e && *p != ' ' && *p != '\t') ++p;
  return p;
}

std::optional<std::string> CsvReader::sha256() const {
  if (sha256_.empty()) return std::nullopt;
  return sha256_;
}

bool CsvReader::has(std::string_view name) const {
  for (const auto& h : header_)
    if (h == name) return true;
  return false;
}

int CsvReader::optional(std::string_view name) {
  for (std::size_t i = 0; i < header_.size(); ++i) {
    if (header_[i] == name) {
      if (slot_of_field_[i] >= 0) return slot_of_field_[i];
      slot_of_field_[i] = static_cast<int>(slot_names_.size());
      slot_names_.emplace_back(name);
      values_.push_back(0.0);
      max_field_ = std::max(max_field_, i + 1);
      return slot_of_field_[i];
    }
  }
  return -1;
}

int CsvReader::require(std::string_view name) {
  const int s = optional(name);
  if (s < 0) {
    // Columns are required before the first row is read: the line read last is the header (after
    // any '#' comment lines, so not always line 1).
    const std::size_t header_line = rows_ == 0 && line_no_ > 0 ? line_no_ : 1;
    line_no_ = 0;
    throw InputError(path_, header_line, std::string(name), "missing required column");
  }
  return s;
}

void CsvReader::fail(const std::string& column, const std::string& msg) const {
  throw InputError(path_, line_no_, column, msg);
}

void CsvReader::refill() {
  beg_ = end_ = 0;
  end_ = std::fread(buf_.data(), 1, buf_.size(), file_.get());
  if (end_ < buf_.size()) {
    if (std::ferror(file_.get())) fail("", std::string("read error: ") + std::strerror(errno));
    eof_ = true;
  }
  if (digest_) {
    digest_->update(buf_.data(), end_);
    if (eof_) {  // the whole file has passed: the digest is complete
      sha256_ = digest_->hex();
      digest_.reset();
    }
  }
}

bool CsvReader::read_line(std::string_view& out) {
  // Lines are returned as views into buf_ or carry_ (when a line spans a buffer refill).
  carry_.clear();
  while (true) {
    const char* b = buf_.data() + beg_;
    const void* nl = std::memchr(b, '\n', end_ - beg_);
    if (nl) {
      const std::size_t len = static_cast<const char*>(nl) - b;
      ++line_no_;
      if (carry_.empty()) {
        out = std::string_view(b, len);
      } else {
        carry_.append(b, len);
        out = carry_;
      }
      beg_ += len + 1;
      return true;
    }
    carry_.append(b, end_ - beg_);
    beg_ = end_ = 0;
    if (eof_) break;
    refill();
  }
  // A last line without its line end was cut while being written (an interrupted logger, a copy
  // that stopped): its last field may be a cut number. It is dropped, with a warning, never used.
  if (!trim(carry_).empty()) {
    const std::string_view t = trim(carry_);
    if (t.front() != '#' && refuse_cut_)
      throw InputError(path_, line_no_ + 1, "",
                       "last line has no line end: the file was cut short (" + std::to_string(t.size()) +
                           " characters of a row); a copy must not pass it on as complete: remove the partial last line (or copy"
                           " the file again), or let fit/diagnose read it as it is (they drop that line with a"
                           " warning)");
    if (t.front() != '#')
      input_warning(path_, line_no_ + 1,
                    "last line has no line end: treated as truncated and not used ('" +
                        std::string(t.substr(0, std::min<std::size_t>(t.size(), 40))) +
                        "'); the rows before it are used: if the file was cut short by a copy, copy it again");
  }
  carry_.clear();
  return false;
}

// One data row (trimmed, not a comment) into values_: each selected field parsed where it lies (no
// copies, no search for its end first); an unselected field is skipped to its comma.
bool CsvReader::parse_row(std::string_view t) {
  const char* p = t.data();
  const char* const e = t.data() + t.size();
  std::size_t field = 0;
  while (field < max_field_) {
    const int slot = slot_of_field_[field];
    if (slot < 0) {
      const char* c = field_end(p, e);
      ++field;
      if (c == e) break;
      p = c + 1;
      if (delim_ == ' ')
        while (p < e && (*p == ' ' || *p == '\t')) ++p;
      continue;
    }
    const char* q = p;
    while (q < e && (*q == ' ' || *q == '\t')) ++q;
    double v = 0;
    const char* const num_end = parse_number(q, e, v);
    const char* end = num_end ? num_end : q;
    while (end < e && (*end == ' ' || *end == '\t')) ++end;
    // Blanks: the number ends at a blank or the line's end, and the blanks after it are the delimiter.
    const bool bad = !num_end || (delim_ == ' ' ? (end == num_end && end < e) : (end < e && *end != delim_));
    if (bad || !std::isfinite(v)) {
      // The field as written, for the message.
      const auto f = trim(std::string_view(p, static_cast<std::size_t>(field_end(delim_ == ' ' ? q : p, e) - p)));
      if (f.empty()) fail(slot_names_[slot], "empty field");
      if (bad) fail(slot_names_[slot], "not a number: '" + field_text(f) + "'");
      if (f.find_first_of("nNiI") != std::string_view::npos) fail(slot_names_[slot], "NaN or infinity is not allowed");
      fail(slot_names_[slot], "not a number: '" + field_text(f) + "' is out of the range of a double");
    }
    values_[slot] = v;
    ++field;
    if (end == e) break;
    p = delim_ == ' ' ? end : end + 1;
  }
  if (field < max_field_) {
    // Name the first selected column that is missing from this row.
    for (std::size_t i = field; i < max_field_; ++i)
      if (slot_of_field_[i] >= 0) fail(slot_names_[slot_of_field_[i]], "missing field (row has too few columns)");
  }
  return true;
}

bool CsvReader::next() {
  std::string_view line;
  while (read_line(line)) {
    const auto t = trim(line);
    if (t.empty() || t.front() == '#') continue;
    parse_row(t);
    if (time_slot_ >= 0) {
      const double tv = values_[time_slot_];
      plausible::check_row_time(*this, slot_names_[time_slot_], tv, rows_ > 0, last_time_);
      last_time_ = tv;
    }
    ++rows_;
    return true;
  }
  if (rows_ == 0) {
    ++line_no_;
    fail("", "no data rows");
  }
  return false;
}

std::size_t format_double(char* buf, double v) {
  const auto r = std::to_chars(buf, buf + 32, v, std::chars_format::general, 17);
  return static_cast<std::size_t>(r.ptr - buf);
}

CsvWriter::CsvWriter(std::string path, const std::vector<std::string>& columns, const std::string& comment)
    : path_(std::move(path)), ncol_(columns.size()) {
  file_.reset(std::fopen(path_.c_str(), "wb"));
  if (!file_) throw std::runtime_error(path_ + ": cannot create: " + std::strerror(errno));
  if (!comment.empty()) out_ += "# " + comment + "\n";
  for (std::size_t i = 0; i < columns.size(); ++i) {
    if (i) out_ += ',';
    out_ += columns[i];
  }
  out_ += '\n';
  out_.reserve(kBufSize + 4096);
}

CsvWriter::~CsvWriter() {
  if (file_) {
    try {
      close();
    } catch (...) {
    }
  }
}

void CsvWriter::row(const double* v, std::size_t n) {
  char tmp[40];
  for (std::size_t i = 0; i < n; ++i)
    if (!std::isfinite(v[i]))  // the format forbids NaN/inf: refuse rather than write an unreadable file
      throw std::invalid_argument(path_ + ": refusing to write a non-finite value in column " + std::to_string(i + 1));
  for (std::size_t i = 0; i < n; ++i) {
    if (i) out_ += ',';
    out_.append(tmp, format_double(tmp, v[i]));
  }
  out_ += '\n';
  if (out_.size() >= kBufSize) flush();
}

void CsvWriter::flush() {
  if (!file_) return;
  if (!out_.empty()) {
    if (std::fwrite(out_.data(), 1, out_.size(), file_.get()) != out_.size())
      throw std::runtime_error(path_ + ": write failed: " + std::strerror(errno));
    out_.clear();
  }
  if (std::fflush(file_.get()) != 0) throw std::runtime_error(path_ + ": write failed: " + std::strerror(errno));
}

void CsvWriter::close() {
  if (!file_) return;
  flush();
  ::fsync(fileno(file_.get()));
  const int rc = std::fclose(file_.release());
  if (rc != 0) throw std::runtime_error(path_ + ": close failed: " + std::strerror(errno));
}

}  // namespace calbench
