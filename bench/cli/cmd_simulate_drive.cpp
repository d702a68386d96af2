// calbench simulate drive --route ROUTE --truth TRUTH.json|random --out DIR [--seed N] [--units N]
#include <iostream>

#include "bench/cli/number_options.hpp"
#include "bench/cli/registry.hpp"
#include "bench/drive/simulate_drive.hpp"

namespace calbench::cli {
namespace {

const bool registered = add_command(11, [](CLI::App& app) {
  CLI::App* sim = app.get_subcommand("simulate");
  auto a = std::make_shared<SimulateDriveArgs>();
  auto* d = sim->add_subcommand("drive", "Simulate a land-vehicle drive: MEMS IMU (ADIS16488A errors, 2460 Hz), "
                                         "FOG-grade reference INS/GNSS, GNSS fixes, with mounting and lever arm");
  d->add_option("--route", a->route, "route file (TOML), e.g. bench/routes/default.toml")->required()->check(CLI::ExistingFile);
  d->add_option("--truth", a->truth, "coefficients.json of the simulated unit (optional key \"mounting\"), or 'random'")->required();
  d->add_option("--out", a->out, "recording folder to write (meta.json, imu.csv, reference.csv, gnss.csv, truth.json)")->required()
      ->check(non_empty());
  d->add_option("--seed", a->seed, "random seed (noise, drift, and the unit and mounting for --truth random)")
      ->check(whole_number(0, std::numeric_limits<std::uint64_t>::max()));
  d->add_option("--serial", a->serial, "device serial to write (default: from the truth, or SIM-<seed>)");
  d->add_option("--until", a->until_s, "simulate only the first SECONDS of the route")->check(finite_positive());
  d->add_flag("--force", a->force, "overwrite an existing recording in --out");
  d->add_option("--inject", a->inject,
                "inject a catalogue effect into the MEMS output, SI units, repeatable (docs/diagnosis.md): e.g. "
                "g_sensitivity:axis=x,f=y,value=1.6e-5, time_offset:value=0.002, lever_arm:x=0.05");
  d->add_option("--effects", a->effects, "JSON file with catalogue keys (as in IMPROVED.json) to inject")
      ->check(CLI::ExistingFile);
  d->add_option("--noise", a->noise,
                "JSON with the unit's in-run drift instead of the data sheet's: {\"gyro\": {\"drift_sigma_deg_h\", "
                "\"drift_tau_s\"}, \"accel\": {\"drift_sigma_mg\", \"drift_tau_s\"}} (kept in truth.json)")
      ->check(CLI::ExistingFile);
  d->add_option("--device-class", a->device_class,
                 "the simulated unit's IMU class: a class file (bench/imu_classes/<name>.toml) or the name or alias of a "
                 "built-in class; its white noise, in-run drift, ranges and LSB, and with --truth random its data-sheet "
                 "spread; meta.json device.model names it (default ADIS16488A)")
      ->check(non_empty());
  d->add_option("--units", a->units,
                 "several MEMS units on the vehicle against one reference: unit k (1..N) with errors and mounting "
                 "from --seed + k-1, turned 90° in yaw from the last, 0.15 m round the route's lever arm; writes "
                 "units.json, reference.csv once and one recording folder per unit (docs/recording-units.md)")
      ->check(whole_number(1, 16));
  d->add_option("--logger-read-hz", a->logger_read_hz,
                 "a logger polling the IMU: it reads R times per second (each interval within +-30 %) and stamps each "
                 "row with its read time; reads faster than the sensor repeat samples (real loggers do; the fit "
                 "measures it, fit drive --sample-time). Default: rows at the sensor's own instants")
      ->check(finite_positive());
  d->add_flag("--gnss-velocity-from-positions", a->gnss_velocity_from_positions,
              "the receiver's velocity is the difference of consecutive fix positions (it lags its stamp by half a fix "
              "interval; sigma that of the difference), as some receivers give it (fit drive --gnss-vel-latency)");
  d->callback([a] {
    const SimulateDriveSummary s = simulate_drive_recording(*a);
    if (a->units > 1)
      std::cout << "simulated " << a->units << " units × " << s.imu_rows << " IMU samples (" << s.duration_s << " s), "
                << s.ref_rows << " reference epochs, " << s.gnss_rows << " GNSS fixes into " << a->out << " (units.json; "
                << a->out << "/1 .. " << a->out << "/" << a->units << ", truth in each truth.json)" << std::endl;
    else
      std::cout << "simulated " << s.imu_rows << " IMU samples (" << s.duration_s << " s), " << s.ref_rows
                << " reference epochs, " << s.gnss_rows << " GNSS fixes into " << a->out << " (truth in " << a->out
                << "/truth.json)" << std::endl;
  });
});

}  // namespace
}  // namespace calbench::cli
