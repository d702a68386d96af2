// Interchange format: lossless round trip and strict validation (issue 2).
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <random>

#include "bench/io/coefficients_json.hpp"
#include "common/input_error.hpp"
#include "tests/support/temp_dir.hpp"
#include "bench/io/recording.hpp"

namespace calbench {
namespace {

using test::TempDir;

void write_file(const fs::path& p, const std::string& text) {
  std::ofstream(p, std::ios::binary) << text;
}

const char* kBenchMeta = R"({"format": "calbench-recording/1", "kind": "bench",
  "device": {"model": "ADIS16488A", "serial": "A1"}, "site": {"lat_deg": 55.75, "lon_deg": 37.62, "h_m": 150.0},
  "imu_rate_hz": 100.0})";

// Expect an InputError whose message names file, line and field.
template <class F>
void expect_input_error(F&& f, const std::string& file_suffix, std::size_t line, const std::string& field,
                        const std::string& words) {
  try {
    f();
    FAIL() << "no error raised";
  } catch (const InputError& e) {
    EXPECT_NE(e.file().find(file_suffix), std::string::npos) << e.what();
    EXPECT_EQ(e.line(), line) << e.what();
    EXPECT_EQ(e.field(), field) << e.what();
    EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
  }
}

void read_all_imu(const fs::path& dir) {
  const auto meta = read_meta(dir);
  ImuReader r(dir / "imu.csv", meta.imu_rate_hz);
  ImuRecord rec;
  while (r.next(rec)) {
  }
}

TEST(RecordingIo, BenchRoundTripIsBitExact) {
  TempDir d;
  RecordingMeta m;
  m.kind = RecordingKind::bench;
  m.device = {"ADIS16488A", "A00123"};
  m.site = Site{55.75, 37.62, 150};
  m.imu_rate_hz = 2460;
  m.extra["custom_key"] = {{"kept", true}};
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<ImuRecord> imu;
  std::vector<BenchRefRow> ref;
  {
    RecordingWriter w(d.path(), m, ImuForm::rates, true, true);
    for (int k = 0; k < 1000; ++k) {
      ImuRecord r;
      r.t = k / 2460.0;
      r.gyro = Vec3(u(rng), u(rng) * 1e-300, u(rng) * 1e3);  // within the IMU bounds (plausible.hpp)
      r.accel = Vec3(u(rng) * 9.8, 1.0 / 3.0, -0.1);
      r.temp_c = 25 + u(rng);
      r.seq = k;
      w.imu(r);
      imu.push_back(r);
      BenchRefRow b{r.t, Vec3(u(rng), u(rng), u(rng) * 1e300), Vec3(u(rng), u(rng), u(rng)), k % 7 - 1, 359.99999999999994};
      w.bench_ref(b);
      ref.push_back(b);
    }
    const auto partial = read_meta(d.path());
    EXPECT_FALSE(partial.complete) << "meta must say incomplete until finish()";
    w.finish();
  }
  const auto m2 = read_meta(d.path());
  EXPECT_TRUE(m2.complete);
  EXPECT_EQ(m2.device.serial, "A00123");
  EXPECT_EQ(m2.extra["custom_key"]["kept"], true);
  ImuReader ir(d.path() / "imu.csv", m2.imu_rate_hz);
  EXPECT_EQ(ir.form(), ImuForm::rates);
  ImuRecord r;
  for (const auto& e : imu) {
    ASSERT_TRUE(ir.next(r));
    EXPECT_EQ(r.t, e.t);
    for (int i = 0; i < 3; ++i) {
      EXPECT_EQ(r.gyro(i), e.gyro(i));
      EXPECT_EQ(r.accel(i), e.accel(i));
    }
    EXPECT_EQ(r.temp_c, e.temp_c);
    EXPECT_EQ(r.seq, e.seq);
  }
  EXPECT_FALSE(ir.next(r));
  BenchRefReader br(d.path() / "reference.csv");
  BenchRefRow b;
  for (const auto& e : ref) {
    ASSERT_TRUE(br.next(b));
    EXPECT_EQ(b.t, e.t);
    EXPECT_EQ(b.step, e.step);
    EXPECT_EQ(b.angle_deg, e.angle_deg);
    for (int i = 0; i < 3; ++i) {
      EXPECT_EQ(b.w(i), e.w(i));
      EXPECT_EQ(b.f(i), e.f(i));
    }
  }
}

// Row k of a drive recording: IMU increments and, with `aiding`, a reference row and a GNSS fix.
void write_drive_row(RecordingWriter& w, int k, bool aiding) {
  ImuRecord r;
  r.t = k * 0.01;
  r.gyro = Vec3(1e-4 * k, -2e-5, 3.3e-6);
  r.accel = Vec3(0.098, 0.001 * k, -0.0981);
  w.imu(r);
  if (!aiding) return;
  DriveRefRow ref;
  ref.t = r.t;
  ref.lat_deg = 34.123456789012345;
  ref.lon_deg = 111.98765432109876;
  ref.h_m = 172.5;
  ref.v_ned = Vec3(11.5, -0.6, 0.25);
  ref.rpy_deg = Vec3(1.4, -3.1, 359.5);
  ref.sigma_pos_m = 0.05;
  ref.sigma_vel_m_s = 0.01;
  ref.sigma_att_deg = 0.01;
  w.drive_ref(ref);
  GnssRow g;
  g.t = r.t;
  g.lat_deg = ref.lat_deg;
  g.lon_deg = ref.lon_deg;
  g.h_m = 170;
  g.v_ned = ref.v_ned;
  g.sigma_h_m = 1;
  g.sigma_v_m = 2;
  g.sigma_vel_m_s = 0.1;
  w.gnss(g);
}

// The meta.json of a 100 Hz drive recording of unit `serial`.
RecordingMeta drive_meta(const std::string& serial, const Vec3& rpy_deg, const Vec3& lever_m) {
  RecordingMeta m;
  m.kind = RecordingKind::drive;
  m.device = {"ADIS16488A", serial};
  m.imu_rate_hz = 100;
  m.mounting = Mounting{rpy_deg, lever_m};
  return m;
}

TEST(RecordingIo, DriveIncrementsRoundTripWithGnss) {
  TempDir d;
  const RecordingMeta m = drive_meta("A9", Vec3(180, 0, 90), Vec3(0.1, -0.2, 0.3));
  {
    RecordingWriter w(d.path(), m, ImuForm::increments, false, false, true);
    for (int k = 1; k <= 50; ++k) write_drive_row(w, k, true);
    w.finish();
  }
  const auto m2 = read_meta(d.path());
  ASSERT_TRUE(m2.mounting.has_value());
  EXPECT_EQ(m2.mounting->lever_arm_m(1), -0.2);
  ImuReader ir(d.path() / "imu.csv", m2.imu_rate_hz);
  EXPECT_EQ(ir.form(), ImuForm::increments);
  ImuRecord r;
  ASSERT_TRUE(ir.next(r));
  EXPECT_DOUBLE_EQ(r.dt, 0.01);  // first row: nominal interval
  EXPECT_EQ(r.gyro(2), 3.3e-6);
  DriveRefReader dr(d.path() / "reference.csv");
  DriveRefRow ref;
  ASSERT_TRUE(dr.next(ref));
  EXPECT_EQ(ref.lat_deg, 34.123456789012345);
  EXPECT_EQ(ref.rpy_deg(2), 359.5);
  GnssReader gr(d.path() / "gnss.csv");
  GnssRow g;
  ASSERT_TRUE(gr.next(g));
  ASSERT_TRUE(g.v_ned.has_value());
  EXPECT_EQ(g.sigma_vel_m_s, 0.1);
}

// A fix off the Earth or a σ that is no σ is refused with file, line and field (a user's gnss.csv
// with lat 400 or a negative σ was read as a fix before).
TEST(RecordingIo, GnssAndReferenceRowsOffTheEarthOrWithNonPositiveSigmaAreRefused) {
  TempDir d;
  const std::string head = "t_s,lat_deg,lon_deg,h_m,vn_m_s,ve_m_s,vd_m_s,sigma_h_m,sigma_v_m,sigma_vel_m_s\n";
  const std::string good = "0,40.1,116.2,50,0,0,0,0.02,0.03,0.05\n";
  auto refused_field = [&](const std::string& row) {
    write_file(d.path() / "gnss.csv", head + good + row);
    GnssReader gr(d.path() / "gnss.csv");
    GnssRow g;
    EXPECT_TRUE(gr.next(g));
    try {
      gr.next(g);
    } catch (const InputError& e) {
      EXPECT_EQ(e.line(), 3u) << e.what();
      return e.field();
    }
    return std::string("(accepted)");
  };
  EXPECT_EQ(refused_field("1,400,116.2,50,0,0,0,0.02,0.03,0.05\n"), "lat_deg");
  EXPECT_EQ(refused_field("1,40.1,-200,50,0,0,0,0.02,0.03,0.05\n"), "lon_deg");
  EXPECT_EQ(refused_field("1,40.1,116.2,2e6,0,0,0,0.02,0.03,0.05\n"), "h_m");
  EXPECT_EQ(refused_field("1,40.1,116.2,50,0,0,0,-0.02,0.03,0.05\n"), "sigma_h_m");
  EXPECT_EQ(refused_field("1,40.1,116.2,50,0,0,0,0.02,0,0.05\n"), "sigma_v_m");
  EXPECT_EQ(refused_field("1,40.1,116.2,50,0,0,0,0.02,0.03,-1\n"), "sigma_vel_m_s");
  EXPECT_EQ(refused_field("1,40.1,359.9,50,0,0,0,0.02,0.03,0.05\n"), "(accepted)") << "longitude 0-360 is a longitude";
  write_file(d.path() / "reference.csv",
             "t_s,lat_deg,lon_deg,h_m,vn_m_s,ve_m_s,vd_m_s,roll_deg,pitch_deg,yaw_deg,sigma_pos_m\n0,40,116,50,0,0,0,0,0,0,0\n");
  DriveRefReader dr(d.path() / "reference.csv");
  DriveRefRow ref;
  try {
    dr.next(ref);
    ADD_FAILURE() << "a zero sigma_pos_m was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "sigma_pos_m");
  }
}

TEST(RecordingIo, ReadsForeignLayoutCommentsReorderedAndUnknownColumns) {
  TempDir d;
  write_file(d.path() / "meta.json", kBenchMeta);
  write_file(d.path() / "imu.csv",
             "# written by another tool\r\nextra,az_m_s2,t_s,gx_rad_s,gy_rad_s,gz_rad_s,ax_m_s2,ay_m_s2\r\n"
             "x,-9.8,0,1e-3,+2E-3,0.003,0,0\r\n# a comment in the middle\r\n\r\nx,-9.7,0.01,1,2,3,4,5\r\n");
  const auto meta = read_meta(d.path());
  ImuReader r(d.path() / "imu.csv", meta.imu_rate_hz);
  ImuRecord rec;
  ASSERT_TRUE(r.next(rec));
  EXPECT_EQ(rec.accel(2), -9.8);
  EXPECT_EQ(rec.gyro(1), 2e-3);
  ASSERT_TRUE(r.next(rec));
  EXPECT_EQ(rec.accel(1), 5.0);
  EXPECT_FALSE(r.next(rec));
}

// A last line without its line end was cut while being written (its last number may be cut): it is
// not used (the reader warns on standard error, naming the file and line).
TEST(RecordingIo, LastLineWithoutLineEndIsTreatedAsTruncated) {
  TempDir d;
  write_file(d.path() / "meta.json", kBenchMeta);
  write_file(d.path() / "imu.csv", "t_s,gx_rad_s,gy_rad_s,gz_rad_s,ax_m_s2,ay_m_s2,az_m_s2\n0,1,2,3,4,5,6\n0.01,1,2,3,4,5,6.7");
  const auto meta = read_meta(d.path());
  ImuReader r(d.path() / "imu.csv", meta.imu_rate_hz);
  ImuRecord rec;
  ASSERT_TRUE(r.next(rec));
  EXPECT_EQ(rec.accel(2), 6.0);
  EXPECT_FALSE(r.next(rec));  // "6.7" may be the first digits of 6.75: not used
}

const char* kHeader = "t_s,gx_rad_s,gy_rad_s,gz_rad_s,ax_m_s2,ay_m_s2,az_m_s2\n";

TEST(RecordingValidation, MissingRequiredColumn) {
  TempDir d;
  write_file(d.path() / "meta.json", kBenchMeta);
  write_file(d.path() / "imu.csv", "t_s,gx_rad_s,gy_rad_s,ax_m_s2,ay_m_s2,az_m_s2\n0,1,2,3,4,5\n");
  expect_input_error([&] { read_all_imu(d.path()); }, "imu.csv", 1, "gz_rad_s", "missing required column");
}

TEST(RecordingValidation, NonNumber) {
  TempDir d;
  write_file(d.path() / "meta.json", kBenchMeta);
  write_file(d.path() / "imu.csv", std::string(kHeader) + "0,1,2,3,4,5,6\n0.01,1,2,3,abc,5,6\n");
  expect_input_error([&] { read_all_imu(d.path()); }, "imu.csv", 3, "ax_m_s2", "not a number");
}

TEST(RecordingValidation, NaNAndInfinity) {
  for (const char* bad : {"nan", "NaN", "inf", "-inf", "1e999"}) {
    TempDir d;
    write_file(d.path() / "meta.json", kBenchMeta);
    write_file(d.path() / "imu.csv", std::string(kHeader) + "0,1,2,3,4,5,6\n0.01,1,2," + bad + ",4,5,6\n");
    SCOPED_TRACE(bad);
    try {
      read_all_imu(d.path());
      FAIL() << "accepted " << bad;
    } catch (const InputError& e) {
      EXPECT_EQ(e.line(), 3u) << e.what();
      EXPECT_EQ(e.field(), "gz_rad_s") << e.what();
    }
  }
}

TEST(RecordingValidation, TimeGoingBackwards) {
  TempDir d;
  write_file(d.path() / "meta.json", kBenchMeta);
  write_file(d.path() / "imu.csv", std::string(kHeader) + "0,1,2,3,4,5,6\n0.02,1,2,3,4,5,6\n0.01,1,2,3,4,5,6\n");
  expect_input_error([&] { read_all_imu(d.path()); }, "imu.csv", 4, "t_s", "time goes backwards");
}

TEST(RecordingValidation, DuplicatedTime) {
  TempDir d;
  write_file(d.path() / "meta.json", kBenchMeta);
  write_file(d.path() / "imu.csv", std::string(kHeader) + "0,1,2,3,4,5,6\n0.01,1,2,3,4,5,6\n0.01,1,2,3,4,5,6\n");
  expect_input_error([&] { read_all_imu(d.path()); }, "imu.csv", 4, "t_s", "duplicated time");
}

TEST(RecordingValidation, EmptyFileAndHeaderOnly) {
  TempDir d;
  write_file(d.path() / "meta.json", kBenchMeta);
  write_file(d.path() / "imu.csv", "");
  expect_input_error([&] { read_all_imu(d.path()); }, "imu.csv", 0, "", "empty file");
  write_file(d.path() / "imu.csv", "# only a comment\n" + std::string(kHeader));
  expect_input_error([&] { read_all_imu(d.path()); }, "imu.csv", 3, "", "no data rows");
}

TEST(RecordingValidation, ShortRow) {
  TempDir d;
  write_file(d.path() / "meta.json", kBenchMeta);
  write_file(d.path() / "imu.csv", std::string(kHeader) + "0,1,2,3,4,5\n");
  expect_input_error([&] { read_all_imu(d.path()); }, "imu.csv", 2, "az_m_s2", "missing field");
}

TEST(RecordingValidation, MissingMetaKeys) {
  TempDir d;
  write_file(d.path() / "meta.json", R"({"format": "calbench-recording/1", "kind": "bench",
    "device": {"model": "ADIS16488A", "serial": "A1"}, "site": {"lat_deg": 1, "lon_deg": 2, "h_m": 3}})");
  expect_input_error([&] { read_meta(d.path()); }, "meta.json", 0, "imu_rate_hz", "missing key");
  write_file(d.path() / "meta.json", R"({"format": "calbench-recording/1", "kind": "bench",
    "device": {"model": "ADIS16488A", "serial": "A1"}, "imu_rate_hz": 100})");
  expect_input_error([&] { read_meta(d.path()); }, "meta.json", 0, "site", "missing key");
  write_file(d.path() / "meta.json", R"({"format": "calbench-recording/1", "kind": "drive",
    "device": {"model": "ADIS16488A", "serial": "A1"}, "imu_rate_hz": 100})");
  expect_input_error([&] { read_meta(d.path()); }, "meta.json", 0, "mounting", "missing key");
  write_file(d.path() / "meta.json", R"({"format": "calbench-recording/1", "kind": "bench",
    "device": {"model": "ADIS16488A"}, "imu_rate_hz": 100})");
  expect_input_error([&] { read_meta(d.path()); }, "meta.json", 0, "device.serial", "missing key");
  write_file(d.path() / "meta.json", "{\"format\": \"calbench-recording/1\",\n \"kind\": bench}");
  expect_input_error([&] { read_meta(d.path()); }, "meta.json", 2, "", "invalid JSON");
}

TEST(RecordingValidation, IncompleteRecordingStaysReadable) {
  TempDir d;
  RecordingMeta m;
  m.kind = RecordingKind::bench;
  m.device = {"ADIS16488A", "A1"};
  m.site = Site{};
  m.imu_rate_hz = 100;
  {
    RecordingWriter w(d.path(), m, ImuForm::rates, /*with_temperature=*/false);
    for (int k = 0; k < 10; ++k) {
      ImuRecord r;
      r.t = k * 0.01;
      w.imu(r);
      w.bench_ref({r.t, Vec3::Zero(), Vec3::Zero(), 0, 0});
    }
    w.flush();
    // destroyed without finish(): an aborted run
  }
  const auto meta = read_meta(d.path());
  EXPECT_FALSE(meta.complete);
  ImuReader r(d.path() / "imu.csv", meta.imu_rate_hz);
  ImuRecord rec;
  int n = 0;
  while (r.next(rec)) ++n;
  EXPECT_EQ(n, 10);
}

TEST(RecordingIo, WriterRefusesNonFiniteValues) {
  TempDir d;
  RecordingMeta m;
  m.kind = RecordingKind::bench;
  m.device = {"ADIS16488A", "A1"};
  m.site = Site{};
  m.imu_rate_hz = 100;
  RecordingWriter w(d.path(), m, ImuForm::rates, /*with_temperature=*/true);
  ImuRecord r;  // temp_c is NaN
  EXPECT_THROW(w.imu(r), std::invalid_argument);
}

TEST(CoefficientsJson, RoundTripKeepsUnknownKeysAndNullSigma) {
  TempDir d;
  CoefficientSet c;
  c.device = {"ADIS16488A", "A7"};
  c.errors.gyro.bias = Vec3(1e-3, -2e-3, 3e-3);
  c.errors.gyro.M(0, 1) = 1.5e-4;
  c.errors.gyro.sigma_M(2, 0) = kUnknownSigma;
  c.extra["temperature"] = {{"gyro_bias_per_c", {1, 2, 3}}};
  write_coefficients(d.path() / "c.json", c);
  const auto r = read_coefficients(d.path() / "c.json");
  EXPECT_EQ(r.errors.gyro.bias, c.errors.gyro.bias);
  EXPECT_EQ(r.errors.gyro.M, c.errors.gyro.M);
  EXPECT_TRUE(std::isinf(r.errors.gyro.sigma_M(2, 0)));
  EXPECT_EQ(r.extra["temperature"]["gyro_bias_per_c"][2], 3);
  write_file(d.path() / "bad.json", R"({"format": "calbench-coefficients/1", "device": {"model": "m", "serial": "s"},
    "gyro": {"bias": [0, 0, "x"], "M": [[0,0,0],[0,0,0],[0,0,0]]}, "accel": {"bias": [0,0,0], "M": [[0,0,0],[0,0,0],[0,0,0]]}})");
  expect_input_error([&] { read_coefficients(d.path() / "bad.json"); }, "bad.json", 0, "gyro.bias[2]", "expected a number");
}

TEST(SensorModel, ComposeEqualsCorrectingTwice) {
  // raw = (I+M1)·x1 + b1 and x1 = (I+M2)·true + b2  ⇒ compose(first, second) describes raw directly.
  TriadErrors a, b;
  a.bias = Vec3(0.01, -0.02, 0.03);
  a.M << 1e-3, 2e-4, -3e-4, 4e-4, -2e-3, 1e-4, 0, 5e-4, 3e-3;
  b.bias = Vec3(-1e-3, 2e-3, 5e-4);
  b.M << -2e-4, 1e-4, 0, 3e-5, 4e-4, -1e-4, 2e-4, 0, -5e-4;
  const TriadErrors c = compose(a, b);
  const Vec3 truth(0.3, -1.2, 9.7);
  const Vec3 raw = a.measure(b.measure(truth));
  EXPECT_LT((c.measure(truth) - raw).norm(), 1e-14);
  EXPECT_LT((c.correct(raw) - truth).norm(), 1e-13);
  EXPECT_LT((b.correct(a.correct(raw)) - truth).norm(), 1e-13);
}

// Issue 35 item 1 (multi-unit `simulate drive`): a unit whose reference and GNSS are the drive's
// shared files is marked complete only after its check of the files it finally holds; a shared
// file that no longer holds what the first unit wrote leaves the unit incomplete.
TEST(RecordingIo, AUnitSharingTheDrivesReferenceIsCheckedAgainstTheSharedFiles) {
  TempDir d;
  RecordingMeta m = drive_meta("S1", Vec3::Zero(), Vec3::Zero());
  RecordingWriter first(d.path() / "1", m, ImuForm::increments, false, false, true);
  for (int k = 1; k <= 30; ++k) write_drive_row(first, k, true);
  EXPECT_THROW(RecordingWriter(d.path() / "x", m, ImuForm::increments, false, false, true).share_table(first, "reference"),
               std::logic_error);  // from a recording still being written
  first.finish();

  m.device.serial = "S2";
  RecordingWriter second(d.path() / "2", m, ImuForm::increments, false, false, true);
  for (int k = 1; k <= 30; ++k) write_drive_row(second, k, false);
  second.share_table(first, "reference");
  second.share_table(first, "gnss");
  second.finish();
  EXPECT_TRUE(read_meta(d.path() / "2").complete);
  for (const char* f : {"reference.csv", "gnss.csv"})
    EXPECT_TRUE(fs::equivalent(d.path() / "1" / f, d.path() / "2" / f) ||
                fs::file_size(d.path() / "1" / f) == fs::file_size(d.path() / "2" / f))
        << f;
  DriveRefReader rr(d.path() / "2" / "reference.csv");
  std::size_t rows = 0;
  for (DriveRefRow r; rr.next(r);) ++rows;
  EXPECT_EQ(rows, 30u);

  // A shared reference that lost its last rows (a lost write): the next unit is not complete.
  m.device.serial = "S3";
  RecordingWriter third(d.path() / "3", m, ImuForm::increments, false, false, true);
  for (int k = 1; k <= 30; ++k) write_drive_row(third, k, false);
  third.share_table(first, "gnss");
  fs::copy_file(d.path() / "1" / "reference.csv", d.path() / "ref_short.csv");
  fs::resize_file(d.path() / "ref_short.csv", fs::file_size(d.path() / "ref_short.csv") / 2);
  third.share_table(first, "reference");
  fs::remove(d.path() / "3" / "reference.csv");
  fs::copy_file(d.path() / "ref_short.csv", d.path() / "3" / "reference.csv");
  EXPECT_ANY_THROW(third.finish());
  EXPECT_FALSE(read_meta(d.path() / "3").complete);
}

}  // namespace
}  // namespace calbench
