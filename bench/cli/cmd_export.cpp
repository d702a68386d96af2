// calbench export kf-gins DIR --out FOLDER [--start T]: a drive recording into KF-GINS's text files
// and a starter configuration (bench/drive/export_kfgins.hpp), to run the peer on the same data.
#include <iostream>

#include "bench/cli/number_options.hpp"
#include "bench/cli/registry.hpp"
#include "bench/drive/export_kfgins.hpp"

namespace calbench::cli {
namespace {

const bool registered = add_command(97, [](CLI::App& app) {
  CLI::App* exp = app.add_subcommand("export", "Convert a recording into other programs' data formats");
  exp->require_subcommand(1);
  auto a = std::make_shared<ExportKfGinsArgs>();
  auto* k = exp->add_subcommand("kf-gins",
                                "drive recording -> KF-GINS text files (imu.txt increments in the forward-right-down IMU frame "
                                "through the nominal mounting, gnss.pos, truth.nav) and a starter kf-gins.yaml");
  k->add_option("dir", a->dir, "drive recording folder (meta.json, imu.csv, gnss.csv, optional reference.csv)")
      ->required()
      ->check(CLI::ExistingDirectory);
  k->add_option("--out", a->out, "folder to write (imu.txt, gnss.pos, truth.nav, kf-gins.yaml; KF-GINS writes its results there)")
      ->required()
      ->check(non_empty());
  k->add_option("--start", a->start_s,
                "start time of KF-GINS, s on the recording clock: its initial state is the first reference epoch (else fix) "
                "at or after it (default: the first IMU sample)")
      ->check(finite_number(0, 1e9));
  k->add_option("--standstill", a->standstill_s,
                "the first SECONDS after the start are a standstill: KF-GINS's initial gyro bias is their mean rate less "
                "the Earth rate (default 0: bias 0 with the raw-data prior 0.5 deg/s)")
      ->check(finite_positive());
  k->add_flag("--force", a->force, "overwrite an earlier export in --out");
  k->callback([a] {
    const ExportSummary s = export_kf_gins(*a);
    std::cout << "exported " << s.imu_rows << " IMU rows, " << s.gnss_rows << " GNSS fixes, " << s.truth_rows
              << " reference rows into " << a->out << "; KF-GINS starts at " << s.start_s << " s from the "
              << (s.init_from_reference ? "reference" : "first fix");
    if (a->standstill_s > 0)
      std::cout << ", initial gyro bias " << s.gyro_bias_dph(0) << ", " << s.gyro_bias_dph(1) << ", " << s.gyro_bias_dph(2)
                << " deg/h from the standstill";
    std::cout << " (run: KF-GINS " << a->out << "/kf-gins.yaml)"
              << std::endl;
  });
});

}  // namespace
}  // namespace calbench::cli
