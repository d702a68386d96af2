// Benchmarks of devices/ (issue 3): emulated ADIS16488A acquisition through the SPI word interface
// (every register read is a 16-bit frame through SpiBus::transfer, 17 frames per sample, pipelined),
// with bench physics (table on a rate step, bench_kinematics) and the full error model.
//   BM_Devices_EmulatedAcquisition: samples per second of wall time (items_per_second), and the
//     dropped-sample count seen by the driver (SEQ_CNT) and by the device (latched but unread).
//   BM_Devices_EmulatedHour: a full emulated hour at 2460 Hz (8 856 000 samples), every sample
//     read through the SPI word interface; drops counted by the driver and by the device.
#include <benchmark/benchmark.h>

#include "calibration/bench_kinematics.hpp"
#include "calibration/earth.hpp"
#include "common/units.hpp"
#include "devices/adis16488a.hpp"
#include "devices/adis16488a_emulator.hpp"

namespace calbench {
namespace {
using namespace devices;

struct AcqRig {
  std::shared_ptr<VirtualClock> clock = std::make_shared<VirtualClock>();
  SiteEarth earth{Site{55.75, 37.62, 150}};
  Adis16488aEmulator emu;
  Adis16488a imu;
  AcqRig()
      : emu(clock,
            [this](double t) {
              // Inner axis spinning at 100 °/s about IMU z, outer tilted 30°.
              AxisState outer{30 * units::kDeg, 0, 0};
              AxisState inner{100 * units::kDeg * t, 100 * units::kDeg, 0};
              const auto k = bench_kinematics(earth, outer, inner, 2);
              return EmuTruth{k.w_ib_b, k.f_b};
            },
            draw_random_unit(11), adis16488a_noise()),
        imu(emu) {
    imu.connect();
  }
};

void BM_Devices_EmulatedAcquisition(benchmark::State& state) {
  AcqRig rig;
  std::int64_t n = 0;
  for (auto _ : state) {
    auto s = rig.imu.read_sample();
    benchmark::DoNotOptimize(s);
    ++n;
  }
  state.SetItemsProcessed(n);
  state.counters["frames_per_sample"] = double(rig.emu.frames()) / double(std::max<std::int64_t>(n, 1));
  state.counters["dropped_driver"] = double(rig.imu.samples_lost());
  state.counters["dropped_device"] = double(rig.emu.samples_overwritten());
  state.counters["emulated_s"] = rig.clock->now();
}
BENCHMARK(BM_Devices_EmulatedAcquisition)->Unit(benchmark::kMicrosecond);

void BM_Devices_EmulatedHour(benchmark::State& state) {
  const double emulated_s = 3600.0;
  double lost = 0, overwritten = 0, samples = 0;
  for (auto _ : state) {
    AcqRig rig;
    const double t0 = rig.clock->now();
    while (rig.clock->now() - t0 < emulated_s) {
      auto s = rig.imu.read_sample();
      benchmark::DoNotOptimize(s);
    }
    lost = double(rig.imu.samples_lost());
    overwritten = double(rig.emu.samples_overwritten());
    samples = double(rig.imu.samples_read());
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(samples) * state.iterations());
  state.counters["samples"] = samples;
  state.counters["dropped_driver"] = lost;
  state.counters["dropped_device"] = overwritten;
  state.counters["realtime_factor"] =
      benchmark::Counter(emulated_s, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_Devices_EmulatedHour)->Unit(benchmark::kSecond)->Iterations(1)->Repetitions(1);

}  // namespace
}  // namespace calbench
