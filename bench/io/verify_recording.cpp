#include "bench/io/verify_recording.hpp"

#include <fstream>
#include <stdexcept>

#include "bench/io/hdf5_recording.hpp"
#include "bench/io/recording.hpp"
#include "common/input_error.hpp"

namespace calbench {

TableTally::TableTally(std::string name, std::vector<std::string> columns)
    : name_(std::move(name)), columns_(std::move(columns)), digest_(std::make_unique<Sha256>()) {}

void TableTally::add(const double* v, std::size_t n) {
  digest_->update(v, n * sizeof(double));  // the doubles' bytes: equal digests mean equal values bit for bit
  ++rows_;
}

const std::string& TableTally::sha256() {
  if (digest_) {
    hex_ = digest_->hex();
    digest_.reset();
  }
  return hex_;
}

TableTally TableTally::finished_copy() const {
  if (digest_) throw std::logic_error("TableTally::finished_copy: table '" + name_ + "' is still being written");
  TableTally t(name_, columns_);
  t.rows_ = rows_;
  t.digest_.reset();
  t.hex_ = hex_;
  return t;
}

void TextTally::add(std::string_view text) {
  digest_->update(text.data(), text.size());
  bytes_ += text.size();
  for (const char c : text) lines_ += c == '\n';
}

const std::string& TextTally::sha256() {
  if (digest_) {
    hex_ = digest_->hex();
    digest_.reset();
  }
  return hex_;
}

namespace {

[[noreturn]] void not_verified(const std::string& file, const std::string& what) {
  throw std::runtime_error(file + ": the output does not read back as written (" + what +
                           "): not kept or marked complete; check the disk and run the command again");
}

std::string join(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& c : v) s.append(s.empty() ? "" : ",").append(c);
  return s;
}

void verify_table(const std::filesystem::path& dir, TableTally& w) {
  const std::filesystem::path as_csv = dir / (w.name() + ".csv");
  const std::string file = table_file(dir, w.name()).string();
  if (!recording_has_table(dir, w.name())) not_verified(file, "table " + w.name() + " is missing");
  try {
    const auto src = open_table(as_csv);
    if (src->columns() != w.columns())
      not_verified(file, "table " + w.name() + " has columns " + join(src->columns()) + ", written " + join(w.columns()));
    std::vector<int> slot;
    for (const auto& c : w.columns()) slot.push_back(src->require(c));
    TableTally back(w.name(), w.columns());
    std::vector<double> row(slot.size());
    if (w.rows() > 0)  // a reader refuses a table without rows; one written without rows is checked by its header
      while (src->next()) {
        for (std::size_t i = 0; i < slot.size(); ++i) row[i] = src->value(slot[i]);
        back.add(row.data(), row.size());
      }
    if (back.rows() != w.rows())
      not_verified(file, "table " + w.name() + ": " + std::to_string(w.rows()) + " rows written, " +
                             std::to_string(back.rows()) + " read back");
    if (back.sha256() != w.sha256()) not_verified(file, "table " + w.name() + ": the values differ from those written");
  } catch (const InputError& e) {
    not_verified(file, e.what());
  }
}

}  // namespace

void verify_written_text(const std::filesystem::path& file, TextTally& written) {
  std::ifstream in(file, std::ios::binary);
  if (!in) not_verified(file.string(), "cannot open it again");
  TextTally back;
  std::vector<char> buf(1 << 20);
  while (in) {
    in.read(buf.data(), static_cast<std::streamsize>(buf.size()));
    back.add(std::string_view(buf.data(), static_cast<std::size_t>(in.gcount())));
  }
  if (in.bad()) not_verified(file.string(), "read error");
  if (back.bytes() != written.bytes() || back.lines() != written.lines())
    not_verified(file.string(), std::to_string(written.lines()) + " lines (" + std::to_string(written.bytes()) +
                                    " bytes) written, " + std::to_string(back.lines()) + " (" + std::to_string(back.bytes()) +
                                    " bytes) read back");
  if (back.sha256() != written.sha256()) not_verified(file.string(), "the bytes differ from those written");
}

void verify_written_recording(const std::filesystem::path& dir, std::vector<TableTally>& written) {
  for (const char* t : kRecordingTables) {
    TableTally* w = nullptr;
    for (auto& x : written)
      if (x.name() == t) w = &x;
    if (w) verify_table(dir, *w);
    else if (recording_has_table(dir, t))
      not_verified(table_file(dir, t).string(), "table " + std::string(t) + " was not written");
  }
  for (const auto& x : written) {
    bool known = false;
    for (const char* t : kRecordingTables) known = known || x.name() == t;
    if (!known) throw std::logic_error("verify_written_recording: unknown table " + x.name());
  }
}

}  // namespace calbench
