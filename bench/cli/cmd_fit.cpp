// calbench fit bench DIR --out COEFFS.json [--method lsq|ekf] [--model paper|full] [--json]
//   [--effects IMPROVED.json]   (catalogue terms held fixed, docs/diagnosis.md)
#include <iostream>

#include "bench/approval_thresholds.hpp"
#include "bench/bench_recording.hpp"
#include "bench/cli/number_options.hpp"
#include "bench/cli/registry.hpp"
#include "bench/multipos/fit_multipos_run.hpp"
#include "bench/diagnose/diagnose_run.hpp"
#include "bench/diagnose/effects_json.hpp"
#include "common/input_error.hpp"
#include "bench/io/json_util.hpp"
#include "bench/io/plan_toml.hpp"
#include "calibration/bench_fit_effects.hpp"
#include "db/approval_quality.hpp"

namespace calbench::cli {
namespace {

struct FitBenchArgs {
  std::string dir, out, method = "lsq", model = "full", plan, effects;
  double block_s = 1.0;
  bool json = false;
};

// The fit's quality judged as db approve will judge the set (db::fit_quality_reasons, the limits
// of the device class's built-in thresholds): one warning line per failing figure, and that the
// approval will refuse it (issue 35 sign-off: "coefficients written" said nothing of χ²/dof 80).
void print_fit_quality_warnings(const CoefficientSet& c) {
  const db::Thresholds t = approval_thresholds("", c.device.model);
  db::CoefficientSetRecord set;
  set.serial = c.device.serial;
  set.model = c.device.model;
  set.source = db::SetSource::bench;
  set.errors = c.errors;
  db::FitEvidence ev;
  ev.bench = c.fit_quality;
  const std::vector<std::string> why = db::fit_quality_reasons(set, ev, t.quality);
  for (const auto& w : why) std::cout << "warning: " << w << "\n";
  if (!why.empty())
    std::cout << "warning: db approve will refuse this set (" << why.size() << " fit-quality figure(s) outside the "
              << t.source << "; another file: db approve --thresholds FILE)\n";
}

// --effects: the catalogue terms of a coefficient set (e.g. diagnose's IMPROVED.json) are held
// fixed: their predicted output is removed at 0.05 s resolution before the fit of b and M, and the
// keys are carried into the output coefficients.
void run_fit_bench_effects(const FitBenchArgs& a, BenchFitOptions opt) {
  EffectTerms sigma;
  const EffectTerms fx = effects_from_json(read_json_file(a.effects), a.effects, &sigma);
  const std::vector<std::string> ids = effect_ids_present(fx);
  if (ids.empty())
    throw InputError(a.effects, 0, "", "no catalogue key (temperature_bias, g_sensitivity, ... docs/diagnosis.md) in this file");
  const DiagInput in = load_diag_input(a.dir, a.block_s);
  opt.table = a.plan.empty() ? recording_table_spec(in.meta) : load_plan(a.plan).table;
  if (!in.meta.complete) std::cerr << "calbench: warning: " << a.dir << " is marked incomplete (interrupted run)\n";
  const BenchFitResult r = fit_bench_with_effects(in.data, fx, opt, &sigma);
  CoefficientSet c = bench_result_to_coefficients(r, opt, in.meta, a.dir);
  effects_to_json(fx, sigma, c.extra);
  c.extra["calibration"]["effects_held_fixed"] = ids;
  c.extra["calibration"]["effects_from"] = a.effects;
  if (!a.out.empty()) write_coefficients(a.out, c);
  if (a.json) {
    auto j = bench_result_json(r, c);
    j["effects_held_fixed"] = ids;
    j["effects_from"] = a.effects;
    j["recording"] = {{"path", a.dir}, {"imu_rows", in.imu_rows}, {"reference_rows", in.ref_rows},
                      {"rows_in_steps", in.used_rows}, {"complete", in.meta.complete},
                      {"input_warnings", input_warnings_json()}};
    print_json(j.dump(2));
  } else {
    std::cout << "bench fit (" << a.method << ", model " << a.model << ") of " << a.dir << ": " << in.imu_rows
              << " IMU rows\ncatalogue terms held fixed (from " << a.effects << "):";
    for (const auto& id : ids) std::cout << " " << id;
    std::cout << "\n" << bench_result_text(r);
    print_fit_quality_warnings(c);
    if (!a.out.empty()) std::cout << "coefficients written to " << a.out << " (with the catalogue keys)\n";
  }
}

void run_fit_bench(const FitBenchArgs& a) {
  if (!a.out.empty()) check_output_path(a.out);  // before the fit: a wrong --out costs nothing
  BenchFitOptions opt;
  opt.method = a.method == "ekf" ? BenchMethod::ekf : BenchMethod::lsq;
  opt.model = a.model == "paper" ? BenchModel::paper : BenchModel::full;
  if (!a.effects.empty()) return run_fit_bench_effects(a, opt);
  const BenchRecordingData data = load_bench_blocks(a.dir, a.block_s);
  opt.table = a.plan.empty() ? recording_table_spec(data.meta) : load_plan(a.plan).table;
  if (data.used_rows == 0)
    throw InputError(a.dir + "/reference.csv", 0, "step", "no IMU sample falls inside a plan step (all steps are −1?)");
  if (!data.meta.complete) std::cerr << "calbench: warning: " << a.dir << " is marked incomplete (interrupted run)\n";
  const BenchFitResult r = fit_bench(data.blocks, opt);
  const CoefficientSet c = bench_result_to_coefficients(r, opt, data.meta, a.dir);
  if (!a.out.empty()) write_coefficients(a.out, c);
  if (a.json) {
    auto j = bench_result_json(r, c);
    j["recording"] = {{"path", a.dir}, {"imu_rows", data.imu_rows}, {"reference_rows", data.ref_rows},
                      {"rows_in_steps", data.used_rows}, {"complete", data.meta.complete},
                      {"input_warnings", input_warnings_json()}};
    print_json(j.dump(2));
  } else {
    std::cout << "bench fit (" << a.method << ", model " << a.model << ") of " << a.dir << ": " << data.imu_rows
              << " IMU rows\n"
              << bench_result_text(r);
    print_fit_quality_warnings(c);
    if (!a.out.empty()) std::cout << "coefficients written to " << a.out << "\n";
  }
}

const bool registered = add_command(30, [](CLI::App& app) {
  auto* fit = app.add_subcommand("fit", "Estimate calibration coefficients from a recording (bench; drive; multipos)");
  fit->require_subcommand(1);
  auto a = std::make_shared<FitBenchArgs>();
  auto* b = fit->add_subcommand("bench", "Factory calibration from a bench recording: gyro drift, skews, scale; "
                                         "accelerometer bias, skews, scale; each with its 1σ");
  b->add_option("dir", a->dir, "bench recording folder (CSV or HDF5)")->required()->check(CLI::ExistingDirectory);
  b->add_option("--out", a->out, "write the coefficients here (coefficients.json schema)")
      ->check(non_empty());
  b->add_option("--method", a->method, "lsq: generalised least squares; ekf: the paper's sequential EKF")
      ->check(CLI::IsMember({"lsq", "ekf"}));
  b->add_option("--model", a->model, "paper: gyro drift + 6 skews (eq 1–3); full: plus scale factors")
      ->check(CLI::IsMember({"paper", "full"}));
  b->add_option("--plan", a->plan, "take the bench's accuracy from this plan's [table] instead of meta.json")
      ->check(CLI::ExistingFile);
  b->add_option("--block", a->block_s, "block length for averaging, seconds")->check(finite_number(0.01, 100.0));
  b->add_option("--effects", a->effects,
                "hold the catalogue terms of this coefficient set fixed (e.g. IMPROVED.json from `calbench diagnose`): "
                "their predicted output is removed before b and M are fitted, and the keys go into --out")
      ->check(CLI::ExistingFile);
  b->add_flag("--json", a->json, "print the result as JSON on stdout");
  b->callback([a] { run_fit_bench(*a); });

  auto m = std::make_shared<FitMultiposArgs>();
  auto* mp = fit->add_subcommand("multipos",
                                 "Calibration without a rate table, from a multipos recording (a unit turned by hand or on "
                                 "a fixture through static poses): accelerometer bias, scale, skews from the gravity "
                                 "magnitude; gyro bias, scale, skews from the rotations between poses; each with its 1σ. Static poses "
                                 "(0.75 s or more) by a test whose noise is learned from the recording");
  mp->add_option("dir", m->dir, "multipos recording folder (meta.json kind \"multipos\", imu.csv)")
      ->required()
      ->check(CLI::ExistingDirectory);
  mp->add_option("--out", m->out, "write the coefficients here (coefficients.json schema, with a \"multipos\" key)")
      ->check(non_empty());
  mp->add_option("--plot", m->plot, "write an SVG plot of the static poses found and the motion between them")
      ->check(non_empty());
  mp->add_option("--device-class", m->device_class,
                 "device class file or built-in class name (default: the class meta.json device.model names, else none): its "
                 "drift priors and a cross-check of the noise; the static test always takes the noise measured on the recording")
      ->check(non_empty());
  mp->add_option("--exclude-pose", m->exclude_poses, "leave static pose K (0-based, as listed) out of the accelerometer fit; repeatable")
      ->check(whole_number(0, 1000000));
  mp->add_option("--exclude-rotation", m->exclude_rotations, "leave rotation K (between poses K and K+1) out of the gyro fit; repeatable")
      ->check(whole_number(0, 1000000));
  mp->add_flag("--earth-rate", m->earth_rate,
               "remove the vertical Earth rate from the static gyro means (needs meta.json site.lat_deg and a gyro that resolves 15 °/h)");
  mp->add_flag("--json", m->json, "print the coefficients and the fit's details as JSON on stdout");
  mp->callback([m] { run_fit_multipos(*m, std::cout); });
});

}  // namespace
}  // namespace calbench::cli
