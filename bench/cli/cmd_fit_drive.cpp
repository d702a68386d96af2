// calbench fit drive DIR [--coeffs BENCH.json] --out RESULT.json [--obs pos,vel,att] [--series CSV]
//                        [--smooth] [--window T0:T1] [--drift-models MODELS.json] [--json]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <iostream>
#include <map>

#include "bench/drive/approval_preview.hpp"
#include "bench/cli/number_options.hpp"
#include "bench/cli/outage_options.hpp"
#include "bench/cli/registry.hpp"
#include "bench/drive/drive_units.hpp"
#include "bench/drive/fit_drive.hpp"
#include "bench/drive/recording_scan.hpp"
#include "bench/io/imu_class_toml.hpp"
#include "calibration/effects/effect_registry.hpp"
#include "calibration/inmotion/priors.hpp"
#include "common/drive_result.hpp"
#include "common/input_error.hpp"
#include "common/json_fields.hpp"
#include "common/units.hpp"

namespace calbench::cli {
namespace {

// The console summary of a RESULT.json (common/drive_result.hpp): the typed parts from r, the
// free-form sections of the writer from r.extra.
void print_summary(const DriveResult& r, const std::string& out) {
  const nlohmann::json& j = r.extra;
  using namespace units;
  // value ± σ: σ to two significant digits and the value to the same decimal place (six digits of σ
  // were noise); a null σ is unknown, not 0 (the value then with five significant digits).
  auto vec = [](const nlohmann::json& v, const nlohmann::json& s, double k, const char* unit) {
    std::ostringstream o;
    for (int i = 0; i < 3; ++i) {
      const double x = v[i].get<double>() / k;
      o << (i ? ", " : "");
      if (s[i].is_null() || !(s[i].get<double>() > 0)) {
        o << std::setprecision(5) << x << " ± " << (s[i].is_null() ? "unknown" : "0");
        continue;
      }
      const double sg = s[i].get<double>() / k;
      const int dec = std::clamp(1 - static_cast<int>(std::floor(std::log10(sg))), 0, 12);
      o << std::fixed << std::setprecision(dec) << x << " ± " << sg << std::defaultfloat;
    }
    o << std::setprecision(6) << ' ' << unit;
    return o.str();
  };
  const SensorErrors& c = r.coefficients.errors;
  std::cout << "in-motion fit of " << r.recording.path << " (window " << r.window_s.value().first << " – "
            << r.window_s.value().second << " s, observations " << r.observations.value() << ")\n"
            << "  gyro drift       " << vec(to_json(c.gyro.bias), sigma_json(c.gyro.sigma_bias), kDegPerHour, "°/h") << "\n"
            << "  accel bias       " << vec(to_json(c.accel.bias), sigma_json(c.accel.sigma_bias), kMilliG, "mg") << "\n"
            << "  mounting rpy     " << vec(to_json(r.mounting.value().value_deg), sigma_json(r.mounting.value().sigma_deg), 1.0, "°") << "\n";
  if (r.lever_arm) {
    const LeverArmEstimate& l = *r.lever_arm;
    std::cout << "  lever arm        " << vec(to_json(l.value), to_json(l.sigma), 1.0, "m") << " (nominal " << l.nominal(0) << ", "
              << l.nominal(1) << ", " << l.nominal(2) << "; prior sigma " << l.prior << " m; observable xyz "
              << (l.observable[0] ? "y" : "n") << (l.observable[1] ? "y" : "n") << (l.observable[2] ? "y" : "n") << ")\n";
  }
  if (r.time_offset) {
    const TimeOffsetEstimate& t = *r.time_offset;
    std::cout << "  time offset      " << std::fixed << std::setprecision(2) << t.value * 1e3 << " ± " << t.sigma * 1e3
              << std::defaultfloat << std::setprecision(6) << " ms (prior sigma " << t.prior * 1e3 << " ms; "
              << (t.observable ? "observable" : "not observable: sigma above half the prior") << ")\n";
  }
  if (j.contains("device_class")) {
    const auto& dc = j["device_class"];
    std::cout << "  device class     " << dc["name"].get<std::string>() << " (" << dc["grade"].get<std::string>() << "; "
              << dc["file"].get<std::string>() << ", by " << dc["chosen_by"].get<std::string>() << ")\n";
  }
  if (j.contains("white_noise")) {
    // The unit's white noise measured on the standstills against the class (docs/in-motion.md).
    const auto& w = j["white_noise"];
    std::cout << "  white noise      ";
    if (w["measured"].is_null()) {
      std::cout << (w["scanned"].get<bool>() ? "no standstill found" : "not measured (--no-noise-scan)")
                << ": the class's ARW " << w["class"]["gyro_deg_sqrt_h"][0].get<double>() << " deg/sqrt(h), VRW "
                << w["class"]["accel_m_s_sqrt_h"][0].get<double>() << " m/s/sqrt(h)\n";
    } else {
      auto three = [](const nlohmann::json& v) {
        std::ostringstream o;
        o << std::setprecision(3) << v[0].get<double>() << " " << v[1].get<double>() << " " << v[2].get<double>();
        return o.str();
      };
      std::cout << "measured on " << w["standstills"].size() << " standstill(s): ARW xyz "
                << three(w["measured"]["gyro_deg_sqrt_h"]) << " deg/sqrt(h) (class " << std::setprecision(3)
                << w["class"]["gyro_deg_sqrt_h"][0].get<double>() << "), VRW xyz " << three(w["measured"]["accel_m_s_sqrt_h"])
                << " m/s/sqrt(h) (class " << w["class"]["accel_m_s_sqrt_h"][0].get<double>() << ")" << std::setprecision(6) << "\n";
      for (const char* s : {"gyro", "accel"})
        if (w["used"][s]["source"].get<std::string>().rfind("measured", 0) == 0)
          std::cout << "  NOTE             the " << s << " white noise differs from the class by more than 2x: the filter uses the "
                    << "measured " << w["used"][s]["value"].get<double>() << " " << w["used"][s]["unit"].get<std::string>() << "\n";
    }
  }
  if (!r.priors.is_null()) {
    const auto& p = r.priors;
    if (p["mode"] == "input set")
      std::cout << "  priors           the input set's sigma combined with the " << p["device_class"].get<std::string>()
                << " stability allowance (gyro scale " << p["allowance"]["gyro_scale_ppm"].get<double>() << " ppm, skew "
                << p["allowance"]["gyro_skew_ppm"].get<double>() << " ppm, ...; RESULT.json priors)\n";
    else
      std::cout << "  priors           data-sheet class (raw data)\n";
    std::map<std::string, int> count;
    for (const auto& [name, st] : r.determined_by.value().coefficients) ++count[st.stage];
    std::cout << "  determined by    ";
    bool first = true;
    for (const char* k : {"drive", "both", "bench", "prior"})
      if (count[k] > 0) {
        std::cout << (first ? "" : ", ") << k << " " << count[k];
        first = false;
      }
    std::cout << " of 24 coefficients (drive share of the information: > 80 % drive, < 20 % "
              << (p["mode"] == "input set" ? "bench" : "prior") << ")\n";
  }
  if (j.contains("unobservable_rotation")) {
    const auto& u = j["unobservable_rotation"];
    char b[200];
    std::snprintf(b, sizeof b, "%.2f, %.2f, %.2f deg about MEMS x, y, z (priors %.2f, %.2f, %.2f deg)", u["sigma_deg"][0].get<double>(),
                  u["sigma_deg"][1].get<double>(), u["sigma_deg"][2].get<double>(), u["sigma_prior_deg"][0].get<double>(),
                  u["sigma_prior_deg"][1].get<double>(), u["sigma_prior_deg"][2].get<double>());
    std::cout << "  common rotation  sigma " << b << ": both triads' skews against the mounting, not observable in motion; "
              << (u["option"] == "hold" ? "held at its priors" : "plain EKF (--unobservable-rotation ekf): overconfident") << "\n";
  }
  if (j.contains("drift_models"))
    for (const auto& m : j["drift_models"]["axes"]) {
      std::cout << "  drift model " << m["sensor"].get<std::string>() << ' ' << m["axis"].get<std::string>() << ": "
                << m["model"].get<std::string>() << " sigma " << m["sigma"].get<double>() << ' '
                << m["sigma_unit"].get<std::string>() << ", T " << m["T_s"].get<double>() << " s";
      if (m["beta_rad_s"].get<double>() > 0) std::cout << ", beta " << m["beta_rad_s"].get<double>() << " rad/s";
      std::cout << "  (" << m["source"].get<std::string>() << ")\n";
    }
  if (r.effects) {
    const EffectsUse& e = *r.effects;
    std::cout << "  catalogue terms applied:";
    if (e.applied.empty()) std::cout << " none";
    for (const auto& k : e.applied) {
      std::cout << ' ' << k;
      EffectId id;
      if (effect_from_name(k, id) && effect_spec(id).compensation == DriveCompensation::time_stamp && e.time_offset_s)
        std::cout << " (" << *e.time_offset_s * 1e3 << " ms: stamps t -> t - τ)";
    }
    std::cout << "\n";
    for (const auto& [key, reason] : e.ignored) std::cout << "  catalogue term ignored: " << key << " (" << reason << ")\n";
  }
  if (j.contains("alignment")) {
    const auto& al = j["alignment"];
    std::cout << "  alignment        ";
    if (al["mode"] == "gnss") {
      std::cout << "GNSS fixes, levelled " << al["level"]["t_s"][0].get<double>() << "–" << al["level"]["t_s"][1].get<double>() << " s"
                << (al["level"].value("gyro_bias_observed", false) ? " (gyro bias from it)"
                                                                   : " (not still by the IMU: no gyro bias from it)")
                << "; heading ";
      if (al["heading"]["t_s"].is_null()) std::cout << "never found (no straight stretch, no hypothesis chosen)";
      else
        std::cout << (al["heading"]["source"].get<std::string>().rfind("hypotheses", 0) == 0 ? "chosen among heading hypotheses"
                                                                                                      : "from the course over ground")
                  << " at " << al["heading"]["t_s"].get<double>() << " s";
      std::cout << " (" << al["epochs_skipped_before_heading"] << " epochs skipped while moving without it)";
    } else {
      std::cout << "reference attitude at the start";
    }
    std::cout << "; " << al["realignments"] << " heading re-alignment(s), " << al["covariance_widenings"]
              << " forced covariance widening(s), " << al["course_updates"]["used"] << " course update(s)\n";
    for (const auto& rec : j["recoveries"])
      std::cout << "    t " << rec["t_s"].get<double>() << " s: " << rec["reason"].get<std::string>() << " -> "
                << rec["action"].get<std::string>() << "\n";
  }
  if (r.adaptive_noise && r.adaptive_noise->scale_max > 1) {
    const auto& an = j["adaptive_noise"];
    std::cout << "  adaptive noise   navigation noise variance scaled up " << r.adaptive_noise->increases << " time(s)";
    if (an.contains("decreases")) std::cout << " and down " << an["decreases"].get<long>() << " time(s)";
    std::cout << ", at most x" << std::setprecision(3) << r.adaptive_noise->scale_max << ", x" << r.adaptive_noise->scale_end
              << std::setprecision(6) << " at the end\n";
    if (an.value("failed", false)) {
      std::cout << "  FAILED           the filter ended with the IMU's noise scaled x" << std::setprecision(3)
                << r.adaptive_noise->scale_end << " (limit " << an["fail_scale"].get<double>() << ")" << std::setprecision(6);
      if (an.contains("above_fail_since"))
        std::cout << ", above the limit since t " << an["above_fail_since"]["t_s"].get<double>() << " s ("
                  << an["above_fail_since"]["observation"].get<std::string>() << " innovations " << std::setprecision(3)
                  << an["above_fail_since"]["nis_per_dof"].get<double>() << "x their expectation, at "
                  << an["above_fail_since"].value("speed_m_s", 0.0) << " m/s turning " << an["above_fail_since"].value("turn_rate_deg_s", 0.0)
                  << " deg/s)" << std::setprecision(6);
      std::cout << ": it followed the fixes and the IMU did not carry the navigation. Its coefficients and NIS do not rest on "
                   "the IMU; db approve refuses the set. calbench diagnose DIR locates the misfit\n";
    }
  }
  if (j.contains("sample_timing") && j["sample_timing"].value("scanned", false)) {
    const auto& st = j["sample_timing"];
    std::cout << "  sample timing    " << std::setprecision(4) << st["read_rate_hz"].get<double>() << " rows/s, "
              << st["distinct_rate_hz"].get<double>() << " distinct samples/s (" << st["repeated_rows"].get<long>()
              << " repeated reads); stamp scatter sigma " << std::setprecision(3) << st["sigma_ms"].get<double>()
              << " ms about the sensor's clock; the filter takes " << st["used_ms"].get<double>() << " ms ("
              << st["source"].get<std::string>() << ")";
    if (applied_logger_correction(st).drop_repeats)
      std::cout << "; " << st["applied"].value("rows_dropped", 0L) << " repeated reads dropped";
    std::cout << std::setprecision(6) << "\n";
  }
  if (j.contains("sample_timing") && !j["sample_timing"].value("scanned", false))
    std::cout << "  sample timing    not measured (--no-noise-scan): the filter takes " << j["sample_timing"]["used_ms"].get<double>()
              << " ms (--sample-time MS gives it)\n";
  if (j.contains("gnss_velocity_latency")) {
    const auto& gl = j["gnss_velocity_latency"];
    std::cout << "  GNSS velocity    describes the motion " << std::setprecision(3) << gl["used_s"].get<double>() * 1e3
              << " ms before its stamp (" << gl["source"].get<std::string>() << "; best " << gl["best_s"].get<double>() * 1e3
              << " ms: RMS against the position differences " << gl["rms_at_best_m_s"].get<double>() << " m/s, at 0 "
              << gl["rms_at_zero_m_s"].get<double>() << " m/s)" << std::setprecision(6) << "\n";
  }
  for (const auto& [k, v] : r.nis) {
    std::cout << "  NIS " << k << ": mean " << std::setprecision(3) << v.mean_nis.value_or(std::nan("")) << std::setprecision(6)
              << " (expected " << v.expected_nis.value_or(std::nan(""));
    if (r.adaptive_noise && r.adaptive_noise->scale_end > 1)
      std::cout << ", with the navigation noise scaled x" << std::setprecision(3) << r.adaptive_noise->scale_end << std::setprecision(6);
    std::cout << "), " << v.rejected.value_or(0) << " rejected";
    if (j.contains("vehicle_constraints") && (k == "nhc" || k == "zupt" || k == "zero_rate"))
      std::cout << ", " << v.epochs.value_or(0) << " used";
    if (v.forced.value_or(0) > 0) std::cout << ", " << *v.forced << " forced after a run of rejections";
    std::cout << "\n";
  }
  if (j.contains("vehicle_constraints")) {
    const auto& vc = j["vehicle_constraints"];
    std::cout << "  standstills      " << vc["standstills_s"].size() << " found (" << std::setprecision(4)
              << vc["standstill_total_s"].get<double>() << std::setprecision(6) << " s in all)";
    for (const auto& s : vc["standstills_s"]) std::cout << "  " << s[0].get<double>() << "–" << s[1].get<double>() << " s";
    std::cout << "\n";
    if (vc.contains("mounting_sigma_deg")) {
      const auto& m = vc["mounting_sigma_deg"];
      std::cout << "  mounting sigma   prior -> posterior (deg):";
      const char* ax[3] = {"roll", "pitch", "yaw"};
      for (int i = 0; i < 3; ++i)
        std::cout << ' ' << ax[i] << ' ' << std::setprecision(3) << m["prior"][i].get<double>() << " -> " << m["posterior"][i].get<double>()
                  << std::setprecision(6) << (m["observable"][i].get<bool>() ? " (observable)" : "") << (i < 2 ? "," : "");
      std::cout << "\n";
    }
  }
  const nlohmann::json& qc = r.qc;
  if (qc.contains("sets"))
    for (const auto& s : qc["sets"])
      std::cout << "  QC " << qc["sample"].get<std::string>() << " from " << qc["from_s"].get<double>() << " s over "
                << qc["horizon_s"].get<double>() << " s, set '" << s["name"].get<std::string>() << "': final ΔS "
                << std::setprecision(4) << metres_or_no_data(s["final_cpe_m"]) << std::setprecision(6) << "\n";
  if (qc.contains("outages")) print_outage_summary(qc["outages"], std::cout);
  if (j.contains("approval_preview")) std::cout << approval_preview_text(j["approval_preview"], out);
  std::cout << std::flush;
}

std::string fmt_default(double v) {
  std::ostringstream o;
  o << v;
  return o.str();
}

const bool registered = add_command(31, [](CLI::App& app) {
  using namespace units;
  CLI::App* fit = app.get_subcommand("fit");
  auto a = std::make_shared<FitDriveArgs>();
  auto json = std::make_shared<bool>(false);
  auto* d = fit->add_subcommand("drive", "In-motion calibration against the reference INS/GNSS of a drive recording "
                                         "(EKF, paper eqs 13-15)");
  // Numbers from the command line: decimal, finite; NaN, inf, hex and negatives are bad input (exit 2).
  const CLI::Validator finite_nonneg = finite_non_negative(), finite_pos = finite_positive();
  d->add_option("dir", a->dir,
                "drive recording folder (CSV or HDF5, docs/recording-hdf5.md), or a multi-unit drive (units.json: every unit fitted against the reference, "
                "parsed once; --out then names a folder, OUT/SLOT/RESULT.json)")
      ->required()
      ->check(CLI::ExistingDirectory);
  d->add_option("--coeffs", a->coeffs,
                 "coefficient set applied to the data first (coefficients.json, or an earlier RESULT.json whose "
                 "mounting estimate then starts this fit); the filter's priors are the set's sigma combined with the "
                 "device class's stability allowance, and the result is the fused set; catalogue keys it carries "
                 "(diagnose --out IMPROVED.json: time_offset, lever_arm, g_sensitivity, scale_*, temperature_*, "
                 "correlated_drift) are compensated on the IMU samples, bench-only keys ignored with a note; a multi-unit "
                 "drive: a folder with SLOT/COEFFS.json or SLOT/RESULT.json per unit")
      ->check(CLI::ExistingPath);
  d->add_option("--out", a->out, "RESULT.json to write (a multi-unit drive: a folder)")->required()
      ->check(non_empty());
  CLI::Option* obs = d->add_option("--obs", a->obs,
                                   "observations to use: any of pos,vel,att (eqs 13, 14, 15) and the vehicle constraints nhc "
                                   "(non-holonomic: no lateral/vertical velocity of the vehicle while moving) and zupt (zero "
                                   "velocity and angular rate at standstills detected from the IMU), which need pos, vel or att "
                                   "besides and a land vehicle (never for a handheld or pedestrian recording); default "
                                   "pos,vel,att, with GNSS aiding pos,vel (velocity where gnss.csv has it)");
  d->add_option("--aiding", a->aiding,
                 "aiding source: reference (reference.csv, a reference INS) or gnss (gnss.csv fixes of the antenna: "
                 "position, velocity where given, no attitude; levelled at the opening standstill, heading from the "
                 "course over ground); default reference.csv when present, else gnss.csv")
      ->check(CLI::IsMember({"reference", "gnss"}));
  d->add_option("--device-class", a->device_class,
                 "IMU device class: a class file (bench/imu_classes/<name>.toml or your own, docs/in-motion.md \"Device "
                 "classes\") or the name or alias of a built-in class; default: the class of meta.json device.model "
                 "(an unknown model is bad input). Its noise, drift, raw priors and stability allowances are the fit's")
      ->check(non_empty());
  d->add_option("--thresholds", a->thresholds,
                 "approval thresholds (JSON, the file of `db approve --thresholds`) the approval preview judges the "
                 "result by; default: the built-in limits of the recording's device class (meta.json device.model)");
  d->add_option("--sample-time", a->sample_time,
                 "sigma of the IMU stamps about the sensor's own clock (a logger stamps a sample when it reads it): "
                 "auto (default: measured from the recording's stamps and repeated reads in the noise scan; 0 for "
                 "regular stamps), off, or milliseconds. The filter adds process noise sigma^2 x (change of rate)^2 per "
                 "step: nothing at rest, large in shaky motion. Where the stamps are not regular the rows repeating the "
                 "previous one are also dropped as second reads (not with off; RESULT.json sample_timing.applied; "
                 "docs/in-motion.md, \"Real loggers\")")
      ->check(non_empty());
  d->add_option("--gnss-vel-latency", a->gnss_vel_latency,
                 "GNSS aiding: how long before its stamp a fix's velocity describes the motion: auto (default: measured "
                 "from gnss.csv, the velocities against the position differences; 0 when the fixes do not tell), off, or "
                 "milliseconds")
      ->check(non_empty());
  d->add_flag("!--no-noise-scan", a->measure_noise,
              "do not scan the recording before the fit: neither the white noise on its standstills (default: measured, "
              "and used where it differs from the class by more than 2x) nor the sample timing (--sample-time auto: 0)");
  d->add_option("--series", a->series, "write the estimate time series (t_s, one column per state, and sigma_*) to CSV");
  d->add_option("--series-every", a->series_every_s,
                "with --series (forward pass): also a row every SECONDS of IMU data between the epochs the filter used "
                "(the navigation solution through a GNSS outage; default 0: rows at the used epochs only)")
      ->check(finite_positive());
  d->add_flag("--smooth", a->smooth, "Rauch-Tung-Striebel backward pass (memory ~21 kB per filter epoch)");
  d->add_option("--window", a->window, "fit only on T0:T1 seconds of the recording (either may be empty)");
  d->add_option("--prior-gyro-bias", a->prior_gyro_bias_dps,
                 "prior 1-sigma of the gyro drift, deg/s, overriding the default (the device class's prior for raw data, ADIS16488A 0.5; with --coeffs the "
                 "set's sigma combined with the allowance)")
      ->check(finite_pos);
  d->add_option("--prior-accel-bias", a->prior_accel_bias_mg,
                 "prior 1-sigma of the accelerometer bias, mg, overriding the default (the device class's prior for raw data, ADIS16488A 30; with --coeffs "
                 "the set's sigma combined with the allowance)")
      ->check(finite_pos);
  // Stability allowances (docs/in-motion.md, "Priors"): finite and >= 0; NaN and negatives are bad input (exit 2).
  const inmotion::StabilityAllowance& def = builtin_imu_class("ADIS16488A").allowance;
  for (const AllowanceOption& al : allowance_options())
    d->add_option(al.option, a->allowance.*al.given,
                  std::string("with --coeffs: stability allowance (1-sigma, how far it can move between the set's "
                              "calibration and the drive) of the ") + al.what + " (default: the device class's; " +
                      def.device_class + " " + fmt_default(def.*al.field / al.unit) + ")")
        ->check(finite_nonneg)
        ->group("Priors with --coeffs (prior = hypot(set sigma, allowance))");
  d->add_option("--estimate", a->estimate,
                 "optional blocks to estimate, comma list: lever (the GNSS antenna lever arm, 3 states: meta.json "
                 "mounting.lever_arm_m plus a correction with prior sigma --lever-arm-sigma) and time (the IMU-GNSS time "
                 "offset, 1 state, prior sigma --time-offset-sigma); default none (the nominal lever arm and the time "
                 "stamps are exact). RESULT.json lever_arm_m and time_offset_s (docs/in-motion.md, \"Lever arm and time offset\")")
      ->option_text("lever,time");
  d->add_option("--lever-arm-sigma", a->lever_arm_sigma, "with --estimate lever: prior 1-sigma of the lever-arm correction per axis, m (default 0.1)")
      ->check(finite_pos);
  d->add_option("--time-offset-sigma", a->time_offset_sigma, "with --estimate time: prior 1-sigma of the time offset, s (default 0.02)")
      ->check(finite_pos);
  d->add_option("--obs-rate", a->obs_rate_hz, "reference epochs used per second (default 10)")->check(finite_pos);
  d->add_option("--constraint-rate", a->constraint_rate_hz,
                "with --obs ...,nhc and/or zupt: at most this many constraint updates per second, taken from the IMU "
                "stream at the covariance steps (default 10)")
      ->check(finite_pos);
  d->add_option("--nhc-sigma", a->nhc_sigma, "with --obs ...,nhc: 1-sigma of the vehicle's lateral and vertical velocity, m/s (default 0.1, a car)")
      ->check(finite_pos);
  d->add_option("--zupt-sigma", a->zupt_sigma, "with --obs ...,zupt: 1-sigma of the velocity at a standstill, m/s (default 0.01)")
      ->check(finite_pos);
  d->add_option("--cov-dt", a->cov_dt, "covariance propagation interval, s (default 0.1)")->check(finite_pos);
  d->add_option("--covariance", a->covariance,
                 "covariance arithmetic: structured (default: the moving rows only, bit for bit the dense results), "
                 "joseph (the same with the Joseph-form update) or dense (full N x N products every step, the reference)")
      ->check(CLI::IsMember({"structured", "joseph", "dense"}))
      ->option_text("structured|joseph|dense");
  d->add_option("--adaptive", a->adaptive,
                 "adaptive process noise: auto (default: on with GNSS aiding, off against a reference INS, whose "
                 "inconsistencies are findings for diagnose), on, or off; on: the navigation noise is scaled by covariance "
                 "matching when the innovations are inconsistent with the model (docs/in-motion.md, \"Adaptive process "
                 "noise and the robust gate\")")
      ->check(CLI::IsMember({"auto", "on", "off"}))
      ->option_text("auto|on|off");
  d->add_option("--unobservable-rotation", a->unobservable_rotation,
                 "hold (default): the common rotation of both triads against the mounting and the MEMS attitude, which "
                 "no in-motion observation tells, keeps the uncertainty its priors give (its covariance carried along at "
                 "every correction; docs/in-motion.md, \"The triads' common rotation\"); ekf: the plain EKF, which learns it "
                 "from its own moving linearisation point (overconfident M skews), for comparison")
      ->check(CLI::IsMember({"hold", "ekf"}))
      ->option_text("hold|ekf");
  d->add_option("--sigma-pos", a->sigma_pos, "reference or fix position 1-sigma, m (default: sigma column, else 0.1 for reference.csv, 2 for gnss.csv)")->check(finite_pos);
  d->add_option("--sigma-vel", a->sigma_vel, "reference or fix velocity 1-sigma, m/s (default: sigma column, else 0.02 for reference.csv, 0.1 for gnss.csv)")->check(finite_pos);
  d->add_option("--sigma-att", a->sigma_att_deg, "reference attitude 1-sigma, deg (default: sigma column, else 0.01)")->check(finite_pos);
  d->add_option("--drift-models", a->drift_models,
                 "identified drift models (MODELS.json of `calbench identify --out`, or a coefficients.json with "
                 "drift_models): they replace the data-sheet shaping filters per axis (exp_cosine: 2 states, eqs 35-36)")
      ->check(CLI::ExistingFile);
  d->add_option("--qc-horizon", a->qc_horizon_s, "horizon of the QC run in RESULT.json, s (default 600)")->check(finite_pos);
  auto outage = std::make_shared<OutageArgs>();
  add_outage_options(d, *outage, a->outages);
  d->add_flag("--json", *json, "print RESULT.json to stdout");
  d->callback([a, json, obs, outage] {
    a->obs_given = obs->count() > 0;
    outage_options(*outage, a->outages);
    if (is_multi_unit_drive(a->dir)) {  // several units against one reference (docs/recording-units.md)
      nlohmann::json s;
      const std::vector<UnitFit> fits = fit_drive_units(*a, 0, &s);
      int failed = 0;
      bool bad = false;
      nlohmann::json all = s;
      for (std::size_t k = 0; k < fits.size(); ++k) {
        const UnitFit& f = fits[k];
        if (!f.error.empty()) {
          ++failed;
          bad = bad || f.bad_input;
          std::cerr << "calbench: unit " << f.slot << ": " << f.error << std::endl;
          continue;
        }
        if (*json) all["units"][k]["RESULT"] = drive_result_to_json(f.result);
        else {
          std::cout << "unit " << f.slot << " (" << f.out.string() << "): ";
          print_summary(f.result, f.out.string());
        }
      }
      if (*json) print_json(all.dump(2));
      else if (failed == static_cast<int>(fits.size()))
        std::cerr << "calbench: no unit fitted: nothing written under " << a->out << std::endl;
      else
        std::cout << fits.size() - static_cast<std::size_t>(failed) << " of " << fits.size() << " units fitted against "
                  << s["reference"]["file"].get<std::string>() << " (parsed once, "
                  << s["reference"]["rows"].dump() << " epochs), " << s["threads"] << " thread(s); "
                  << (fs::path(a->out) / "units.json").string() << " names each RESULT.json" << std::endl;
      if (failed) throw Exit{bad ? 2 : 1};
      return;
    }
    if (!a->coeffs.empty() && fs::is_directory(a->coeffs))
      throw InputError(a->coeffs, 0, "",
                       "is a folder: --coeffs FOLDER is for a multi-unit drive (units.json); give the set's file "
                       "(coefficients.json or RESULT.json)");
    const DriveResult r = fit_drive(*a);
    if (*json) print_json(drive_result_to_json(r).dump(2));
    else print_summary(r, a->out);
  });
});

}  // namespace
}  // namespace calbench::cli
