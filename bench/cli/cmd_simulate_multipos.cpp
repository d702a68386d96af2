// calbench simulate multipos --out DIR [--seed N] [--device-class NAME|FILE] [--model TEXT] [--serial S]
//   [--poses N] [--still MIN,MAX] [--opening-still S] [--noise-factor K] [--rate HZ] [--site-lat DEG] [--force]
#include <iostream>

#include "bench/cli/number_options.hpp"
#include "bench/cli/registry.hpp"
#include "bench/multipos/multipos_import.hpp"
#include "bench/multipos/simulate_multipos.hpp"

namespace calbench::cli {
namespace {

const bool registered = add_command(12, [](CLI::App& app) {
  CLI::App* sim = app.get_subcommand("simulate");
  auto a = std::make_shared<SimulateMultiposArgs>();
  auto lat = std::make_shared<double>(0.0);
  auto* m = sim->add_subcommand("multipos", "Simulate a unit turned by hand through static poses (kind multipos, for fit "
                                            "multipos): the device class's unit spread and noise, the truth in truth.json");
  m->add_option("--out", a->out, "recording folder to write (meta.json, imu.csv, and truth.json beside them)")->required()
      ->check(non_empty());
  m->add_option("--seed", a->seed, "random seed (the unit's errors, the poses and turns, the noise)")
      ->check(whole_number(0, std::numeric_limits<std::uint64_t>::max()));
  m->add_option("--device-class", a->device_class,
                "the simulated unit's IMU class: a class file (bench/imu_classes/<name>.toml) or the name or alias of a "
                "built-in class; its unit spread (bias, scale, skew), white noise and bias drift (default ICM-42688-P, "
                "consumer MEMS)")
      ->check(non_empty());
  m->add_option("--model", a->model,
                "device model written to meta.json (default: the class's name; any text, e.g. 'unknown' for a unit of no "
                "known class: fit multipos then measures its noise and takes wide drift priors)")
      ->check(non_empty());
  m->add_option("--serial", a->serial, "device serial written to meta.json (default SIM-<seed>)")->check(non_empty());
  m->add_option("--poses", a->poses, "static poses, the opening one included (default 24)")->check(whole_number(2, 1000));
  m->add_option("--still", a->still,
                "MIN,MAX: seconds each pose is held still, drawn uniformly (default 1,3: short hand-held poses)");
  m->add_option("--opening-still", a->opening_still_s,
                "seconds of the first pose, an opening static interval (default 0: the first pose is as short as the "
                "others; real recordings may have one or not)")
      ->check(finite_number(0, 3600));
  m->add_option("--noise-factor", a->noise_factor,
                "white noise = K x the class's densities (ARW, VRW) (default 1; 0: bias drift only)")
      ->check(finite_number(0, 1000));
  m->add_option("--rate", a->rate_hz, "sample rate, Hz (default 100)")->check(finite_number(10, 50000));
  m->add_option("--site-lat", *lat,
                "site latitude, deg: meta.json site, WGS-84 normal gravity and the Earth's rate in the data (default: "
                "no site, standard gravity 9.80665 m/s², no Earth rate)")
      ->check(finite_number(-90, 90));
  m->add_flag("--force", a->force, "overwrite an existing recording in --out");
  m->callback([a, lat, m] {
    if (m->count("--site-lat")) a->site_lat_deg = *lat;
    const SimulateMultiposSummary s = simulate_multipos_recording(*a);
    std::cout << "simulated " << s.poses << " static poses (" << s.poses - 1 << " turns), " << s.samples << " samples ("
              << s.duration_s << " s at " << s.rate_hz << " Hz) of one " << s.device_class << " unit into " << s.out
              << " (truth in " << s.truth << ")" << std::endl;
    if (const std::string n = unknown_model_note(s.model); !n.empty()) std::cerr << "calbench: note: " << n << std::endl;
  });
});

}  // namespace
}  // namespace calbench::cli
