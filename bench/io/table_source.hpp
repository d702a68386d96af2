// A table of named numeric columns read row by row: a CSV file of the interchange format
// (csv.hpp) or a dataset of an HDF5 recording (hdf5_recording.hpp, docs/recording-hdf5.md). The
// recording readers (recording.hpp) take their rows from either; a defect is an InputError that
// names the file, the place (CSV line; HDF5 dataset and row) and the column.
#pragma once
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace calbench {

class TableSource {
 public:
  virtual ~TableSource() = default;
  // Select a column by name; returns a slot for value(). require() throws if it is absent.
  virtual int require(std::string_view name) = 0;
  virtual int optional(std::string_view name) = 0;  // −1 if absent
  virtual bool has(std::string_view name) const = 0;
  // Every column's name, in the order of the file.
  virtual const std::vector<std::string>& columns() const = 0;
  // Enforce strictly increasing values in this slot (time).
  virtual void set_time_slot(int slot) = 0;
  // The next row; false at the end. The first call fails if there is no row.
  virtual bool next() = 0;
  virtual double value(int slot) const = 0;
  // The file, and the position of the row last read: its line (CSV) or its 1-based row (HDF5).
  virtual const std::string& path() const = 0;
  virtual std::size_t line() const = 0;
  // An error at the row last read, in `column`: file, line or dataset and row, column, message.
  [[noreturn]] virtual void fail_at(const std::string& column, const std::string& msg) const = 0;
  // SHA-256 (hex) of the file's bytes, when they were digested while reading (digest requested at
  // open) and the file has been read to its end; nullopt otherwise.
  virtual std::optional<std::string> sha256() const { return std::nullopt; }
};

}  // namespace calbench
