// calbench import kf-gins --imu IMU.txt --truth truth.nav [--gnss GNSS.pos] --out DIR
#include <algorithm>
#include <iostream>

#include "bench/cli/number_options.hpp"
#include "bench/cli/registry.hpp"
#include "bench/drive/import_kfgins.hpp"
#include "bench/multipos/import_csv.hpp"
#include "bench/multipos/import_imutk.hpp"
#include "common/input_error.hpp"

namespace calbench::cli {
namespace {

// The options every multipos importer has (--out, device, rate, gravity or site, --force); finish()
// in the callback checks and copies the site.
struct TargetOptions {
  double gravity = 0, lat = 1000, h = 0;
  CLI::App* app = nullptr;
  void add(CLI::App* a, MultiposTarget& t) {
    app = a;
    a->add_option("--out", t.out, "recording folder to write")->required()
      ->check(non_empty());
    a->add_option("--rate", t.rate_hz, "sample rate, Hz (default: from the median interval)")->check(finite_positive());
    // The serial is required: it keys the unit's coefficient sets in the database ("unknown" would
    // merge every unit's). The model may be left out: a unit of no known class is normal (issue 55).
    const CLI::Validator non_empty(
        [](std::string& v) { return v.find_first_not_of(" \t") == std::string::npos ? std::string("must not be empty") : std::string(); },
        "TEXT");
    a->add_option("--model", t.model, "device model for meta.json (default 'unknown'): a device class name or alias gives "
                                      "fit multipos the class's drift priors and a noise cross-check (docs/in-motion.md, "
                                      "'Device classes'); any other name is fitted without a class, its noise measured")
        ->check(non_empty);
    a->add_option("--serial", t.serial, "device serial for meta.json (keys the unit's coefficient sets in the database)")
        ->required()
        ->check(non_empty);
    a->add_option("--gravity", gravity, "local gravity, m/s² (meta.json gravity_m_s2: overrides the site's normal gravity)")
        ->check(finite_number(9.7, 9.9));
    a->add_option("--site-lat", lat, "site latitude, deg (meta.json site: normal gravity unless --gravity, and the Earth rate)")
        ->check(finite_number(-90, 90));
    a->add_option("--site-h", h, "site height, m (with --site-lat)")->check(finite_number(-1e4, 1e5));
    a->add_flag("--force", t.force, "overwrite an existing recording in --out");
  }
  // After the import: a model no built-in class knows is fine; say what fit multipos will do with it.
  static void note_model(const MultiposTarget& t) {
    if (const std::string n = unknown_model_note(t.model); !n.empty()) std::cerr << "calbench: note: " << n << std::endl;
  }
  void finish(MultiposTarget& t) const {
    if (app->count("--gravity")) t.gravity_m_s2 = gravity;
    if (app->count("--site-lat")) {
      t.lat_deg = lat;
      t.h_m = h;
    } else if (app->count("--site-h")) {
      throw InputError("--site-h", 0, "", "needs --site-lat");
    }
  }
};

const bool registered = add_command(95, [](CLI::App& app) {
  CLI::App* imp = app.add_subcommand("import", "Convert other data formats into the recording interchange format");
  imp->require_subcommand(1);
  auto a = std::make_shared<ImportKfGinsArgs>();
  auto rpy = std::make_shared<std::vector<double>>();
  auto lever = std::make_shared<std::vector<double>>();
  auto* k = imp->add_subcommand("kf-gins", "KF-GINS text files (IMU increments, truth.nav, GNSS .pos) -> drive recording");
  k->add_option("--imu", a->imu, "IMU file: t, dtheta xyz (rad), dvel xyz (m/s)")->required()->check(CLI::ExistingFile);
  k->add_option("--truth", a->truth, "truth.nav: week, t, lat, lon (deg), h, vn, ve, vd, roll, pitch, yaw (deg)")->required()->check(CLI::ExistingFile);
  k->add_option("--gnss", a->gnss, "GNSS .pos: t, lat, lon (deg), h, std n/e/u (m)")->check(CLI::ExistingFile);
  k->add_option("--out", a->out, "recording folder to write")->required()
      ->check(non_empty());
  k->add_option("--rate", a->rate_hz, "IMU rate, Hz (default: from the median interval)")->check(finite_positive());
  k->add_option("--model", a->model, "device model for meta.json");
  k->add_option("--serial", a->serial, "device serial for meta.json");
  k->add_option("--mounting-rpy", *rpy, "nominal mounting roll,pitch,yaw deg (default 0,0,0: IMU = body axes)")
      ->expected(3)
      ->delimiter(',')
      ->check(finite_number(-360, 360));
  k->add_option("--lever-arm", *lever, "IMU origin in reference body axes, m (default 0,0,0)")
      ->expected(3)
      ->delimiter(',')
      ->check(finite_number(-100, 100));
  k->add_option("--ref-sigma-pos", a->ref_sigma_pos_m, "reference position 1-sigma written to reference.csv, m (0.05)")->check(finite_positive());
  k->add_option("--ref-sigma-vel", a->ref_sigma_vel_m_s, "reference velocity 1-sigma, m/s (0.01)")->check(finite_positive());
  k->add_option("--ref-sigma-att", a->ref_sigma_att_deg, "reference attitude 1-sigma, deg (0.01)")->check(finite_positive());
  k->add_flag("--force", a->force, "overwrite an existing recording in --out");
  k->callback([a, rpy, lever] {
    if (rpy->size() == 3) a->mounting_rpy_deg = Vec3((*rpy)[0], (*rpy)[1], (*rpy)[2]);
    if (lever->size() == 3) a->lever_arm_m = Vec3((*lever)[0], (*lever)[1], (*lever)[2]);
    const ImportSummary s = import_kf_gins(*a);
    std::cout << "imported " << s.imu_rows << " IMU rows (" << s.rate_hz << " Hz), " << s.ref_rows << " reference rows, "
              << s.gnss_rows << " GNSS fixes into " << a->out << std::endl;
  });

  // IMU-TK text files -> multipos recording.
  auto t = std::make_shared<ImportImuTkArgs>();
  auto conv = std::make_shared<std::vector<std::vector<double>>>(4);
  auto* it = imp->add_subcommand("imu-tk", "IMU-TK text files (accelerometer and gyro, rows: t x y z) -> multipos recording");
  it->add_option("acc", t->acc, "accelerometer file (t x y z)")->required()->check(CLI::ExistingFile);
  it->add_option("gyro", t->gyro, "gyro file (t x y z, same time stamps)")->required()->check(CLI::ExistingFile);
  static const char* const names[4] = {"--acc-offset", "--acc-scale", "--gyro-offset", "--gyro-scale"};
  static const char* const help[4] = {"accelerometer counts at zero input: one value or x,y,z (default 0: the file is SI)",
                         "accelerometer m/s² per count: one value or x,y,z (default 1)",
                         "gyro counts at zero input: one value or x,y,z (default 0)",
                         "gyro rad/s per count: one value or x,y,z (default 1)"};
  for (int k = 0; k < 4; ++k)
    it->add_option(names[k], (*conv)[k], help[k])->delimiter(',')->expected(1, 3)->check(finite_number(-1e9, 1e9));
  it->add_option("--time-unit", t->time_unit, "unit of the files' time column: s, ms, us or ns (default s)")
      ->check(CLI::IsMember({"s", "ms", "us", "ns"}));
  auto target = std::make_shared<TargetOptions>();
  target->add(it, *t);
  it->callback([t, conv, target] {
    CountsConversion* cc[4] = {&t->acc_counts, &t->acc_counts, &t->gyro_counts, &t->gyro_counts};
    for (int k = 0; k < 4; ++k) {
      const auto& v = (*conv)[k];
      if (v.empty()) continue;
      if (v.size() == 2) throw InputError(names[k], 0, "", "give one value or three (x,y,z), not two");
      const Vec3 x = v.size() == 1 ? Vec3::Constant(v[0]) : Vec3(v[0], v[1], v[2]);
      if (k % 2 == 0) cc[k]->offset = x;
      else {
        if ((x.array() == 0).any()) throw InputError(names[k], 0, "", "a scale of 0 maps every count to zero");
        cc[k]->scale = x;
      }
      cc[k]->given = true;
    }
    target->finish(*t);
    const ImportImuTkSummary s = import_imu_tk(*t);
    std::cout << "imported " << s.rows << " rows (" << s.rate_hz << " Hz) into " << t->out << " (kind multipos)"
              << std::endl;
    TargetOptions::note_model(*t);
  });

  // One CSV with a header line -> multipos recording.
  auto c = std::make_shared<ImportCsvArgs>();
  auto cols = std::make_shared<std::vector<std::vector<std::string>>>(2);
  auto delim = std::make_shared<std::string>("auto");
  auto kind = std::make_shared<std::string>();
  auto* ic = imp->add_subcommand("csv", "one CSV with a header line (time, gyro xyz, accelerometer xyz) -> multipos recording");
  ic->add_option("file", c->file, "the CSV file (a header line naming the columns, '.' decimal point)")
      ->required()
      ->check(CLI::ExistingFile);
  ic->add_option("--kind", *kind, "recording kind to write (multipos)")->required()->check(CLI::IsMember({"multipos"}));
  ic->add_option("--time", c->time_col, "time column: header name or 1-based index (default t)");
  ic->add_option("--gyro", (*cols)[0], "gyro columns x,y,z: header names or 1-based indices (default gx,gy,gz)")
      ->delimiter(',')
      ->expected(3);
  ic->add_option("--accel", (*cols)[1], "accelerometer columns x,y,z: header names or 1-based indices (default ax,ay,az)")
      ->delimiter(',')
      ->expected(3);
  ic->add_option("--gyro-unit", c->gyro_unit, "gyro unit: rad/s, deg/s or mdeg/s (rad, deg, mdeg with --increments; default rad/s)")
      ->check(CLI::IsMember({"rad/s", "deg/s", "mdeg/s"}));
  ic->add_option("--accel-unit", c->accel_unit, "accelerometer unit: m/s2, g or mg (times s with --increments; default m/s2)")
      ->check(CLI::IsMember({"m/s2", "g", "mg"}));
  ic->add_option("--time-unit", c->time_unit, "unit of the time column: s, ms, us or ns (default s)")
      ->check(CLI::IsMember({"s", "ms", "us", "ns"}));
  ic->add_flag("--increments", c->increments, "the gyro and accelerometer columns are increments per sample (angle, velocity), not rates");
  ic->add_option("--delimiter", *delim, "field delimiter: auto (from the header line), comma, semicolon, tab or space (tab and space: runs of blanks)")
      ->check(CLI::IsMember({"auto", "comma", "semicolon", "tab", "space"}));
  auto ctarget = std::make_shared<TargetOptions>();
  ctarget->add(ic, *c);
  ic->callback([c, cols, delim, kind, ctarget] {  // kind: held here, or CLI11 writes into a freed string
    for (int k = 0; k < 2; ++k)
      if ((*cols)[k].size() == 3) std::copy_n((*cols)[k].begin(), 3, (k == 0 ? c->gyro_cols : c->accel_cols).begin());
    c->delimiter = *delim == "comma" ? ',' : *delim == "semicolon" ? ';' : (*delim == "tab" || *delim == "space") ? ' ' : '\0';
    ctarget->finish(*c);
    const ImportCsvSummary s = import_csv(*c);
    const char* dname = s.delimiter == ',' ? "comma" : s.delimiter == ';' ? "semicolon" : "blanks";
    std::cout << "imported " << s.rows << " rows (" << s.rate_hz << " Hz, " << dname << "-separated) into " << c->out
              << " (kind multipos)" << std::endl;
    TargetOptions::note_model(*c);
  });
});

}  // namespace
}  // namespace calbench::cli
