// Helpers shared by the db tests: temporary databases and coefficient payloads.
#pragma once
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <random>
#include <sstream>
#include <string>

#include "common/sensor_model.hpp"
#include "db/store.hpp"

namespace calbench::db::test {

struct TempDir {
  std::filesystem::path path;
  TempDir() {
    char tmpl[] = "/tmp/calbench_db_test_XXXXXX";
    path = ::mkdtemp(tmpl);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
  std::string db() const { return (path / "test.db").string(); }
};

inline OpenOptions create_opts() {
  OpenOptions o;
  o.create = true;
  return o;
}

// The station's actor (an OS user: records, does not sign) and a QC engineer who signs approvals.
inline Actor test_actor() { return Actor{"tester", "station-T", "OS user", "tester"}; }
inline Actor qc_actor() { return Actor{"qc-anna", "qc-desk", "--operator", "anna"}; }

// A plausible ADIS16488A error set with σ, drawn from `seed`.
inline SensorErrors random_errors(unsigned seed) {
  std::mt19937 g(seed);
  std::normal_distribution<double> n(0, 1);
  SensorErrors e;
  for (int i = 0; i < 3; ++i) {
    e.gyro.bias(i) = 1e-3 * n(g);
    e.accel.bias(i) = 0.1 * n(g);
    e.gyro.sigma_bias(i) = 1e-6;
    e.accel.sigma_bias(i) = 1e-4;
    for (int j = 0; j < 3; ++j) {
      e.gyro.M(i, j) = (i == j ? 3e-3 : 3e-4) * n(g);
      e.accel.M(i, j) = (i == j ? 3e-3 : 3e-4) * n(g);
      e.gyro.sigma_M(i, j) = 2e-5;
      e.accel.sigma_M(i, j) = 2e-5;
    }
  }
  return e;
}

inline std::string payload(const std::string& serial, const SensorErrors& e, const std::string& extra = "") {
  return coefficients_json_text(DeviceInfo{"ADIS16488A", serial, ""}, e, extra);
}

inline BenchRunInput bench_run(bool qc_pass = true) {
  BenchRunInput r;
  r.station = "station-T";
  r.plan = "factory.toml";
  r.recording_path = "/data/rec";
  r.recording_sha256 = std::string(64, 'a');
  r.started_at = "2026-11-22T01:00:00Z";
  r.ended_at = "2026-11-22T01:40:00Z";
  r.qc = {QcResult{"gyro.residual_rms", 1e-5, 1e-4, qc_pass, "rad/s", kInSample, "|value| ≤ threshold"}};
  return r;
}

}  // namespace calbench::db::test
