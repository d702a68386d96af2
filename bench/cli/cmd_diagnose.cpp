// calbench diagnose DIR [--coeffs COEFFS.json] [--json] [--report OUT.html] [--out IMPROVED.json]
// Physics discovery (docs/diagnosis.md): locate where the recording and the model disagree, name
// the missing effect from the catalogue, fit it and show the improvement.
#include <iostream>

#include "bench/bench_recording.hpp"
#include "bench/cli/number_options.hpp"
#include "bench/cli/registry.hpp"
#include "bench/diagnose/diagnose_run.hpp"
#include "bench/diagnose/drive_run.hpp"
#include "bench/diagnose/effects_json.hpp"
#include "bench/diagnose/gnss_run.hpp"
#include "bench/diagnose/multipos_run.hpp"
#include "common/input_error.hpp"
#include "bench/io/hdf5_recording.hpp"
#include "bench/io/json_util.hpp"
#include "bench/io/plan_toml.hpp"

namespace calbench::cli {
namespace {

struct DiagnoseArgs {
  std::string dir, coeffs, report, out, plan, device_class;
  bool json = false;
  bool no_innovations = false;
  bool list_effects = false;
};

// --out: IMPROVED.json claims an improvement; without a finding there is none, and none is written
// (said on standard error). Returns whether it was written.
bool write_improved(const DiagnoseArgs& a, bool found, const CoefficientSet& improved) {
  if (a.out.empty()) return false;
  if (!found) {
    std::cerr << "calbench: no finding: " << a.out << " not written (nothing to improve)\n";
    return false;
  }
  write_coefficients(a.out, improved);
  return true;
}

// GNSS-only drives (no reference.csv, gnss.csv): bench/diagnose/gnss_run.hpp, docs/diagnosis.md
// "GNSS-only drives". The filter always runs (it is the evidence): --no-innovations does not apply.
void run_diagnose_gnss(const DiagnoseArgs& a, const std::optional<DriveCoeffs>& given) {
  if (a.no_innovations)
    throw InputError("--no-innovations", 0, "", a.dir + " is a GNSS-only drive: its evidence is the in-motion filter's innovations, which cannot be skipped");
  if (!a.report.empty())
    throw InputError("--report", 0, "", a.dir + " is a GNSS-only drive: the HTML report needs a reference INS (reference.csv); use --json");
  const RecordingMeta meta = read_meta(a.dir);
  if (!meta.complete) std::cerr << "calbench: warning: " << a.dir << " is marked incomplete (interrupted run)\n";
  const GnssDiagRun run = run_gnss_diagnosis(a.dir, given ? &*given : nullptr, a.device_class);
  const bool write_out = write_improved(a, !run.core.findings.empty(), run.improved);
  if (a.json) {
    auto j = gnss_diagnosis_json(run);
    j["recording"] = {{"path", a.dir}, {"complete", meta.complete}, {"input_warnings", input_warnings_json()}};
    print_json(j.dump(2));
  } else {
    std::cout << "diagnosis of " << a.dir << "\n" << gnss_diagnosis_text(run);
    if (write_out) std::cout << "improved coefficients written to " << a.out << "\n";
  }
}

// Drive recordings (meta.json kind "drive"): bench/diagnose/drive_run.hpp, docs/diagnosis.md "Drives".
void run_diagnose_drive(const DiagnoseArgs& a) {
  if (!a.plan.empty())  // an option for another kind of recording is not silently ignored
    throw InputError("--plan", 0, "", a.dir + " is a drive recording: --plan (the bench table's accuracy) applies to bench recordings");
  std::optional<DriveCoeffs> given;
  if (!a.coeffs.empty()) {
    given = read_drive_coeffs(a.coeffs);
    check_same_unit(given->set.device, a.coeffs, a.dir);
  }
  if (drive_is_gnss_only(a.dir)) return run_diagnose_gnss(a, given);
  if (!recording_has_table(a.dir, "reference"))
    throw InputError((std::filesystem::path(a.dir) / "reference.csv").string(), 0, "",
                     "cannot open, and there is no gnss.csv either: a drive needs a reference INS (reference.csv) or GNSS "
                     "fixes (gnss.csv) to be diagnosed against");
  DriveDiagInput in = load_drive_diag_input(a.dir, given ? given->mounting_rpy_deg : std::nullopt);
  in.device_class = a.device_class;
  if (!in.meta.complete) std::cerr << "calbench: warning: " << a.dir << " is marked incomplete (interrupted run)\n";
  const DriveDiagRun run = run_drive_diagnosis(in, given ? &*given : nullptr, !a.no_innovations);
  const bool write_out = write_improved(a, !run.result.core.findings.empty(), run.improved);
  if (!a.report.empty()) write_drive_diagnosis_report(a.report, in, run, a.dir);
  if (a.json) {
    auto j = drive_diagnosis_json(in, run);
    j["recording"] = {{"path", a.dir}, {"imu_rows", in.imu_rows}, {"reference_rows", in.ref_rows},
                      {"complete", in.meta.complete}, {"input_warnings", input_warnings_json()}};
    print_json(j.dump(2));
  } else {
    std::cout << "diagnosis of " << a.dir << "\n" << drive_diagnosis_text(in, run);
    if (write_out) std::cout << "improved coefficients written to " << a.out << "\n";
    if (!a.report.empty()) std::cout << "report written to " << a.report << "\n";
  }
}

// Multipos recordings (meta.json kind "multipos"): bench/diagnose/multipos_run.hpp, docs/diagnosis.md
// "Multi-position recordings".
void run_diagnose_multipos(const DiagnoseArgs& a) {
  if (!a.plan.empty())
    throw InputError("--plan", 0, "", a.dir + " is a multipos recording: --plan (the bench table's accuracy) applies to bench recordings");
  if (a.no_innovations)
    throw InputError("--no-innovations", 0, "", a.dir + " is a multipos recording: --no-innovations applies to drives");
  if (!a.report.empty())
    throw InputError("--report", 0, "", a.dir + " is a multipos recording: the HTML report covers bench and drive recordings; "
                                            "use --json (per-pose residuals before/after) or fit multipos --plot");
  const MultiposDiagRun run = run_multipos_diagnosis(a.dir, a.coeffs, a.device_class);
  const bool write_out = write_improved(a, !run.result.core.findings.empty(), run.improved);
  if (a.json) {
    auto j = multipos_diagnosis_json(run);
    j["recording"] = {{"path", a.dir}, {"kind", "multipos"}, {"input_warnings", input_warnings_json()}};
    print_json(j.dump(2));
  } else {
    std::cout << "diagnosis of " << a.dir << " (multipos)\n" << multipos_diagnosis_text(run);
    if (write_out) std::cout << "improved coefficients written to " << a.out << "\n";
  }
}

void run_diagnose(const DiagnoseArgs& a) {
  for (const std::string* f : {&a.out, &a.report})  // before the work: a wrong path costs nothing
    if (!f->empty()) check_output_path(*f);
  const RecordingKind kind = read_meta(a.dir).kind;
  if (kind == RecordingKind::drive) return run_diagnose_drive(a);
  if (kind == RecordingKind::multipos) return run_diagnose_multipos(a);
  if (a.no_innovations)
    throw InputError("--no-innovations", 0, "", a.dir + " is a bench recording: --no-innovations (the in-motion filter runs) applies to drives");
  const DiagInput in = load_diag_input(a.dir);
  const TableSpec table = a.plan.empty() ? recording_table_spec(in.meta) : load_plan(a.plan).table;
  if (!in.meta.complete) std::cerr << "calbench: warning: " << a.dir << " is marked incomplete (interrupted run)\n";
  CoefficientSet given;
  if (!a.coeffs.empty()) {
    given = read_coefficients(a.coeffs);
    check_same_unit(given.device, a.coeffs, a.dir);
  }
  const DiagRun run = run_diagnosis(in, a.coeffs.empty() ? nullptr : &given, table, a.device_class);
  const bool write_out = write_improved(a, !run.result.findings.empty(), run.improved);
  if (!a.report.empty()) write_diagnosis_report(a.report, in, run, a.dir);
  if (a.json) {
    auto j = diagnosis_json(run);
    j["recording"] = {{"path", a.dir}, {"imu_rows", in.imu_rows}, {"complete", in.meta.complete},
                      {"input_warnings", input_warnings_json()}};
    print_json(j.dump(2));
  } else {
    std::cout << "diagnosis of " << a.dir << "\n" << diagnosis_text(run);
    if (write_out) std::cout << "improved coefficients written to " << a.out << "\n";
    if (!a.report.empty()) std::cout << "report written to " << a.report << "\n";
  }
}

const bool registered = add_command(60, [](CLI::App& app) {
  auto a = std::make_shared<DiagnoseArgs>();
  auto* d = app.add_subcommand("diagnose",
                               "Physics discovery: locate where recording and model disagree, name the missing effect, "
                               "model it, show the fit improve (bench, drive and multipos recordings; a GNSS-only drive through the aided filter's "
                               "innovations against the fixes: time offset, lever arm, scale with --coeffs)");
  d->add_option("dir", a->dir, "recording folder (bench, drive or multipos; CSV or HDF5, docs/recording-hdf5.md); a drive without "
                "reference.csv but with gnss.csv is diagnosed from the GNSS-aided filter's innovations (docs/diagnosis.md, GNSS-only drives)")->check(CLI::ExistingDirectory);
  d->add_flag("--list-effects", a->list_effects,
              "print the catalogue of effects (docs/diagnosis.md, generated from the effect registry) and exit; "
              "with --json as JSON");
  d->add_option("--coeffs", a->coeffs, "coefficients to test (default: fit them first with the bench fit; on a drive: b and M fitted on "
                "the drive; a drive also takes an in-motion RESULT.json, mounting included; multipos: fit multipos)")
      ->check(CLI::ExistingFile);
  d->add_flag("--json", a->json, "print findings as JSON on stdout");
  d->add_option("--report", a->report, "write an HTML report with before/after plots (gnuplot)")
      ->check(non_empty());
  d->add_option("--out", a->out, "write IMPROVED.json: coefficients refitted with the new terms as extra keys")
      ->check(non_empty());
  d->add_option("--plan", a->plan, "take the bench's accuracy from this plan's [table] instead of meta.json")
      ->check(CLI::ExistingFile);
  d->add_option("--device-class", a->device_class,
                 "bench: the class whose drift prior judges the residual; drives: the IMU device class of the in-motion "
                 "filter runs (as fit drive --device-class) and of the drift prior; multipos: the "
                 "class whose noise and drift the poses are judged by (as fit multipos --device-class); a class file "
                 "or a built-in class name; default from meta.json device.model")
      ->check(non_empty());
  d->add_flag("--no-innovations", a->no_innovations,
              "drives: skip the in-motion filter runs whose innovation statistics are reported (before/after the "
              "new terms)");
  d->callback([a] {
    if (a->list_effects) {
      if (a->json) print_json(effect_catalogue_json().dump(2));
      else std::cout << effect_catalogue_markdown();
      return;
    }
    if (a->dir.empty()) throw CLI::RequiredError("dir");
    run_diagnose(*a);
  });
});

}  // namespace
}  // namespace calbench::cli
