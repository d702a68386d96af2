// Coefficient database at fleet scale: 10,000 devices × 5 versions (50,000 sets, 1.2 M indexed
// coefficients), built once in a temporary folder. Times: storing one set (one durable
// transaction: WAL, synchronous=FULL), looking a set up by id, the newest approved set of a
// device by serial, and the fleet view.
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <filesystem>
#include <random>

#include "db/store.hpp"

namespace {
using namespace calbench;
using namespace calbench::db;

constexpr int kDevices = 10000, kVersions = 5;

std::string serial_of(int i) { return std::string("P").append(std::to_string(100000 + i)); }

SensorErrors errors(std::mt19937& g) {
  std::normal_distribution<double> n(0, 1);
  SensorErrors e;
  for (int i = 0; i < 3; ++i) {
    e.gyro.bias(i) = 1e-3 * n(g);
    e.accel.bias(i) = 0.1 * n(g);
    e.gyro.sigma_bias(i) = 1e-6;
    e.accel.sigma_bias(i) = 1e-4;
    for (int j = 0; j < 3; ++j) {
      e.gyro.M(i, j) = 1e-3 * n(g);
      e.accel.M(i, j) = 1e-3 * n(g);
      e.gyro.sigma_M(i, j) = e.accel.sigma_M(i, j) = 2e-5;
    }
  }
  return e;
}

struct FleetDb {
  std::filesystem::path dir;
  std::unique_ptr<Store> store;
  std::int64_t max_set = 0;
  FleetDb() {
    char tmpl[] = "/tmp/calbench_db_bench_XXXXXX";
    dir = ::mkdtemp(tmpl);
    OpenOptions o;
    o.create = true;
    store = std::make_unique<Store>((dir / "fleet.db").string(), o, Actor{"bench", "perf"});
    std::mt19937 g(1);
    // One transaction for the bulk load (the timed stores below are one transaction each).
    store->connection().write_transaction([&] {
      for (int v = 0; v < kVersions; ++v)
        for (int d = 0; d < kDevices; ++d) {
          const DeviceInfo dev{"ADIS16488A", serial_of(d), "1.10"};
          const auto s = store->store_set(dev, SetSource::bench, coefficients_json_text(dev, errors(g)));
          if (v < kVersions - 1) store->set_status(s.set_id, SetStatus::approved, "bulk");
          max_set = s.set_id;
        }
    });
  }
  ~FleetDb() {
    store.reset();
    std::error_code ec;
    std::filesystem::remove_all(dir, ec);
  }
};

FleetDb& fleet() {
  static FleetDb f;
  return f;
}

void BM_Db_StoreSet(benchmark::State& state) {
  auto& f = fleet();
  std::mt19937 g(2);
  for (auto _ : state) {
    const DeviceInfo dev{"ADIS16488A", serial_of(static_cast<int>(g() % kDevices)), ""};
    benchmark::DoNotOptimize(f.store->store_set(dev, SetSource::bench, coefficients_json_text(dev, errors(g))));
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_Db_StoreSet)->Unit(benchmark::kMillisecond);

void BM_Db_GetSetById(benchmark::State& state) {
  auto& f = fleet();
  std::mt19937 g(3);
  for (auto _ : state) benchmark::DoNotOptimize(f.store->get_set(1 + static_cast<std::int64_t>(g() % f.max_set)));
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_Db_GetSetById)->Unit(benchmark::kMicrosecond);

void BM_Db_LatestApprovedBySerial(benchmark::State& state) {
  auto& f = fleet();
  std::mt19937 g(4);
  for (auto _ : state) {
    const auto d = f.store->find_device(serial_of(static_cast<int>(g() % kDevices)));
    benchmark::DoNotOptimize(f.store->latest_set(d->id, SetStatus::approved));
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_Db_LatestApprovedBySerial)->Unit(benchmark::kMicrosecond);

void BM_Db_FleetView(benchmark::State& state) {
  auto& f = fleet();
  for (auto _ : state) benchmark::DoNotOptimize(f.store->fleet());
}
BENCHMARK(BM_Db_FleetView)->Unit(benchmark::kMillisecond)->Iterations(3);

}  // namespace
