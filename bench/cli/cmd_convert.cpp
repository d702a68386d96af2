// calbench convert DIR --to h5|csv [--out NEW_DIR] [--json]
#include <atomic>
#include <csignal>
#include <iostream>
#include <memory>

#include "bench/cli/number_options.hpp"
#include "bench/cli/registry.hpp"
#include "bench/io/convert_recording.hpp"
#include "bench/io/json_util.hpp"

namespace calbench::cli {
namespace {

std::atomic<bool> g_stop{false};
extern "C" void on_convert_signal(int) { g_stop = true; }

struct ConvertArgs {
  std::string dir, to, out;
  bool json = false;
};

const bool registered = add_command(96, [](CLI::App& app) {
  auto a = std::make_shared<ConvertArgs>();
  auto* sub = app.add_subcommand(
      "convert",
      "convert a recording folder between CSV (the interchange form: imu.csv, reference.csv, gnss.csv) and HDF5 "
      "(recording.h5: one dataset per table, docs/recording-hdf5.md); values bit for bit, the new folder appears only "
      "when complete");
  sub->add_option("DIR", a->dir, "recording folder (meta.json and its tables)")->required();
  sub->add_option("--to", a->to, "target form: h5 or csv")->required()->check(CLI::IsMember({"h5", "csv"}));
  sub->add_option("--out", a->out, "new recording folder (must not exist; default: DIR-h5 or DIR-csv beside DIR)")
      ->check(non_empty());
  sub->add_flag("--json", a->json, "machine output");
  sub->callback([a] {
    std::signal(SIGINT, on_convert_signal);
    std::signal(SIGTERM, on_convert_signal);
    const ConvertResult r = convert_recording(a->dir, a->to, a->out, &g_stop);
    if (a->json) {
      nlohmann::json j = {{"out", r.out.string()}, {"from", r.from}, {"to", r.to}, {"tables", nlohmann::json::array()}};
      for (const auto& t : r.tables) j["tables"].push_back({{"name", t.name}, {"rows", t.rows}, {"columns", t.columns}});
      std::cout << j.dump(2) << "\n";
    } else {
      std::cout << "converted " << a->dir << " (" << r.from << ") to " << r.out.string() << " (" << r.to << "):";
      for (const auto& t : r.tables) std::cout << " " << t.name << " " << t.rows << " rows";
      std::cout << "\n";
    }
  });
});

}  // namespace
}  // namespace calbench::cli
