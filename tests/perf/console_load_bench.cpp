// The web console under load (issue 38 item 5): 50 concurrent users browsing a SQLite store of
// 100,000 devices through the real server (`calbench serve`, spawned), timed client-side.
//
// Fixture, once per process: the store is filled through db::Store only (store_bench, set_status,
// add_console_account), several thousand devices per enclosing write transaction (the store's
// nested calls join it). Every device has one bench run with its QC results and one bench set with
// a fit_quality of the factory plan's 38 steps; the newest 300 sets are drafts (the QC queue, one
// in ten with a failing QC result), every 3000th device's set is revoked, the rest are approved by
// one of 50 QC accounts (qc01..qc50, one per user). The filled file is cached in the build folder
// (console_load/, keyed by schema and fixture version and device count), so only the first run
// pays the fill; its time is printed once.
//
// One benchmark run (one iteration): spawn `calbench serve --db FILE --listen 127.0.0.1:PORT`
// (the executable: $CALBENCH, else the one built beside this benchmark), wait until it answers, let
// 50 threads log in (each with its own account: GET /login for the double-submit CSRF token, POST
// /login), wait for all, then each makes kRequests GETs, each after a think time drawn from an
// exponential distribution with the benchmark's argument as its mean (3 s: people browsing, who read
// each page; 0: a closed loop with 50 requests always outstanding, the server's saturation): the queue, device pages of random serials, set pages of random
// sets, audit searches (by serial, or by a QC person's name). Reported: p50/p95/max per page kind
// in ms, the login's (GET + POST), pages/s of the browsing phase, and the server's peak memory
// (VmHWM) and RSS after the run, read from /proc before it is stopped.
//
// CALBENCH_LOAD_DEVICES overrides the device count (a quick trial of the benchmark itself).
#include <benchmark/benchmark.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <barrier>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <random>
#include <thread>

#include "common/coefficients_codec.hpp"
#include "db/console_accounts.hpp"
#include "db/store.hpp"

// Last: httplib.h brings <resolv.h>, whose macro _res breaks Eigen's headers if they come after it.
#include <httplib.h>

extern char** environ;

namespace {
using namespace calbench;
using namespace calbench::db;
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

constexpr int kUsers = 50;
constexpr int kRequests = 12;  // page requests per user and run (after its login)
constexpr int kDrafts = 300;
constexpr int kRevokeEvery = 3000;
constexpr int kFillChunk = 5000;  // devices per enclosing write transaction
constexpr int kFixtureVersion = 2;  // bump when the fill changes (a new cache file); 2: schema 8 with its audit indexes
const char* kPassword = "load-bench-password";

const int kDevices = [] {
  const char* e = std::getenv("CALBENCH_LOAD_DEVICES");
  return e && std::atoi(e) > 0 ? std::atoi(e) : 100000;
}();

std::string serial_of(int i) { return "L" + std::to_string(1000000 + i); }
std::string qc_login(int k) { return (k < 9 ? "qc0" : "qc") + std::to_string(k + 1); }
std::string qc_name(int k) { return "QC Person " + std::to_string(k + 1); }

// A unit's coefficients and its bench fit's quality, inside the default thresholds (the approved
// sets meet them, as they would have had to).
CoefficientSet unit_set(int i, std::mt19937& g) {
  std::normal_distribution<double> n(0, 1);
  CoefficientSet c;
  c.device = {"ADIS16488A", serial_of(i)};
  SensorErrors& e = c.errors;
  for (int a = 0; a < 3; ++a) {
    e.gyro.bias(a) = 3e-4 * n(g);
    e.accel.bias(a) = 0.05 * n(g);
    e.gyro.sigma_bias(a) = 1e-6;
    e.accel.sigma_bias(a) = 1e-4;
    for (int b = 0; b < 3; ++b) {
      e.gyro.M(a, b) = (a == b ? 3e-3 : 3e-4) * n(g);
      e.accel.M(a, b) = (a == b ? 3e-3 : 3e-4) * n(g);
      e.gyro.sigma_M(a, b) = e.accel.sigma_M(a, b) = 2e-5;
    }
  }
  BenchFitQuality q;
  for (int a = 0; a < 3; ++a) q.gyro_chi2_dof(a) = 1 + 0.1 * n(g), q.accel_chi2_dof(a) = 1 + 0.1 * n(g);
  for (int s = 0; s < 38; ++s) {  // bench/plans/factory.toml: 14 static positions, 24 rate steps
    StepMeanResidual r;
    r.step = s;
    r.kind = s < 14 ? kStepStatic : kStepRate;
    for (int a = 0; a < 3; ++a) r.gyro(a) = 1e-5 * n(g), r.accel(a) = 1e-4 * n(g);
    q.steps.push_back(r);
  }
  c.fit_quality = q;
  return c;
}

BenchRunInput unit_run(int i, std::mt19937& g, bool qc_fails) {
  std::normal_distribution<double> n(0, 1);
  BenchRunInput r;
  r.station = "station-" + std::to_string(1 + i % 4);
  r.plan = "factory.toml";
  r.recording_path = "/data/recordings/" + serial_of(i);
  r.recording_sha256 = std::string(64, 'a');
  r.started_at = "2026-11-20T08:00:00Z";
  r.ended_at = "2026-11-20T08:42:00Z";
  r.qc = {QcResult{"samples_lost", qc_fails ? 12.0 : 0.0, 0.0, !qc_fails, "samples", kSampleNotApplicable, "value ≤ threshold"},
          QcResult{"step_repeats", 0, std::nullopt, true, "", kSampleNotApplicable, ""},
          QcResult{"gyro.residual_rms", 1e-5 * (1 + 0.1 * std::abs(n(g))), 1e-4, true, "rad/s", kInSample, "|value| ≤ threshold"},
          QcResult{"accel.residual_rms", 1e-3 * (1 + 0.1 * std::abs(n(g))), 1e-2, true, "m/s²", kInSample, "|value| ≤ threshold"}};
  return r;
}

Actor named(const std::string& user, const std::string& station) {
  Actor a;
  a.user = user;
  a.station = station;
  a.source = "--operator";
  return a;
}

void fill(const fs::path& file) {
  OpenOptions o;
  o.create = true;
  Store st(file.string(), o, named("Operator 1", "station-1"));
  for (int k = 0; k < kUsers; ++k) add_console_account(st, qc_login(k), qc_name(k), "qc", kPassword);
  std::mt19937 g(38);
  for (int base = 0; base < kDevices; base += kFillChunk) {
    st.connection().write_transaction([&] {
      for (int i = base; i < std::min(kDevices, base + kFillChunk); ++i) {
        const bool draft = i >= kDevices - kDrafts;
        const CoefficientSet c = unit_set(i, g);
        const std::string station = "station-" + std::to_string(1 + i % 4);
        st.set_actor(named("Operator " + std::to_string(1 + i % 7), station));
        const StoredSet s = st.store_bench(DeviceInfo{"ADIS16488A", serial_of(i), "1.10"},
                                           unit_run(i, g, draft && i % 10 == 0), coefficients_to_json(c).dump());
        if (draft) continue;
        st.set_actor(named(qc_name(i % kUsers), "qc-desk"));
        st.set_status(s.set_id, SetStatus::approved, "");
        if (i % kRevokeEvery == kRevokeEvery / 2)
          st.set_status(s.set_id, SetStatus::revoked, "gyro bias drift found at the customer");
      }
    });
  }
}

struct Fixture {
  fs::path file, dir;
  double fill_s = 0;
  std::string skip;
  Fixture() {
    // The build folder: this executable is <build>/tests/calbench_perf.
    dir = fs::read_symlink("/proc/self/exe").parent_path().parent_path() / "console_load";
    fs::create_directories(dir);
    file = dir / ("store-schema" + std::to_string(kSchemaVersion) + "-v" + std::to_string(kFixtureVersion) + "-" +
                  std::to_string(kDevices) + ".db");
    if (fs::exists(file)) {
      std::fprintf(stderr, "console_load_bench: cached store %s\n", file.c_str());
      return;
    }
    const fs::path tmp = fs::path(file).concat(".filling");
    for (const char* x : {"", "-wal", "-shm"}) fs::remove(fs::path(tmp).concat(x));
    const auto t0 = Clock::now();
    try {
      fill(tmp);
    } catch (const std::exception& e) {
      skip = std::string("filling the store failed: ") + e.what();
      std::fprintf(stderr, "console_load_bench: %s\n", skip.c_str());
      return;
    }
    fill_s = std::chrono::duration<double>(Clock::now() - t0).count();
    fs::rename(tmp, file);  // the store is closed: its WAL is checkpointed and gone
    std::fprintf(stderr, "console_load_bench: filled %s (%d devices, %d drafts) in %.0f s\n", file.c_str(), kDevices,
                 kDrafts, fill_s);
  }
};
Fixture& fixture() {
  static Fixture f;
  return f;
}

std::string calbench_binary() {
  const char* e = std::getenv("CALBENCH");
  return e && *e ? e : CALBENCH_BINARY;
}

int free_port() {
  const int s = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t len = sizeof a;
  int port = -1;
  if (::bind(s, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0 &&
      ::getsockname(s, reinterpret_cast<sockaddr*>(&a), &len) == 0)
    port = ntohs(a.sin_port);
  ::close(s);
  return port;
}

// kB of a /proc/PID/status field (VmHWM, VmRSS), -1 when unreadable.
long proc_kb(pid_t pid, const std::string& key) {
  std::ifstream f("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(f, line);)
    if (line.rfind(key + ":", 0) == 0) return std::atol(line.c_str() + key.size() + 1);
  return -1;
}

// `calbench serve` on the store, until destroyed (SIGTERM).
struct Server {
  pid_t pid = -1;
  int port = -1;
  std::string error;
  Server(const fs::path& db, const fs::path& log) {
    port = free_port();
    const std::string bin = calbench_binary(), listen = "127.0.0.1:" + std::to_string(port);
    std::vector<std::string> args = {bin, "serve", "--db", db.string(), "--listen", listen};
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&fa, 1, 2);
    const int rc = posix_spawn(&pid, bin.c_str(), &fa, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&fa);
    if (rc != 0) {
      pid = -1;
      error = "cannot start " + bin + " (set CALBENCH to the calbench executable)";
      return;
    }
    httplib::Client cli("127.0.0.1", port);
    for (const auto t0 = Clock::now(); Clock::now() - t0 < std::chrono::seconds(60);) {
      if (auto r = cli.Get("/login"); r && r->status == 200) return;
      int status = 0;
      if (::waitpid(pid, &status, WNOHANG) == pid) {
        pid = -1;
        error = "calbench serve exited at start; see " + log.string();
        return;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    error = "calbench serve did not answer within 60 s; see " + log.string();
  }
  ~Server() {
    if (pid <= 0) return;
    ::kill(pid, SIGTERM);
    int status = 0;
    ::waitpid(pid, &status, 0);
  }
};

enum Kind { kLogin, kQueue, kDevice, kSet, kAudit, kKinds };
const char* kKindNames[kKinds] = {"login", "queue", "device", "set", "audit"};

// The value of cookie `name` in a Set-Cookie header, "" when absent.
std::string set_cookie(const httplib::Result& r, const std::string& name) {
  const std::string v = r->get_header_value("Set-Cookie");
  if (v.rfind(name + "=", 0) != 0) return {};
  return v.substr(name.size() + 1, v.find(';') - name.size() - 1);
}

// Marks the end of the logins: the browsing phase starts when the last user has logged in.
struct StartMark {
  Clock::time_point* at;
  void operator()() noexcept { *at = Clock::now(); }
};
using StartBarrier = std::barrier<StartMark>;

struct UserResult {
  std::vector<double> ms[kKinds];
  std::string error;
};

void user(int u, int port, double think_ms, StartBarrier& start, UserResult& out) {
  httplib::Client cli("127.0.0.1", port);
  cli.set_keep_alive(true);  // as a browser
  cli.set_read_timeout(120, 0);
  const auto ms_since = [](Clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
  };
  std::string session;
  {
    const auto t0 = Clock::now();
    auto form = cli.Get("/login");
    const std::string pre = form && form->status == 200 ? set_cookie(form, "calbench_login") : "";
    if (pre.empty()) {
      out.error = "GET /login: no login cookie";
    } else {
      // The form's token (bound to its cookie by the server) as a browser posts it back.
      const std::string& html = form->body;
      const std::string key = "name=\"csrf\" value=\"";
      const auto at = html.find(key);
      const std::string csrf = at == std::string::npos ? "" : html.substr(at + key.size(), html.find('"', at + key.size()) - at - key.size());
      httplib::Params p{{"csrf", csrf}, {"login", qc_login(u)}, {"password", kPassword}};
      auto r = cli.Post("/login", {{"Cookie", "calbench_login=" + pre}}, p);
      session = r && r->status == 303 ? set_cookie(r, "calbench_session") : "";
      if (session.empty()) out.error = "POST /login as " + qc_login(u) + ": " + (r ? std::to_string(r->status) : "no answer");
    }
    out.ms[kLogin].push_back(ms_since(t0));
  }
  start.arrive_and_wait();  // every user logged in (or failed): the browsing starts together
  if (!out.error.empty()) return;
  const httplib::Headers h{{"Cookie", "calbench_session=" + session}};
  std::mt19937 g(1000 + u);  // the same walk in every run
  std::uniform_int_distribution<int> device(0, kDevices - 1), pick(0, 99);
  std::exponential_distribution<double> think(think_ms > 0 ? 1.0 / think_ms : 1.0);
  for (int k = 0; k < kRequests; ++k) {
    // A person reads the page before the next (exponential think time; 0: no pause, the saturation case).
    if (think_ms > 0) std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(think(g)));
    const int p = pick(g);
    Kind kind;
    std::string path, expect;
    if (p < 20) {
      kind = kQueue, path = "/queue", expect = "id=\"queue\"";
    } else if (p < 55) {
      kind = kDevice, path = "/device/" + serial_of(device(g)), expect = "id=\"report\"";
    } else if (p < 85) {
      kind = kSet, path = "/set/" + std::to_string(1 + device(g)), expect = "id=\"report\"";  // one set per device
    } else {
      kind = kAudit, expect = "id=\"audit\"";
      path = p < 95 ? "/audit?serial=" + serial_of(device(g)) : "/audit?who=QC+Person+" + std::to_string(1 + device(g) % kUsers);
    }
    const auto t0 = Clock::now();
    auto r = cli.Get(path, h);
    out.ms[kind].push_back(ms_since(t0));
    if (!r || r->status != 200 || r->body.find(expect) == std::string::npos) {
      out.error = "GET " + path + ": " + (r ? std::to_string(r->status) : "no answer");
      return;
    }
  }
}

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(q * static_cast<double>(v.size() - 1) + 0.5)];
}

void BM_ConsoleLoad(benchmark::State& state) {
  Fixture& f = fixture();
  if (!f.skip.empty()) {
    state.SkipWithError(f.skip.c_str());
    return;
  }
  for (auto _ : state) {
    Server srv(f.file, f.dir / "serve.log");
    if (!srv.error.empty()) {
      state.SkipWithError(srv.error.c_str());
      return;
    }
    std::vector<UserResult> res(kUsers);
    Clock::time_point browse0;
    StartBarrier start(kUsers, StartMark{&browse0});
    std::vector<std::thread> users;
    const auto t0 = Clock::now();
    const double think_ms = static_cast<double>(state.range(0));
    for (int u = 0; u < kUsers; ++u) users.emplace_back(user, u, srv.port, think_ms, std::ref(start), std::ref(res[u]));
    for (auto& t : users) t.join();
    const auto t1 = Clock::now();
    const double browse_s = std::chrono::duration<double>(t1 - browse0).count();
    state.SetIterationTime(std::chrono::duration<double>(t1 - t0).count());
    state.counters["server_peak_MB"] = static_cast<double>(proc_kb(srv.pid, "VmHWM")) / 1024.0;
    state.counters["server_rss_MB"] = static_cast<double>(proc_kb(srv.pid, "VmRSS")) / 1024.0;
    std::vector<double> all[kKinds];
    std::size_t pages = 0;
    for (const auto& r : res) {
      if (!r.error.empty()) {
        state.SkipWithError(("a user failed: " + r.error).c_str());
        return;
      }
      for (int k = 0; k < kKinds; ++k) all[k].insert(all[k].end(), r.ms[k].begin(), r.ms[k].end());
    }
    for (int k = 0; k < kKinds; ++k) {
      const std::string n = kKindNames[k];
      if (k != kLogin) pages += all[k].size();
      state.counters[n + "_p50_ms"] = quantile(all[k], 0.5);
      state.counters[n + "_p95_ms"] = quantile(all[k], 0.95);
      state.counters[n + "_max_ms"] = quantile(all[k], 1.0);
    }
    state.counters["pages_per_s"] = static_cast<double>(pages) / browse_s;
  }
  state.counters["devices"] = kDevices;
  if (f.fill_s > 0) state.counters["fill_s"] = f.fill_s;  // only in the process that filled the store
  state.SetLabel(std::to_string(kUsers) + " users x " + std::to_string(kRequests) + " pages, " +
                 (state.range(0) > 0 ? "think time " + std::to_string(state.range(0) / 1000.0).substr(0, 3) + " s (mean, exponential)"
                                     : "no think time (saturation)"));
}
// Argument: the users' mean think time in ms. 3000: people browsing (each reads a page for seconds);
// 0: every user requests the next page the moment the last arrives, the server's saturation.
BENCHMARK(BM_ConsoleLoad)->Arg(3000)->Arg(0)->Unit(benchmark::kSecond)->UseManualTime()->Iterations(1);

}  // namespace
