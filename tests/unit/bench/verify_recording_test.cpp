// verify_written_recording / verify_written_text (issue 35): an output is complete only when it
// reads back as written. Each case writes a real folder with the real writers, then changes what
// is on disk the way a lost write would (a value, a row, a table, bytes) and expects the check to
// name the file and what differs; the unchanged folder passes.
#include <gtest/gtest.h>

#include <fstream>
#include <functional>
#include <sstream>

#include "bench/io/csv.hpp"
#include "bench/io/hdf5_recording.hpp"
#include "bench/io/recording.hpp"
#include "bench/io/verify_recording.hpp"
#include "tests/support/temp_dir.hpp"

namespace calbench {
namespace {

namespace fs = std::filesystem;
using test::TempDir;

const std::vector<std::string> kImuCols = {"t_s", "gx_rad_s", "gy_rad_s", "gz_rad_s", "ax_m_s2", "ay_m_s2", "az_m_s2"};

// imu.csv of n rows with values that need all 17 digits; returns its tally.
TableTally write_imu(const fs::path& dir, int n) {
  TableTally tally("imu", kImuCols);
  CsvWriter w((dir / "imu.csv").string(), kImuCols, "test");
  for (int k = 0; k < n; ++k) {
    const double v[] = {0.01 * k, 1.0 / 3 + k, -2.0 / 7, 1e-17 * k, 0.1, -0.2, -9.80665 + 1e-15 * k};
    w.row(v, 7);
    tally.add(v, 7);
  }
  w.close();
  return tally;
}

std::string read_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

void write_text(const fs::path& p, const std::string& t) { std::ofstream(p, std::ios::binary) << t; }

// The message of the check's refusal ("" if it passed).
std::string refusal(const fs::path& dir, std::vector<TableTally>& t) {
  try {
    verify_written_recording(dir, t);
    return "";
  } catch (const std::runtime_error& e) {
    return e.what();
  }
}

// imu.csv of 50 rows written and tallied, then changed on disk by `edit`: the check's refusal.
std::string refusal_after(const std::function<void(std::string&)>& edit) {
  TempDir d;
  std::vector<TableTally> t;
  t.push_back(write_imu(d.path(), 50));
  std::string text = read_text(d.path() / "imu.csv");
  edit(text);
  write_text(d.path() / "imu.csv", text);
  return refusal(d.path(), t);
}

TEST(VerifyRecording, UnchangedCsvPasses) {
  TempDir d;
  std::vector<TableTally> t;
  t.push_back(write_imu(d.path(), 50));
  EXPECT_EQ(refusal(d.path(), t), "");
}

TEST(VerifyRecording, OneValueChangedInTheLastDigitIsRefused) {
  const std::string m = refusal_after([](std::string& text) {
    const auto p = text.find("0.33333333333333331");  // 1/3, 17 digits: to the next double up
    ASSERT_NE(p, std::string::npos);
    text.replace(p, 19, "0.33333333333333337");
  });
  EXPECT_NE(m.find("imu.csv"), std::string::npos) << m;
  EXPECT_NE(m.find("the values differ"), std::string::npos) << m;
}

TEST(VerifyRecording, ARowLostIsRefusedWithBothCounts) {
  const std::string m = refusal_after([](std::string& text) { text.erase(text.rfind('\n', text.size() - 2) + 1); });
  EXPECT_NE(m.find("50 rows written, 49 read back"), std::string::npos) << m;
}

TEST(VerifyRecording, MissingAndUnwrittenTablesAreRefused) {
  TempDir d;
  std::vector<TableTally> t;
  t.push_back(write_imu(d.path(), 5));
  t.emplace_back("reference", std::vector<std::string>{"t_s", "x"});
  std::string m = refusal(d.path(), t);
  EXPECT_NE(m.find("table reference is missing"), std::string::npos) << m;
  t.pop_back();
  { CsvWriter w((d.path() / "gnss.csv").string(), {"t_s", "lat_deg"}); w.row({0.0, 1.0}); }
  m = refusal(d.path(), t);
  EXPECT_NE(m.find("gnss.csv"), std::string::npos) << m;
  EXPECT_NE(m.find("table gnss was not written"), std::string::npos) << m;
}

// An overwrite (simulate drive --force) by a recording without GNSS of one with gnss.csv: the old
// table is removed, not read back as an unwritten part of the new recording.
TEST(VerifyRecording, AnOverwriteRemovesTablesTheNewRecordingHasNot) {
  TempDir d;
  { CsvWriter w((d.path() / "gnss.csv").string(), {"t_s", "lat_deg"}); w.row({0.0, 1.0}); }
  RecordingMeta meta;
  meta.kind = RecordingKind::drive;
  meta.imu_rate_hz = 100;
  RecordingWriter w(d.path(), meta, ImuForm::rates, false, false, false);
  EXPECT_FALSE(std::filesystem::exists(d.path() / "gnss.csv"));
}

TEST(VerifyRecording, OtherColumnsAreRefused) {
  const std::string m = refusal_after([](std::string& text) { text.replace(text.find("gz_rad_s"), 8, "gz_deg_s"); });
  EXPECT_NE(m.find("has columns t_s,gx_rad_s,gy_rad_s,gz_deg_s"), std::string::npos) << m;
}

TEST(VerifyRecording, Hdf5WrittenTableIsReadBack) {
  TempDir d;
  TableTally tally("imu", kImuCols);
  {
    Hdf5RecordingWriter w(d.path() / kHdf5RecordingFile, "{}");
    w.begin_table("imu", kImuCols, {});
    for (int k = 0; k < 20; ++k) {
      const double v[] = {0.01 * k, 1.0 / 3, 0, 0, 0, 0, -9.8};
      w.row(v);
      tally.add(v, 7);
    }
    w.end_table();
    w.close();
  }
  std::vector<TableTally> t;
  t.push_back(std::move(tally));
  EXPECT_EQ(refusal(d.path(), t), "");
  std::vector<TableTally> more;  // a tally of one row more than the file holds
  more.emplace_back("imu", kImuCols);
  for (int k = 0; k < 21; ++k) {
    const double v[] = {0.01 * k, 1.0 / 3, 0, 0, 0, 0, -9.8};
    more.back().add(v, 7);
  }
  const std::string m = refusal(d.path(), more);
  EXPECT_NE(m.find("21 rows written, 20 read back"), std::string::npos) << m;
}

// verify_written_text of `file` against a tally of `tallied`: its refusal ("" if it passed).
std::string text_refusal(const fs::path& file, const std::string& tallied) {
  TextTally t;
  t.add(tallied);
  try {
    verify_written_text(file, t);
    return "";
  } catch (const std::runtime_error& e) {
    return e.what();
  }
}

TEST(VerifyText, BytesLinesAndDigest) {
  TempDir d;
  const fs::path f = d.path() / "imu.txt";
  write_text(f, "1 2 3\n4 5 6\n");
  EXPECT_EQ(text_refusal(f, "1 2 3\n4 5 6\n"), "");
  const std::string changed = text_refusal(f, "1 2 3\n4 5 7\n");
  EXPECT_NE(changed.find("the bytes differ"), std::string::npos) << changed;
  const std::string lost = text_refusal(f, "1 2 3\n4 5 6\n7 8 9\n");
  EXPECT_NE(lost.find("3 lines (18 bytes) written, 2 (12 bytes) read back"), std::string::npos) << lost;
}

}  // namespace
}  // namespace calbench
