// Streaming CSV for the recording interchange format: a header line naming the columns, comma
// separated, '#' comment lines, '.' decimal point. Rows are parsed one at a time from a buffered
// file, so a recording never sits in memory as text. Only selected columns are parsed; unknown
// columns are ignored. Every defect is an InputError naming file, line and column.
#pragma once
#include <cstdio>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "bench/io/sha256.hpp"
#include "bench/io/table_source.hpp"

namespace calbench {

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};
using FilePtr = std::unique_ptr<std::FILE, FileCloser>;

class CsvReader final : public TableSource {
 public:
  // digest: SHA-256 of the file's bytes as they are read (sha256() once read to the end).
  // delim: ',' (the interchange format), ';', or ' ' for runs of blanks (spaces and tabs, as
  // space- and tab-separated loggers write them); 0 picks one from the header line (the most
  // frequent of ';' and ',', else blanks). Decimal point always '.'.
  explicit CsvReader(std::string path, bool digest = false, char delim = ',');
  ~CsvReader() override;
  CsvReader(const CsvReader&) = delete;
  CsvReader& operator=(const CsvReader&) = delete;

  // Select a column by name; returns a slot for value(). require() throws if it is absent.
  int require(std::string_view name) override;
  int optional(std::string_view name) override;  // −1 if absent
  bool has(std::string_view name) const override;
  const std::vector<std::string>& columns() const override { return header_; }
  // Enforce strictly increasing values in this slot (time).
  void set_time_slot(int slot) override { time_slot_ = slot; }

  // Parse the next data row; false at end of file. The first call fails if there is no data row.
  bool next() override;
  double value(int slot) const override { return values_[static_cast<std::size_t>(slot)]; }
  std::size_t line() const override { return line_no_; }
  const std::string& path() const override { return path_; }
  [[noreturn]] void fail_at(const std::string& column, const std::string& msg) const override { fail(column, msg); }
  std::optional<std::string> sha256() const override;
  const std::vector<std::string>& header() const { return header_; }
  char delimiter() const { return delim_; }
  // '#' comment lines before the header, without the '#' and one following blank.
  const std::vector<std::string>& comments() const { return comments_; }
  std::size_t rows() const { return rows_; }
  // A last line without its line end (a file cut while written or copied) is an InputError
  // instead of a warning: for a copy (convert), which must not pass a cut table on as complete.
  void refuse_cut_last_line() { refuse_cut_ = true; }

 private:
  bool refuse_cut_ = false;
  char delim_ = ',';
  const char* field_end(const char* p, const char* e) const;  // the delimiter ending the field at p, or e
  bool read_line(std::string_view& out);
  bool parse_row(std::string_view t);
  void refill();
  [[noreturn]] void fail(const std::string& column, const std::string& msg) const;
  std::unique_ptr<Sha256> digest_;  // while reading
  std::string sha256_;              // the digest once the file is read to its end
  std::vector<std::string> comments_;

  std::string path_;
  FilePtr file_;  // closed by its destructor, also when the constructor throws after opening
  std::vector<char> buf_;
  std::size_t beg_ = 0, end_ = 0;
  bool eof_ = false;
  std::string carry_;
  std::vector<std::string> header_;
  std::vector<int> slot_of_field_;  // field index -> slot (−1 if not selected)
  std::vector<std::string> slot_names_;
  std::vector<double> values_;
  std::size_t max_field_ = 0;
  std::size_t line_no_ = 0;
  std::size_t rows_ = 0;
  int time_slot_ = -1;
  double last_time_ = 0;
};

class CsvWriter {
 public:
  // Creates (truncates) the file and writes the comment (if any) and the header.
  CsvWriter(std::string path, const std::vector<std::string>& columns, const std::string& comment = {});
  ~CsvWriter();
  CsvWriter(const CsvWriter&) = delete;
  CsvWriter& operator=(const CsvWriter&) = delete;

  // One row; values printed with 17 significant digits (lossless for doubles).
  void row(const double* values, std::size_t n);
  void row(std::initializer_list<double> v) { row(v.begin(), v.size()); }
  void flush();   // hand buffered rows to the OS (a crash after this keeps them)
  void close();   // flush, fsync and close; throws on any write error
  std::size_t columns() const { return ncol_; }

 private:
  std::string path_;
  FilePtr file_;
  std::string out_;
  std::size_t ncol_;
};

// Format one double with 17 significant digits into buf; returns the length.
std::size_t format_double(char* buf, double v);

}  // namespace calbench
