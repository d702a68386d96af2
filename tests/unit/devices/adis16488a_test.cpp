// The ADIS16488A driver against the emulator: pipelining, paging, 32-bit reads, scaling, identity,
// PROD_ID mismatch, error flags, sample loss, self-test, DEC_RATE, provisioning (a set the registers
// cannot hold refused with nothing written; the read-back registers checked against the set, every
// coefficient; the provisioned unit's outputs equal to the truth, scale errors up to the limit).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <set>

#include "common/units.hpp"
#include "devices/adis16488a.hpp"
#include "devices/adis16488a_emulator.hpp"

using namespace calbench;
using namespace calbench::devices;

namespace {

const Vec3 kW(0.1, -0.2, 0.3);
const Vec3 kF(0.5, -1.0, -9.7);

NoiseSpec quiet() {  // no noise, no drift, only the 32-bit output quantisation
  NoiseSpec n = adis16488a_noise();
  n.gyro.white_density = n.accel.white_density = 0;
  n.gyro.drift_sigma = n.accel.drift_sigma = 0;
  return n;
}

struct Rig {
  std::shared_ptr<VirtualClock> clock = std::make_shared<VirtualClock>();
  Adis16488aEmulator emu;
  Adis16488a imu;
  explicit Rig(const SensorErrors& truth = {}, NoiseSpec noise = quiet())
      : emu(clock, [](double) { return EmuTruth{kW, kF}; }, truth, noise), imu(emu) {}
};

TEST(Adis16488a, IdentityAndPipelinedFrames) {
  Rig r;
  auto id = r.imu.connect();
  EXPECT_EQ(id.prod_id, 0x4068);
  EXPECT_EQ(id.serial, 0x1234);
  EXPECT_EQ(id.firmware(), "1.10 (2016-06-15)");
  EXPECT_EQ(id.dec_rate, 0);
  EXPECT_DOUBLE_EQ(id.output_rate_hz, 2460.0);
  // N registers in N+1 frames, page frame only when the page changes.
  const auto f0 = r.emu.frames();
  auto w = r.imu.read_words(3, {0x78, 0x7A, 0x7C});
  EXPECT_EQ(r.emu.frames() - f0, 5u);  // connect() ended on page 4: one page frame + 3 requests + 1
  EXPECT_EQ(w, (std::vector<std::uint16_t>{0x0110, 0x0615, 0x2016}));
}

TEST(Adis16488a, PageCacheAvoidsRedundantPageFrames) {
  Rig r;
  r.imu.connect();
  r.imu.select_page(3);
  const auto f0 = r.emu.frames();
  r.imu.read16(adis::reg("DEC_RATE"));
  r.imu.read16(adis::reg("CONFIG"));
  EXPECT_EQ(r.emu.frames() - f0, 4u);  // 2 × (request + dummy), no page frame
  EXPECT_EQ(r.imu.read16(adis::reg("CONFIG")), 0x00C0);
  r.imu.read16(adis::reg("PROD_ID"));  // page 0: one page frame more
  EXPECT_EQ(r.imu.cached_page(), 0);
  EXPECT_EQ(r.emu.peek(0, 0x00), 0);
}

TEST(Adis16488a, ScaledSampleMatchesTruthAndThe32BitPair) {
  Rig r;
  r.imu.connect();
  auto s = r.imu.read_sample();
  ASSERT_TRUE(s);
  const double glsb = adis::reg("X_GYRO").scale, alsb = adis::reg("X_ACCL").scale;
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(s->gyro[i], kW[i], 0.51 * glsb);
    EXPECT_NEAR(s->accel[i], kF[i], 0.51 * alsb);
  }
  EXPECT_NEAR(s->temp_c, 31.5, 0.01);
  EXPECT_FALSE(s->error());
  // read32 gives the same raw value as the sample's OUT:LOW pair.
  const auto raw = static_cast<std::int32_t>(r.imu.read32(adis::reg("Z_GYRO")));
  EXPECT_NEAR(raw * glsb, kW[2], 0.51 * glsb);
  EXPECT_EQ(r.emu.busy_violations(), 0u);
}

TEST(Adis16488a, WrongProdIdIsRefused) {
  Rig r;
  r.emu.faults().prod_id = 0x4060;
  try {
    r.imu.connect();
    FAIL();
  } catch (const DeviceError& e) {
    EXPECT_NE(std::string(e.what()).find("0x4060"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("0x4068"), std::string::npos);
  }
}

TEST(Adis16488a, ErrorFlagsAreFlaggedAndDecoded) {
  Rig r;
  r.imu.connect();
  ASSERT_FALSE(r.imu.read_sample()->error());
  r.emu.faults().sys_e_flag = adis::sys_e::spi_error | adis::sys_e::overrun;
  r.imu.read_sample();  // a sample latched before the fault may come first
  auto s = r.imu.read_sample();
  ASSERT_TRUE(s);
  EXPECT_TRUE(s->error());
  EXPECT_EQ(s->error_text(), "SPI communication error; processing overrun");
  EXPECT_GE(r.imu.error_samples(), 1u);
  // New-mag / new-baro data flags are not errors.
  EXPECT_EQ(adis::decode_sys_e_flag(adis::sys_e::new_mag | adis::sys_e::new_baro), "");
}

// Issue 35: injected faults are the emulator's configuration. after_self_test: a unit that fails in
// service is identified and self-tested as a good one; flags_from_s delays the flags further.
TEST(Adis16488a, ConfiguredFaultsActAfterTheSelfTestAndFromTheirTime) {
  auto clock = std::make_shared<VirtualClock>();
  Adis16488aEmulatorConfig cfg;
  cfg.faults.sys_e_flag = adis::sys_e::spi_error;
  cfg.faults.after_self_test = true;
  cfg.faults.flags_from_s = 2.0;
  Adis16488aEmulator emu(clock, [](double) { return EmuTruth{kW, kF}; }, {}, quiet(), cfg);
  Adis16488a imu(emu);
  imu.connect();
  ASSERT_FALSE(imu.read_sample()->error());  // before the self-test: a good unit
  ASSERT_TRUE(imu.self_test().passed);
  for (int k = 0; k < 100; ++k) ASSERT_FALSE(imu.read_sample()->error()) << k;  // before 2 s
  clock->wait_until(2.0);
  imu.read_sample();  // a sample latched before may come first
  auto s = imu.read_sample();
  ASSERT_TRUE(s);
  EXPECT_TRUE(s->error());
  EXPECT_EQ(s->error_text(), "SPI communication error");
}

TEST(Adis16488a, MissingSamplesAreCounted) {
  Rig r;
  r.imu.connect();
  r.emu.faults().skip_every = 10;
  std::uint64_t lost = 0;
  double t_prev = -1;
  for (int k = 0; k < 200; ++k) {
    auto s = r.imu.read_sample();
    ASSERT_TRUE(s);
    lost += s->lost_before;
    if (t_prev >= 0) { EXPECT_NEAR(s->t - t_prev, (1 + s->lost_before) / 2460.0, 1e-9); }
    t_prev = s->t;
  }
  // 200 samples read while every 10th internal sample is missing: 200/9 ≈ 22 gaps.
  EXPECT_GE(lost, 21u);
  EXPECT_LE(lost, 23u);
  EXPECT_EQ(lost, r.imu.samples_lost());
  EXPECT_EQ(r.emu.samples_overwritten(), 0u);
}

TEST(Adis16488a, SlowReaderLosesSamplesAndTheDriverSeesIt) {
  Rig r;
  r.imu.connect();
  r.emu.set_stall(40e-6);  // 17 frames × ~42 µs ≈ 0.7 ms > 0.41 ms sample period
  for (int k = 0; k < 100; ++k) ASSERT_TRUE(r.imu.read_sample());
  EXPECT_GT(r.imu.samples_lost(), 50u);
  // Every sample the device produced was either read or counted as lost (±1 for the one in flight).
  const double diff = double(r.emu.samples_produced()) - double(r.imu.samples_read() + r.imu.samples_lost());
  EXPECT_LE(std::abs(diff), 2.0);
}

TEST(Adis16488a, DecRateChangesTheOutputRate) {
  Rig r;
  r.imu.connect();
  r.imu.set_dec_rate(3);
  auto a = r.imu.read_sample();
  auto b = r.imu.read_sample();
  ASSERT_TRUE(a && b);
  EXPECT_NEAR(b->t - a->t, 4 / 2460.0, 1e-12);
  EXPECT_NEAR(b->host_time - a->host_time, 4 / 2460.0, 1e-6);
  EXPECT_THROW(r.imu.set_dec_rate(5000), std::invalid_argument);
}

TEST(Adis16488a, SelfTestPassAndFail) {
  Rig r;
  r.imu.connect();
  auto ok = r.imu.self_test();
  EXPECT_TRUE(ok.passed) << ok.message;
  r.emu.faults().self_test_diag = 0x0001 | 0x0010;
  auto bad = r.imu.self_test();
  EXPECT_FALSE(bad.passed);
  EXPECT_EQ(bad.message, "X gyro self-test failed; Y accelerometer self-test failed");
  EXPECT_EQ(r.emu.busy_violations(), 0u);  // the driver waited the 12 ms
}

TEST(Adis16488a, UserCalQuantisationRoundTripsExactly) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> s16(-3000, 3000);
  std::uniform_int_distribution<std::int32_t> s32(-50'000'000, 50'000'000);
  for (int k = 0; k < 200; ++k) {
    UserCal c;
    for (int i = 0; i < 3; ++i) {
      c.gyro_scale[i] = static_cast<std::int16_t>(s16(rng));
      c.accel_scale[i] = static_cast<std::int16_t>(s16(rng));
      c.gyro_bias[i] = s32(rng);
      c.accel_bias[i] = s32(rng);
    }
    EXPECT_EQ(user_cal_from_errors(errors_from_user_cal(c)), c);
  }
}

TEST(Adis16488a, ResidualModelPredictsTheDeviceOutput) {
  SensorErrors e = draw_random_unit(3);  // bias, scale and skews
  const UserCal c = user_cal_from_errors(e);
  const SensorErrors res = residual_after_user_cal(e, c);
  // Diagonal and bias removed down to quantisation; the skews stay for the host.
  for (int i = 0; i < 3; ++i) {
    EXPECT_LT(std::abs(res.gyro.M(i, i)), 2.0 / 32768);
    EXPECT_LT(std::abs(res.gyro.bias[i]), 1e-7);
    for (int j = 0; j < 3; ++j)
      if (i != j) { EXPECT_NEAR(res.gyro.M(i, j), e.gyro.M(i, j), 0.02 * std::abs(e.gyro.M(i, j)) + 1e-9); }
  }
  Rig r(e);
  r.imu.connect();
  auto before = r.imu.read_sample();
  auto p = r.imu.provision(c);
  EXPECT_TRUE(p.ok) << p.message;
  EXPECT_EQ(p.flash_count_after, p.flash_count_before + 1);
  r.imu.read_sample();
  auto after = r.imu.read_sample();
  ASSERT_TRUE(before && after);
  const Vec3 g_pred = res.gyro.measure(kW), a_pred = res.accel.measure(kF);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(after->gyro[i], g_pred[i], 2 * adis::reg("X_GYRO").scale);
    EXPECT_NEAR(after->accel[i], a_pred[i], 2 * adis::reg("X_ACCL").scale);
    EXPECT_GT(std::abs(before->gyro[i] - after->gyro[i]), 1e-4);  // the output really changed
  }
  EXPECT_EQ(r.emu.busy_violations(), 0u);
}

TEST(Adis16488a, ProvisioningSurvivesPowerCycleOnlyAfterFlashUpdate) {
  Rig r;
  r.imu.connect();
  UserCal c;
  c.gyro_scale = {100, -200, 300};
  c.accel_bias = {-5, 6, -70000};
  r.imu.write_user_cal(c);
  EXPECT_EQ(r.imu.read_user_cal(), c);
  r.emu.power_cycle();
  r.imu.connect();
  EXPECT_EQ(r.imu.read_user_cal(), UserCal{});  // not flashed: lost
  auto p = r.imu.provision(c);
  ASSERT_TRUE(p.ok) << p.message;
  r.emu.power_cycle();
  r.imu.connect();
  EXPECT_EQ(r.imu.read_user_cal(), c);
  // Software reset also restores from flash; factory restore clears the RAM copy.
  r.imu.software_reset();
  EXPECT_EQ(r.imu.read_user_cal(), c);
}

TEST(Adis16488a, FlashFailureIsReported) {
  Rig r;
  r.imu.connect();
  r.emu.faults().flash_update_fails = true;
  UserCal c;
  c.gyro_bias = {1, 2, 3};
  r.imu.write_user_cal(c);
  EXPECT_THROW(r.imu.flash_update(), DeviceError);
}

// An approved set with accel M[0][0] = −0.6 needs X_ACCL_SCALE = (1/0.4 − 1)·2¹⁵ = 49152: beyond the
// register. It used to be clamped to 32767, read back "equal" and reported ok while the unit kept a
// −20 % scale error. Now it is refused, each coefficient named, and nothing reaches the unit.
TEST(Adis16488a, ASetTheRegistersCannotHoldIsRefusedBeforeAnythingIsWritten) {
  SensorErrors e;
  e.accel.M(0, 0) = -0.6;
  e.gyro.M(2, 2) = -1.5;     // 1 + M ≤ 0: no gain cancels it
  e.accel.bias[1] = 3.0e5;   // m/s²: beyond the 32-bit XA_BIAS (±2³¹ · 0.8 mg/2¹⁶ ≈ 2.57e5 m/s²)
  e.gyro.M(0, 0) = -0.4999;  // fits (X_GYRO_SCALE 32755)
  const auto m = user_cal_misfits(e);
  ASSERT_EQ(m.size(), 3u);
  EXPECT_EQ(m[0].coefficient, "gyro M[2][2]");
  EXPECT_EQ(m[0].reg, "Z_GYRO_SCALE");
  EXPECT_TRUE(std::isnan(m[0].needed_lsb));
  EXPECT_EQ(m[1].coefficient, "accel M[0][0]");
  EXPECT_EQ(m[1].reg, "X_ACCL_SCALE");
  EXPECT_DOUBLE_EQ(m[1].value, -0.6);
  EXPECT_NEAR(m[1].needed_lsb, 49152, 1e-6);
  EXPECT_EQ(m[1].reg_min, -32767);
  EXPECT_EQ(m[1].reg_max, 32767);
  EXPECT_NEAR(m[1].min, 1.0 / (1.0 + 32767.5 / 32768) - 1.0, 1e-15);
  EXPECT_EQ(m[1].text(),
            "accel M[0][0] = -0.6: X_ACCL_SCALE would need 49152 LSB, outside -32767..32767; "
            "it holds -0.499996 < accel M[0][0] < 65535");
  EXPECT_EQ(m[2].coefficient, "accel bias[1]");
  EXPECT_EQ(m[2].reg, "YA_BIAS");
  EXPECT_THROW(user_cal_from_errors(e), UserCalRangeError);

  Rig r(e);
  r.imu.connect();
  const auto frames = r.emu.write_frames();
  const ProvisionResult p = r.imu.provision(e);
  EXPECT_FALSE(p.ok);
  EXPECT_FALSE(p.wrote);
  EXPECT_EQ(p.misfits.size(), 3u);
  EXPECT_NE(p.message.find("accel M[0][0] = -0.6: X_ACCL_SCALE would need 49152 LSB"), std::string::npos) << p.message;
  EXPECT_EQ(r.emu.write_frames(), frames);  // not one register write, no flash update
  EXPECT_EQ(r.emu.flash_count(), 0u);
  for (std::uint8_t o = 0x04; o < 0x28; o += 2) EXPECT_EQ(r.emu.peek(2, o), 0) << "page 2 offset " << int(o);
}

TEST(Adis16488a, ScaleRegisterLimitsAreTheRoundedRange) {
  const auto fits = [](double m) {
    SensorErrors e;
    e.gyro.M(1, 1) = m;
    return user_cal_misfits(e).empty();
  };
  EXPECT_TRUE(fits(-0.499995));  // 32767.3 → 32767
  EXPECT_EQ(user_cal_from_errors([] { SensorErrors e; e.gyro.M(1, 1) = -0.499995; return e; }()).gyro_scale[1], 32767);
  EXPECT_FALSE(fits(-0.499997));  // 32767.6 → 32768
  EXPECT_FALSE(fits(-0.5));
  EXPECT_TRUE(fits(65534.0));    // −32767.49999 → −32767
  EXPECT_FALSE(fits(65536.0));   // −32768: a gain of 0
  EXPECT_FALSE(fits(std::numeric_limits<double>::quiet_NaN()));
}

TEST(Adis16488a, ReadBackIsCheckedAgainstTheSetEveryCoefficient) {
  SensorErrors e = draw_random_unit(5);
  e.accel.M(0, 0) = -0.45;
  e.gyro.M(1, 1) = 0.8;
  const UserCal c = user_cal_from_errors(e);
  auto checks = check_user_cal(e, c);
  ASSERT_EQ(checks.size(), 24u);  // 9 M + 3 bias, two triads
  int host = 0;
  for (const auto& k : checks) {
    EXPECT_TRUE(k.ok) << k.text();
    host += k.host_applied;
    if (!k.host_applied) EXPECT_LE(std::abs(k.residual), k.tolerance);
  }
  EXPECT_EQ(host, 12);  // the skews: the host's, not a mismatch
  EXPECT_EQ(checks[12 + 0].coefficient, "accel M[0][0]");
  EXPECT_EQ(checks[12 + 0].reg, "X_ACCL_SCALE");
  EXPECT_NEAR(checks[12 + 0].unit, -0.45, 0.5 / 32768);
  EXPECT_EQ(checks[9].coefficient, "gyro bias[0]");
  EXPECT_EQ(checks[9].reg, "XG_BIAS");

  // The clamped register of the −0.6 set: the unit's correction leaves a −20 % scale error.
  SensorErrors big = e;
  big.accel.M(0, 0) = -0.6;
  UserCal clamped = c;
  clamped.accel_scale[0] = 32767;
  checks = check_user_cal(big, clamped);
  EXPECT_FALSE(checks[12].ok);
  EXPECT_NEAR(checks[12].residual, (1 + 32767.0 / 32768) * 0.4 - 1, 1e-12);
  EXPECT_NEAR(checks[12].unit, 1 / (1 + 32767.0 / 32768) - 1, 1e-12);
  // One LSB off, in any register, is more than the half LSB quantisation allows. (A scale one LSB
  // off may also move the bias the unit applies by more than half an LSB: b·2⁻¹⁵.)
  const std::array<std::pair<int, const char*>, 4> cases = {
      {{0, "gyro M[2][2]"}, {1, "accel M[1][1]"}, {2, "gyro bias[0]"}, {3, "accel bias[2]"}}};
  for (const auto& [which, name] : cases) {
    UserCal off = c;
    if (which == 0) ++off.gyro_scale[2];
    if (which == 1) --off.accel_scale[1];
    if (which == 2) ++off.gyro_bias[0];
    if (which == 3) --off.accel_bias[2];
    std::set<std::string> bad;
    for (const auto& k : check_user_cal(e, off))
      if (!k.ok) bad.insert(k.coefficient);
    EXPECT_TRUE(bad.count(name)) << name;
    EXPECT_LE(bad.size(), which < 2 ? 2u : 1u) << name;
  }
}

// End to end: a unit with known errors (large scale errors, to the register limit), the inverse
// provisioned, samples read: the unit's outputs are the truth up to quantisation, and with skews the
// host's residual (from the registers read back) recovers the truth. Beyond the limit: refused.
TEST(Adis16488a, ProvisionedUnitOutputsTheTruthUpToTheRegisterLimit) {
  const double g_lsb = adis::reg("X_GYRO").scale, a_lsb = adis::reg("X_ACCL").scale;
  for (double big : {-0.4999, -0.3, 0.9, 3.0}) {
    SensorErrors e;
    e.gyro.M.diagonal() = Vec3(big, 2e-3, -0.49);
    e.accel.M.diagonal() = Vec3(-0.2, big, 0.45);
    e.gyro.bias = Vec3(2e-3, -1e-3, 5e-4);
    e.accel.bias = Vec3(0.05, -0.1, 0.2);
    for (bool skews : {false, true}) {
      if (skews) e.gyro.M(0, 1) = e.accel.M(2, 0) = 1e-3;
      Rig r(e);
      r.imu.connect();
      const ProvisionResult p = r.imu.provision(e);
      ASSERT_TRUE(p.ok) << big << ": " << p.message;
      EXPECT_EQ(p.read_back, p.written);
      const SensorErrors host = residual_after_user_cal(e, p.read_back);
      r.imu.read_sample();
      const auto s = r.imu.read_sample();
      ASSERT_TRUE(s);
      const Vec3 g = skews ? host.gyro.correct(s->gyro) : s->gyro;
      const Vec3 a = skews ? host.accel.correct(s->accel) : s->accel;
      for (int i = 0; i < 3; ++i) {
        // Half a SCALE LSB times 1 + M, plus the output and bias quantisation.
        EXPECT_NEAR(g[i], kW[i], 0.5 / 32768 * (1 + std::abs(e.gyro.M(i, i))) * kW.norm() + 4 * g_lsb) << big << " " << i;
        EXPECT_NEAR(a[i], kF[i], 0.5 / 32768 * (1 + std::abs(e.accel.M(i, i))) * kF.norm() + 4 * a_lsb) << big << " " << i;
      }
    }
  }
  // Beyond the register: refused, the unit untouched, its output still carries the error.
  SensorErrors e;
  e.accel.M(0, 0) = -0.6;
  Rig r(e);
  r.imu.connect();
  EXPECT_FALSE(r.imu.provision(e).ok);
  r.imu.read_sample();
  const auto s = r.imu.read_sample();
  ASSERT_TRUE(s);
  EXPECT_NEAR(s->accel[0], 0.4 * kF[0], 2 * a_lsb);
  EXPECT_EQ(r.emu.flash_count(), 0u);
}

// A unit that holds something else than it was sent (here: bit 8 of X_ACCL_SCALE flipped on its way
// in). The provisioning fails and names the coefficients the unit would apply differently.
struct CorruptingBus : SpiBus {
  Adis16488aEmulator& emu;
  int page = -1;
  explicit CorruptingBus(Adis16488aEmulator& e) : emu(e) {}
  std::vector<std::uint16_t> transfer(const std::vector<std::uint16_t>& words) override {
    std::vector<std::uint16_t> w = words;
    for (auto& x : w) {
      if ((x & 0xFF00) == 0x8000) page = x & 0xFF;                                        // PAGE_ID write
      else if (page == 2 && (x & 0xFF00) == (0x8000 | 0x0B << 8)) x = static_cast<std::uint16_t>(x ^ 0x01);  // X_ACCL_SCALE high byte
    }
    return emu.transfer(w);
  }
  bool wait_data_ready(double t) override { return emu.wait_data_ready(t); }
  double now() const override { return emu.now(); }
  void delay(double s) override { emu.delay(s); }
  std::string describe() const override { return "corrupting bus"; }
};

TEST(Adis16488a, ProvisioningFailsWhenTheUnitWouldApplySomethingElse) {
  const SensorErrors e = draw_random_unit(2);
  Rig r(e);
  CorruptingBus bus(r.emu);
  Adis16488a imu(bus);
  imu.connect();
  const ProvisionResult p = imu.provision(e);
  EXPECT_FALSE(p.ok);
  EXPECT_TRUE(p.wrote);
  EXPECT_EQ(p.read_back.accel_scale[0], static_cast<std::int16_t>(p.written.accel_scale[0] ^ 0x100));
  std::set<std::string> bad;
  for (const auto& k : p.checks)
    if (!k.ok) bad.insert(k.coefficient);
  // The scale, and the bias it carries (B was computed for the intended gain).
  EXPECT_EQ(bad, (std::set<std::string>{"accel M[0][0]", "accel bias[0]"}));
  EXPECT_NE(p.message.find("the unit would apply something other than the approved set: accel M[0][0]: the unit's "
                           "X_ACCL_SCALE cancels"),
            std::string::npos)
      << p.message;
}

}  // namespace
