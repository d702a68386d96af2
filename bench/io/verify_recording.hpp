// The check every recording writer makes before it marks its output complete (issue 35): what it
// wrote is read back and compared with what it meant to write — the same tables (none missing,
// none extra), the same columns, the same number of rows and the same values bit for bit (SHA-256
// of the doubles, row by row). The writer tallies the rows as it writes them (TableTally); the
// folder is then re-read, CSV or HDF5, by the readers every command uses (open_table).
#pragma once
#include <cstddef>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "bench/io/sha256.hpp"

namespace calbench {

// One table as written: its name ("imu", "reference", "gnss"), columns, rows and values digest.
class TableTally {
 public:
  TableTally(std::string name, std::vector<std::string> columns);
  void add(const double* v, std::size_t n);  // one row, in column order
  const std::string& name() const { return name_; }
  const std::vector<std::string>& columns() const { return columns_; }
  std::size_t rows() const { return rows_; }
  const std::string& sha256();  // of the values tallied; finishes the tally (add() may not follow)
  // The same table as tallied, for a file shared with another recording (std::logic_error unless
  // finished: the copy's figures must not move).
  TableTally finished_copy() const;

 private:
  std::string name_;
  std::vector<std::string> columns_;
  std::size_t rows_ = 0;
  std::unique_ptr<Sha256> digest_;
  std::string hex_;
};

// A text file as written (KF-GINS files of `export kf-gins`, JSON outputs): its lines and the
// SHA-256 of its bytes.
class TextTally {
 public:
  TextTally() : digest_(std::make_unique<Sha256>()) {}
  void add(std::string_view text);  // bytes as written; lines counted by their '\n'
  std::size_t lines() const { return lines_; }
  std::size_t bytes() const { return bytes_; }
  const std::string& sha256();  // finishes the tally

 private:
  std::size_t lines_ = 0, bytes_ = 0;
  std::unique_ptr<Sha256> digest_;
  std::string hex_;
};

// Re-reads `file` and compares its lines, size and digest with `written`: std::runtime_error
// naming the file and what differs otherwise.
void verify_written_text(const std::filesystem::path& file, TextTally& written);

// Re-reads every table of the recording folder `dir` and compares it with `written`: a table
// missing, one not written, other columns, another row count or other values throw
// std::runtime_error naming the file and what differs (the output is not to be marked complete).
void verify_written_recording(const std::filesystem::path& dir, std::vector<TableTally>& written);

}  // namespace calbench
