// calbench qc DIR --coeffs A.json [--coeffs B.json ...|none] [--from T0] [--horizon S] [--json] [--plot OUT.png]
//              [--outages 15,30,60 --outage-count N --outage-gap S]   (GNSS-only recordings: outage QC)
#include <algorithm>
#include <iomanip>
#include <iostream>

#include "bench/cli/number_options.hpp"
#include "bench/cli/registry.hpp"
#include "bench/io/hdf5_recording.hpp"
#include "bench/io/recording.hpp"
#include "bench/cli/outage_options.hpp"
#include "bench/drive/fit_drive.hpp"
#include "bench/drive/qc_drive.hpp"
#include "bench/drive/recording_scan.hpp"
#include "common/input_error.hpp"
#include "calibration/effects/effect_compensation.hpp"

namespace calbench::cli {
namespace {

struct QcArgs {
  std::string dir, plot;
  std::vector<std::string> coeffs;
  double from = std::numeric_limits<double>::quiet_NaN();
  double horizon = 600;
  bool horizon_given = false;
  bool json = false;
  OutageArgs outage;
  OutageOptions outages;
};

// Outage QC (docs/in-motion.md, "Outage QC"): the aided filter is fit drive's GNSS filter with the
// first --coeffs set as its input (none: raw data, data-sheet priors), over the whole recording.
void run_outages(const QcArgs& a, const std::vector<QcSet>& sets, std::optional<double> from, const std::string& sample) {
  OutageOptions o = a.outages;
  outage_options(a.outage, o);
  if (!o.enabled) throw InputError("--outages", 0, "", "none: nothing to do (the recording has no reference.csv)");
  if (!recording_has_table(a.dir, "gnss"))
    throw InputError((fs::path(a.dir) / "gnss.csv").string(), 0, "", "the outage QC needs gnss.csv in the recording (no such file)");
  if (!a.plot.empty())
    throw InputError("--plot", 0, "", "not available with the outage QC (the device report plots the outage errors)");
  if (a.horizon_given)
    throw InputError("--horizon", 0, "", "not used by the outage QC (its lengths are --outages)");
  if (from) o.request.earliest_s = *from;
  FitDriveArgs f;
  f.dir = a.dir;
  f.aiding = "gnss";
  f.obs_given = false;
  f.qc = false;
  f.write_out = false;
  f.coeffs = a.coeffs.front() == "none" ? std::string() : a.coeffs.front();
  OutageRecorder rec;
  f.on_epoch = [&rec](const inmotion::InMotionFilter& g, const inmotion::RefObs& r, bool took) { rec.epoch(g, r, took); };
  const DriveResult fitted = fit_drive(f);
  // The outages navigate the rows as the aided filter read them (the logger's correction, if any).
  if (fitted.extra.contains("sample_timing")) o.logger = applied_logger_correction(fitted.extra["sample_timing"]);
  const std::string aided_by = "fit drive's GNSS filter over the whole recording with the first --coeffs set (" +
                               a.coeffs.front() + ") as its input, its state recorded at every fix";
  const std::string smp = from ? sample : "in-sample unless the sets were fitted on other data (outages over the whole drive)";
  nlohmann::json j = {{"sample", smp}, {"outages", run_outage_qc(a.dir, sets, rec.epochs(), o, aided_by, smp)}};
  if (a.json) {
    print_json(j.dump(2));
    return;
  }
  std::cout << "QC of " << a.dir << " (GNSS-only): simulated GNSS outages, aided by " << aided_by << "\n";
  print_outage_summary(j["outages"], std::cout);
  std::cout << std::flush;
}

void run(const QcArgs& a) {
  std::vector<QcSet> sets;
  for (const auto& c : a.coeffs) {
    sets.push_back(load_qc_set(c));
    if (sets.back().device) check_same_unit(*sets.back().device, c, a.dir);
  }
  // Out-of-sample by default: start where the latest fit window of an in-motion result ended.
  std::optional<double> from;
  std::string sample = "as requested with --from";
  if (std::isfinite(a.from)) from = a.from;
  else {
    for (const auto& s : sets)
      if (s.fit_window_s) from = std::max(from.value_or(0.0), s.fit_window_s->second);
    sample = from ? "out-of-sample (from the end of the fit window of the in-motion result)"
                  : "from the start of the recording (no fit window known: in-sample if the sets were fitted on this drive)";
  }
  // A GNSS-only recording (or --outages given): simulated GNSS outages instead of the reference run.
  const bool outage_mode = a.outage.given() || (!recording_has_table(a.dir, "reference") && recording_has_table(a.dir, "gnss"));
  if (outage_mode) {
    run_outages(a, sets, from, sample);
    return;
  }
  const QcOutcome q = run_qc(a.dir, sets, from, a.horizon);
  nlohmann::json j = qc_json(q);
  j["sample"] = sample;
  // Catalogue terms of a set (docs/diagnosis.md): which were applied, which ignored (only for sets
  // that carry any, so the output of plain sets is unchanged).
  for (std::size_t i = 0; i < sets.size(); ++i) {
    if (!sets[i].effects.any()) continue;
    const EffectUse u = drive_effect_use(sets[i].effects, q.has_temperature);
    nlohmann::json ign = nlohmann::json::array();
    for (const auto& [k, why] : u.ignored) ign.push_back({{"key", k}, {"reason", why}});
    j["sets"][i]["effects"] = {{"applied", u.applied}, {"ignored", ign}};
  }
  if (!a.plot.empty()) qc_plot(q, a.plot, "Inertial-only navigation, " + a.dir);
  if (a.json) {
    print_json(j.dump(2));
    return;
  }
  std::cout << "QC of " << a.dir << ": inertial-only navigation from T0 = " << q.from_s << " s for " << q.horizon_s << " s, "
            << sample << "\n";
  for (const auto& s : j["sets"]) {
    // ΔS to four significant digits (the JSON keeps them all).
    std::cout << std::setprecision(4) << "  " << s["name"].get<std::string>() << ": final ΔS " << metres_or_no_data(s["final_cpe_m"])
              << ", max " << metres_or_no_data(s["max_cpe_m"]);
    // The marks in time order (a JSON object's keys come sorted as text: "10", "120", "30", …).
    std::vector<std::pair<double, std::string>> marks;
    for (const auto& [k, v] : s["cpe_m_at"].items()) marks.emplace_back(std::stod(k), k);
    std::sort(marks.begin(), marks.end());
    for (const auto& [t, k] : marks) std::cout << ", @" << k << " s " << s["cpe_m_at"][k].get<double>() << " m";
    if (s.contains("effects")) {
      std::cout << "; catalogue terms applied:";
      for (const auto& k : s["effects"]["applied"]) std::cout << ' ' << k.get<std::string>();
      for (const auto& k : s["effects"]["ignored"]) std::cout << " (ignored: " << k["key"].get<std::string>() << ")";
    }
    std::cout << "\n";
  }
  std::cout << std::flush;
}

const bool registered = add_command(50, [](CLI::App& app) {
  auto a = std::make_shared<QcArgs>();
  auto* q = app.add_subcommand("qc", "Quality control by inertial-only navigation: circular position error (eq 39) "
                                     "per coefficient set against the reference of a drive; on a GNSS-only drive "
                                     "(gnss.csv, no reference.csv) the errors of simulated GNSS outages against the fixes");
  q->add_option("dir", a->dir, "drive recording folder (CSV or HDF5)")->required()->check(CLI::ExistingDirectory);
  q->add_option("--coeffs", a->coeffs,
                 "coefficients.json, in-motion RESULT.json, or 'none' (repeatable); catalogue keys of a set "
                 "(IMPROVED.json) are compensated on the IMU samples")
      ->required();
  q->add_option("--from", a->from, "start time T0, s (default: end of the fit window of a RESULT.json, else the start)")
      ->check(finite_number());
  CLI::Option* horizon =
      q->add_option("--horizon", a->horizon, "navigation horizon S, s (default 600; not with the outage QC)")->check(finite_positive());
  add_outage_options(q, a->outage, a->outages);
  q->add_flag("--json", a->json, "machine output");
  q->add_option("--plot", a->plot, "write a PNG with one curve per set (gnuplot)")
      ->check(non_empty());
  q->callback([a, horizon] {
    a->horizon_given = horizon->count() > 0;
    run(*a);
  });
});

}  // namespace
}  // namespace calbench::cli
