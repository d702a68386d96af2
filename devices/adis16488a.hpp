// ADIS16488A driver over any SpiBus: paging with a cached page, pipelined reads (N registers in
// N+1 frames), 32-bit LOW/OUT pairs, scaling to SI, identity (PROD_ID 0x4068, SERIAL_NUM, FIRM_REV),
// DEC_RATE, SYS_E_FLAG/DIAG_STS decoding, self-test, sample-loss detection, and provisioning of the
// user calibration registers (page 2) with flash update and read-back.
#pragma once
#include <array>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/sensor_model.hpp"
#include "devices/adis16488a_regs.hpp"
#include "devices/spi_bus.hpp"

namespace calbench::devices {

// The unit answered but something about it is wrong (identity, self-test, flash). The message says what.
class DeviceError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct ImuIdentity {
  std::uint16_t prod_id = 0;
  std::uint16_t serial = 0;
  std::uint16_t firm_rev = 0, firm_dm = 0, firm_y = 0;  // BCD
  int dec_rate = 0;
  double output_rate_hz = 0;
  std::string firmware() const;  // "1.10 (2016-06-15)"
  std::string serial_string() const;
};

struct SelfTestResult {
  bool passed = false;
  std::uint16_t diag_sts = 0, sys_e_flag = 0;
  std::string message;  // decoded failures, empty when passed
};

struct ImuSample {
  double t = 0;          // device time, s: first sample 0, then (SEQ_CNT steps)·(DEC_RATE+1)/2460
  double host_time = 0;  // bus clock when it was read
  Vec3 gyro = Vec3::Zero();   // rad/s
  Vec3 accel = Vec3::Zero();  // m/s²
  double temp_c = 0;
  std::uint16_t seq_cnt = 0, sys_e_flag = 0, diag_sts = 0;
  std::uint32_t lost_before = 0;  // samples missed between the previous sample and this one
  bool saturated = false;         // a gyro/accel output at its full-scale limit
  bool error() const { return (sys_e_flag & adis::kSysErrorMask) != 0; }
  std::string error_text() const { return adis::decode_sys_e_flag(sys_e_flag); }
};

// The user calibration registers on page 2, as the device stores them.
// Device model ASSUMED (docs/devices.md "User calibration"): per axis,
//   output = (1 + SCALE/2¹⁵)·raw + BIAS,  BIAS in LSBs of the 32-bit output.
struct UserCal {
  std::array<std::int16_t, 3> gyro_scale{}, accel_scale{};
  std::array<std::int32_t, 3> gyro_bias{}, accel_bias{};
  bool operator==(const UserCal&) const = default;
};

// A coefficient of a set that the user calibration registers cannot hold: its scale register would
// need a value outside −32767..32767 (−32768 is a gain of 0, which cancels nothing), or its bias
// register one outside the 32-bit range. Provisioning refuses such a set before writing anything.
struct RegisterMisfit {
  std::string coefficient;  // "accel M[0][0]", "gyro bias[2]"
  std::string reg;          // "X_ACCL_SCALE", "ZG_BIAS"
  double value = 0;         // the set's coefficient (dimensionless; rad/s; m/s²)
  double needed_lsb = 0;    // the register value it would need (NaN: none, 1 + M_ii ≤ 0 or not finite)
  std::int64_t reg_min = 0, reg_max = 0;  // the register's range, LSB
  double min = 0, max = 0;  // the coefficient's range the register holds (open interval)
  std::string text() const;  // "accel M[0][0] = -0.6: X_ACCL_SCALE would need 49152 LSB, …"
};
// Every coefficient of `e` its registers cannot hold (empty: the set fits).
std::vector<RegisterMisfit> user_cal_misfits(const SensorErrors& e);

class UserCalRangeError : public std::invalid_argument {
 public:
  explicit UserCalRangeError(std::vector<RegisterMisfit> m);
  std::vector<RegisterMisfit> misfits;
};

// Registers that cancel the per-axis part of `e` (diag(M) and b) as closely as quantisation allows.
// The skews (off-diagonal M) cannot be held by the device: see residual_after_user_cal().
// Throws UserCalRangeError (never clamps) when user_cal_misfits(e) is not empty.
UserCal user_cal_from_errors(const SensorErrors& e);
// The diagonal errors those registers cancel exactly (σ = 0). user_cal_from_errors() of the result
// gives back the same registers.
SensorErrors errors_from_user_cal(const UserCal& r);
// What the host must still apply to the device's output when `r` is provisioned into a unit whose
// errors are `e`: M' = D(I+M) − I, b' = D·b + B (D = diag(1 + s)), σ carried over.
SensorErrors residual_after_user_cal(const SensorErrors& e, const UserCal& r);

// One coefficient of an approved set against what a unit holding registers `r` applies.
struct CoefficientCheck {
  std::string coefficient;    // "gyro M[0][0]", "gyro M[0][1]", "accel bias[2]"
  std::string reg;            // the register that holds it; "" for a skew (the host's)
  double approved = 0;        // the set's value (dimensionless; rad/s; m/s²)
  double unit = 0;            // the error the unit's registers cancel, decoded to SI (skews: 0)
  double residual = 0;        // what is left after the unit's correction: residual_after_user_cal(set, r)
  double tolerance = 0;       // half an LSB of the register (plus float rounding); skews: 0
  bool host_applied = false;  // a skew: the part cannot hold it, the host applies `residual`
  bool ok = false;            // |residual| ≤ tolerance; skews: true (not a mismatch)
  std::string text() const;   // why it is not ok
};
// Every coefficient (diagonal, skews, biases of both triads, 24 in all) of `approved` against the
// correction registers `r` (as read back from the unit) apply.
std::vector<CoefficientCheck> check_user_cal(const SensorErrors& approved, const UserCal& r);

struct ProvisionResult {
  bool ok = false;
  bool wrote = false;  // anything was sent to the user calibration registers
  UserCal written, read_back;
  std::uint32_t flash_count_before = 0, flash_count_after = 0;
  std::vector<RegisterMisfit> misfits;   // provision(SensorErrors): why the set was refused
  std::vector<CoefficientCheck> checks;  // provision(SensorErrors): the read-back registers vs the set
  std::string message;
};

struct Adis16488aOptions {
  bool check_prod_id = true;
  bool seq_cnt_loss_detection = true;  // SEQ_CNT steps by 1 per output sample (ASSUMED; see docs)
  double data_ready_timeout_s = 0.1;
};

class Adis16488a {
 public:
  explicit Adis16488a(SpiBus& bus, Adis16488aOptions opt = {});

  // Reads PROD_ID (throws DeviceError unless 0x4068), SERIAL_NUM, FIRM_*, DEC_RATE.
  ImuIdentity connect();
  const ImuIdentity& identity() const { return id_; }

  // Register access (pages switched as needed; the page is cached).
  std::uint16_t read16(const adis::Reg& r);
  std::uint32_t read32(const adis::Reg& r);  // OUT/HIGH word first, then LOW, combined
  // Pipelined read of many words on one page: N requests in N+1 frames.
  std::vector<std::uint16_t> read_words(std::uint8_t page, const std::vector<std::uint8_t>& offsets);
  void write16(const adis::Reg& r, std::uint16_t v);
  void write32(const adis::Reg& r, std::uint32_t v);
  void select_page(std::uint8_t page);
  int cached_page() const { return page_; }
  void invalidate_page() { page_ = -1; }

  void set_dec_rate(int dec_rate);  // 0..2047; output rate 2460/(dec_rate+1) Hz
  SelfTestResult self_test();       // GLOB_CMD bit 1, wait 12 ms, DIAG_STS + SYS_E_FLAG
  void software_reset();            // GLOB_CMD bit 7, wait 120 ms
  void flash_update();              // GLOB_CMD bit 3, wait 375 ms; throws DeviceError on flash failure

  // Wait for data-ready and read one sample (17 frames). nullopt on data-ready timeout.
  std::optional<ImuSample> read_sample();
  std::uint64_t samples_read() const { return samples_; }
  std::uint64_t samples_lost() const { return lost_; }
  std::uint64_t error_samples() const { return errors_; }

  UserCal read_user_cal();
  void write_user_cal(const UserCal& c);
  // Write, flash update, read back and compare; also checks FLSHCNT went up.
  ProvisionResult provision(const UserCal& c);
  // An approved set: refused with nothing written when user_cal_misfits() names anything; else
  // provision(user_cal_from_errors(set)), and ok only when, moreover, check_user_cal(set, read-back)
  // finds every coefficient the unit applies equal to the set's within quantisation.
  ProvisionResult provision(const SensorErrors& approved);

  SpiBus& bus() { return bus_; }

 private:
  void glob_cmd(std::uint16_t bits, double wait_s);
  SpiBus& bus_;
  Adis16488aOptions opt_;
  int page_ = -1;
  ImuIdentity id_;
  double period_ = 1.0 / adis::kInternalRateHz;
  bool have_last_ = false;
  std::uint16_t last_seq_ = 0;
  double t_dev_ = 0, last_host_ = 0;
  std::uint64_t samples_ = 0, lost_ = 0, errors_ = 0;
  std::vector<std::uint8_t> sample_offsets_;
};

}  // namespace calbench::devices
