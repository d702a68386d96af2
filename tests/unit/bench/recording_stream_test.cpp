// Reading recordings fast (issue 22): the IMU rows parsed ahead on a thread keep their order,
// their line numbers and the input error at the row it was found (after the rows before it); the
// digest computed while reading is the file's SHA-256, given only once the file was read to its
// end; an HDF5 table written in blocks reads back bit for bit, across chunks, with its names.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <random>

#include "bench/io/csv.hpp"
#include "bench/io/hdf5_recording.hpp"
#include "bench/io/recording.hpp"
#include "common/input_error.hpp"
#include "tests/support/temp_dir.hpp"

namespace calbench {
namespace {

using test::TempDir;

// n rows of rates, t = k/100, values drawn from seed; bad_row (0: none) gets a non-number gz.
std::vector<std::array<double, 7>> write_imu(const fs::path& file, int n, int bad_row, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> nd(0.0, 1.0);
  std::vector<std::array<double, 7>> rows;
  CsvWriter w(file.string(), {"t_s", "gx_rad_s", "gy_rad_s", "gz_rad_s", "ax_m_s2", "ay_m_s2", "az_m_s2"}, "test");
  for (int k = 1; k <= n; ++k) {
    std::array<double, 7> r{k / 100.0, nd(rng), nd(rng), nd(rng), nd(rng), nd(rng), nd(rng) - 9.8};
    rows.push_back(r);
    w.row(r.data(), r.size());
  }
  w.close();
  if (bad_row > 0) {  // line = bad_row + 2 (comment, header)
    std::ifstream in(file);
    std::string text((std::istreambuf_iterator<char>(in)), {}), out;
    std::size_t pos = 0;
    for (int line = 1; line < bad_row + 2; ++line) pos = text.find('\n', pos) + 1;
    const std::size_t c3 = text.find(',', text.find(',', text.find(',', pos) + 1) + 1);  // before gz
    const std::size_t c4 = text.find(',', c3 + 1);
    text.replace(c3 + 1, c4 - c3 - 1, "0.1x");
    std::ofstream(file, std::ios::binary) << text;
  }
  return rows;
}

TEST(RecordingStream, ThreadedImuReaderKeepsOrderAndLines) {
  TempDir d;
  const auto rows = write_imu(d.path() / "imu.csv", 20000, 0, 1);
  ImuReader r(d.path() / "imu.csv", 100.0);
  ImuRecord rec;
  std::size_t k = 0;
  while (r.next(rec)) {
    ASSERT_LT(k, rows.size());
    EXPECT_EQ(rec.t, rows[k][0]);
    EXPECT_EQ(rec.gyro(2), rows[k][3]);
    EXPECT_EQ(rec.accel(2), rows[k][6]);
    EXPECT_EQ(r.line(), k + 3) << "comment and header lines first";
    ++k;
  }
  EXPECT_EQ(k, rows.size());
}

TEST(RecordingStream, ErrorComesAtItsRowAfterTheRowsBefore) {
  TempDir d;
  write_imu(d.path() / "imu.csv", 20000, 12345, 2);
  ImuReader r(d.path() / "imu.csv", 100.0);
  ImuRecord rec;
  std::size_t k = 0;
  try {
    while (r.next(rec)) ++k;
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(k, 12344u) << "every row before the bad one is delivered";
    EXPECT_EQ(e.line(), 12345u + 2) << e.what();
    EXPECT_EQ(e.field(), "gz_rad_s") << e.what();
    EXPECT_NE(std::string(e.what()).find("not a number: '0.1x'"), std::string::npos) << e.what();
  }
}

TEST(RecordingStream, DigestWhileReadingIsTheFilesSha256) {
  TempDir d;
  write_imu(d.path() / "imu.csv", 30000, 0, 3);
  ImuReader r(d.path() / "imu.csv", 100.0, /*digest=*/true);
  ImuRecord rec;
  EXPECT_FALSE(r.sha256()) << "not before the end";
  for (int i = 0; i < 10; ++i) r.next(rec);
  EXPECT_FALSE(r.sha256());
  while (r.next(rec)) {
  }
  ASSERT_TRUE(r.sha256());
  EXPECT_EQ(*r.sha256(), sha256_file(d.path() / "imu.csv"));
  ImuReader plain(d.path() / "imu.csv", 100.0);
  while (plain.next(rec)) {
  }
  EXPECT_FALSE(plain.sha256()) << "no digest unless asked";
}

TEST(RecordingStream, Hdf5TableRoundTripAcrossChunks) {
  TempDir d;
  const fs::path f = d.path() / kHdf5RecordingFile;
  const std::vector<std::string> cols = {"t_s", "a", "b"};
  std::vector<std::array<double, 3>> rows;
  {
    Hdf5RecordingWriter w(f, "{}");
    w.begin_table("imu", cols, {"first comment", "second"});
    for (int k = 0; k < 20001; ++k) {  // 2 full chunks and a partial one
      const std::array<double, 3> r{k * 0.01, std::sin(k * 0.1) * 1e-7, 1.0 / (k + 3)};
      rows.push_back(r);
      w.row(r.data());
    }
    w.end_table();
    w.begin_table("gnss", cols, {});
    const double one[3] = {0.5, 1, 2};
    w.row(one);
    w.end_table();
    w.close();
  }
  const Hdf5TableInfo info = hdf5_table_info(f, "imu");
  EXPECT_EQ(info.columns, cols);
  EXPECT_EQ(info.rows, rows.size());
  ASSERT_EQ(info.comments.size(), 2u);
  EXPECT_EQ(info.comments[1], "second");
  const auto t = open_hdf5_table(f, "imu");
  const int ts = t->require("t_s"), b = t->require("b");
  t->set_time_slot(ts);
  std::size_t k = 0;
  while (t->next()) {
    ASSERT_LT(k, rows.size());
    EXPECT_EQ(t->value(ts), rows[k][0]);
    EXPECT_EQ(t->value(b), rows[k][2]);
    EXPECT_EQ(t->line(), k + 1);
    ++k;
  }
  EXPECT_EQ(k, rows.size());
  EXPECT_EQ(hdf5_table_info(f, "gnss").rows, 1u);
  EXPECT_TRUE(recording_has_table(d.path(), "gnss"));
  EXPECT_FALSE(recording_has_table(d.path(), "reference"));
  try {
    open_hdf5_table(f, "reference");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "/reference");
    EXPECT_NE(std::string(e.what()).find("no dataset /reference"), std::string::npos) << e.what();
  }
  try {
    const auto u = open_hdf5_table(f, "imu");
    u->require("c");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "c");
    EXPECT_NE(std::string(e.what()).find("dataset /imu: missing required column"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace calbench
