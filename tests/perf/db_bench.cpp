// Coefficient database at fleet scale, SQLite and PostgreSQL side by side: 100,000 devices × 5
// versions (500,000 sets, 12 M indexed coefficients, 1 M audit entries) per backend, built once
// in a temporary folder (PostgreSQL: a throw-away server started with tests/support/pg_server.sh;
// its rows are skipped with a message when PostgreSQL is not installed).
//
// The fill is bulk SQL through the store's own connection, in one transaction per backend
// (INSERT … SELECT of generated rows: the same tables, payload texts of real size, audit entries);
// PostgreSQL then gets the VACUUM ANALYZE its autovacuum would run. Every timed operation goes
// through db::Store: storing one set (one durable transaction: SQLite WAL with synchronous=FULL,
// PostgreSQL SERIALIZABLE with fsync on), a set by id, the newest approved / newest set of a
// device by serial, and the fleet view.
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <random>

#include "db/schema.hpp"
#include "db/store.hpp"
#include "tests/support/pg_server.hpp"

namespace {
using namespace calbench;
using namespace calbench::db;

constexpr int kVersions = 5, kPayloads = 100;
// 100,000 devices; CALBENCH_DB_BENCH_DEVICES overrides (a quick trial of the benchmark itself).
const int kDevices = [] {
  const char* e = std::getenv("CALBENCH_DB_BENCH_DEVICES");
  return e && std::atoi(e) > 0 ? std::atoi(e) : 100000;
}();

enum class Backend { sqlite, postgres };

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

// devices, then kVersions sets per device (set ids version by version; all but the newest approved),
// 24 values per set, and the audit entries the store would have written — all in one transaction.
void bulk_fill(Connection& c) {
  const std::string now = c.now_sql();
  const bool pg = c.dialect() == Dialect::postgres;
  c.write_transaction([&] {
    c.exec("CREATE TEMP TABLE bench_payloads(k INTEGER PRIMARY KEY, payload TEXT NOT NULL)");
    c.exec("CREATE TEMP TABLE bench_names(name TEXT NOT NULL)");
    std::mt19937 g(1);
    auto p = c.prepare("INSERT INTO bench_payloads(k, payload) VALUES (?, ?)");
    for (int k = 0; k < kPayloads; ++k) {
      const DeviceInfo dev{"ADIS16488A", serial_of(k), "1.10"};
      p.reset();
      p.bind(1, k).bind(2, coefficients_json_text(dev, errors(g))).run();
    }
    auto n = c.prepare("INSERT INTO bench_names(name) VALUES (?)");
    for (const auto& name : coefficient_names()) {
      n.reset();
      n.bind(1, name).run();
    }
    auto dev = c.prepare("WITH RECURSIVE g(x) AS (SELECT 0 UNION ALL SELECT x + 1 FROM g WHERE x < ?) "
                         "INSERT INTO devices(model, serial, firmware, created_at) "
                         "SELECT 'ADIS16488A', 'P' || CAST(100000 + x AS TEXT), '1.10', " + now + " FROM g");
    dev.bind(1, kDevices - 1).run();
    c.prepare("INSERT INTO audit_log(at, \"user\", station, entity, entity_id, device_id, action, detail) "
              "SELECT " + now + ", 'bench', 'perf', 'device', id, id, 'create', model || ' ' || serial FROM devices")
        .run();
    for (int v = 1; v <= kVersions; ++v) {
      auto s = c.prepare("INSERT INTO coefficient_sets(device_id, version, source, payload_json, status, created_at, "
                         "created_by, uid) SELECT d.id, ?, 'bench', p.payload, 'draft', " + now +
                         ", 'bench@perf', d.serial || '/' || CAST(? AS TEXT) FROM devices d "
                         "JOIN bench_payloads p ON p.k = d.id % 100 ORDER BY d.id");
      s.bind(1, v).bind(2, std::to_string(v)).run();
    }
    c.prepare(std::string("INSERT INTO coefficient_values(set_id, name, value, sigma) SELECT s.id, n.name, ") +
              (pg ? "(random() - 0.5) * 2e-3" : "(random() % 1000000) * 1e-9") +
              ", 2e-5 FROM coefficient_sets s CROSS JOIN bench_names n ORDER BY s.id, n.name")
        .run();
    c.prepare("INSERT INTO audit_log(at, \"user\", station, entity, entity_id, device_id, action, detail) "
              "SELECT " + now + ", 'bench', 'perf', 'coefficient_set', id, device_id, 'create', "
              "'version ' || CAST(version AS TEXT) || ', source bench, status draft' FROM coefficient_sets")
        .run();
    // The bulk approval by SQL (its audit rows first), with the rule that a status changes only with
    // its signed row (and, on PostgreSQL, only inside the server's functions) lifted for this
    // fixture alone.
    auto aa = c.prepare("INSERT INTO audit_log(at, \"user\", station, entity, entity_id, device_id, action, detail) "
                        "SELECT " + now + ", 'bench', 'perf', 'coefficient_set', id, device_id, 'status', "
                        "'draft -> approved: bulk' FROM coefficient_sets WHERE version < ?");
    aa.bind(1, kVersions).run();
    if (pg) c.exec("SET CONSTRAINTS ALL IMMEDIATE");  // its audit check runs now, not at commit
    c.exec(pg ? "ALTER TABLE coefficient_sets DISABLE TRIGGER coefficient_sets_update"
              : "DROP TRIGGER coefficient_sets_approval_signed");
    auto a = c.prepare("UPDATE coefficient_sets SET status = 'approved' WHERE version < ?");
    a.bind(1, kVersions).run();
    c.exec(pg ? "ALTER TABLE coefficient_sets ENABLE TRIGGER coefficient_sets_update" : schema9_approval_signed_trigger());
    c.exec("DROP TABLE bench_payloads");
    c.exec("DROP TABLE bench_names");
  });
  if (pg) c.exec("VACUUM ANALYZE");
}

struct FleetDb {
  std::filesystem::path dir;
  std::unique_ptr<test::PgServer> pg;
  std::unique_ptr<Store> store;
  std::string skip;  // why this backend is not measured
  std::int64_t max_set = 0;
  double fill_s = 0;
  explicit FleetDb(Backend b) {
    char tmpl[] = "/tmp/calbench_db_bench_XXXXXX";
    dir = ::mkdtemp(tmpl);
    std::string target;
    OpenOptions o;
    if (b == Backend::postgres) {
      pg = std::make_unique<test::PgServer>((dir / "pg").string());
      if (!pg->available()) {
        skip = "PostgreSQL rows skipped: " + pg->why();
        std::fprintf(stderr, "db_bench: %s\n", skip.c_str());
        return;
      }
      pg->create_database();
      target = pg->uri();
    } else {
      o.create = true;
      target = (dir / "fleet.db").string();
    }
    store = std::make_unique<Store>(target, o, Actor{"bench", "perf"});
    const auto t0 = std::chrono::steady_clock::now();
    bulk_fill(store->connection());
    fill_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    max_set = store->count("coefficient_sets");
    std::fprintf(stderr, "db_bench: %s filled with %lld sets, %lld values in %.0f s\n",
                 b == Backend::postgres ? "PostgreSQL" : "SQLite", static_cast<long long>(max_set),
                 static_cast<long long>(store->count("coefficient_values")), fill_s);
  }
  ~FleetDb() {
    store.reset();
    pg.reset();  // stops the server
    std::error_code ec;
    std::filesystem::remove_all(dir, ec);
  }
};

FleetDb& fleet(Backend b) {
  if (b == Backend::postgres) {
    static FleetDb pg(Backend::postgres);
    return pg;
  }
  static FleetDb lite(Backend::sqlite);
  return lite;
}

// The backend's database, or nullptr after SkipWithError.
FleetDb* ready(benchmark::State& state, Backend b) {
  auto& f = fleet(b);
  if (!f.store) {
    state.SkipWithError(f.skip.c_str());
    return nullptr;
  }
  return &f;
}

void BM_Db_StoreSet(benchmark::State& state, Backend b) {
  auto* f = ready(state, b);
  if (!f) return;
  std::mt19937 g(2);
  for (auto _ : state) {
    const DeviceInfo dev{"ADIS16488A", serial_of(static_cast<int>(g() % kDevices)), ""};
    benchmark::DoNotOptimize(f->store->store_set(dev, SetSource::bench, coefficients_json_text(dev, errors(g))));
  }
  state.SetItemsProcessed(state.iterations());
  state.counters["fill_s"] = f->fill_s;
}
BENCHMARK_CAPTURE(BM_Db_StoreSet, sqlite, Backend::sqlite)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_Db_StoreSet, postgres, Backend::postgres)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_Db_GetSetById(benchmark::State& state, Backend b) {
  auto* f = ready(state, b);
  if (!f) return;
  std::mt19937 g(3);
  for (auto _ : state) benchmark::DoNotOptimize(f->store->get_set(1 + static_cast<std::int64_t>(g() % f->max_set)));
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK_CAPTURE(BM_Db_GetSetById, sqlite, Backend::sqlite)->Unit(benchmark::kMicrosecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_Db_GetSetById, postgres, Backend::postgres)->Unit(benchmark::kMicrosecond)->UseRealTime();

// Device by serial, then its newest set with the given status (approved) or of any status.
void latest_by_serial(benchmark::State& state, Backend b, std::optional<SetStatus> status, unsigned seed) {
  auto* f = ready(state, b);
  if (!f) return;
  std::mt19937 g(seed);
  for (auto _ : state) {
    const auto d = f->store->find_device(serial_of(static_cast<int>(g() % kDevices)));
    benchmark::DoNotOptimize(f->store->latest_set(d->id, status));
  }
  state.SetItemsProcessed(state.iterations());
}
void BM_Db_LatestApprovedBySerial(benchmark::State& state, Backend b) {
  latest_by_serial(state, b, SetStatus::approved, 4);
}
BENCHMARK_CAPTURE(BM_Db_LatestApprovedBySerial, sqlite, Backend::sqlite)->Unit(benchmark::kMicrosecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_Db_LatestApprovedBySerial, postgres, Backend::postgres)->Unit(benchmark::kMicrosecond)->UseRealTime();
void BM_Db_LatestBySerial(benchmark::State& state, Backend b) { latest_by_serial(state, b, std::nullopt, 5); }
BENCHMARK_CAPTURE(BM_Db_LatestBySerial, sqlite, Backend::sqlite)->Unit(benchmark::kMicrosecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_Db_LatestBySerial, postgres, Backend::postgres)->Unit(benchmark::kMicrosecond)->UseRealTime();

void BM_Db_FleetView(benchmark::State& state, Backend b) {
  auto* f = ready(state, b);
  if (!f) return;
  std::size_t rows = 0;
  for (auto _ : state) {
    auto v = f->store->fleet();
    rows = v.size();
    benchmark::DoNotOptimize(v);
  }
  state.counters["values"] = static_cast<double>(rows);
}
BENCHMARK_CAPTURE(BM_Db_FleetView, sqlite, Backend::sqlite)->Unit(benchmark::kMillisecond)->Iterations(1)->UseRealTime();
BENCHMARK_CAPTURE(BM_Db_FleetView, postgres, Backend::postgres)->Unit(benchmark::kMillisecond)->Iterations(1)->UseRealTime();

}  // namespace
