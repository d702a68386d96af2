#include "bench/drive/fit_drive.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <sstream>
#include <tuple>

#include "bench/diagnose/effects_json.hpp"
#include "bench/approval_thresholds.hpp"
#include "bench/drive/approval_preview.hpp"
#include "bench/drive/drive_series.hpp"
#include "bench/drive/drive_stream.hpp"
#include "bench/drive/qc_drive.hpp"
#include "bench/drive/recording_scan.hpp"
#include "bench/drive/reference_info.hpp"
#include "bench/io/coefficients_json.hpp"
#include "bench/io/drift_models_json.hpp"
#include "calibration/effects/effect_registry.hpp"
#include "common/drive_result.hpp"
#include "common/input_error.hpp"
#include "bench/io/input_warning.hpp"
#include "bench/io/hdf5_recording.hpp"
#include "bench/io/recording.hpp"
#include "bench/io/recording_location.hpp"
#include "bench/io/json_util.hpp"
#include "bench/io/imu_class_toml.hpp"
#include "calibration/identification/standstill_noise.hpp"
#include "calibration/inmotion/inmotion_filter.hpp"
#include "calibration/inmotion/obs_names.hpp"
#include "common/number_parse.hpp"
#include "common/units.hpp"

namespace calbench {

const std::array<AllowanceOption, 7>& allowance_options() {
  using namespace units;
  using A = FitDriveArgs::Allowances;
  using S = inmotion::StabilityAllowance;
  static const std::array<AllowanceOption, 7> t = {{
      {"--allowance-gyro-bias-dph", &A::gyro_bias_dph, &S::gyro_bias, kDegPerHour, "gyro_bias_dph", "gyro bias, deg/h"},
      {"--allowance-accel-bias-mg", &A::accel_bias_mg, &S::accel_bias, kMilliG, "accel_bias_mg", "accelerometer bias, mg"},
      {"--allowance-gyro-scale-ppm", &A::gyro_scale_ppm, &S::gyro_scale, kPpm, "gyro_scale_ppm", "gyro scale factor, ppm"},
      {"--allowance-gyro-skew-ppm", &A::gyro_skew_ppm, &S::gyro_skew, kPpm, "gyro_skew_ppm", "gyro skew, ppm"},
      {"--allowance-accel-scale-ppm", &A::accel_scale_ppm, &S::accel_scale, kPpm, "accel_scale_ppm",
       "accelerometer scale factor, ppm"},
      {"--allowance-accel-skew-ppm", &A::accel_skew_ppm, &S::accel_skew, kPpm, "accel_skew_ppm", "accelerometer skew, ppm"},
      {"--allowance-mount-deg", &A::mount_deg, &S::mount, kDeg, "mount_deg",
       "mounting per axis when --coeffs is a RESULT.json, deg"},
  }};
  return t;
}

namespace {

std::pair<double, double> parse_window(const std::string& w) {
  double t0 = -std::numeric_limits<double>::infinity(), t1 = std::numeric_limits<double>::infinity();
  if (w.empty()) return {t0, t1};
  const auto c = w.find(':');
  if (c == std::string::npos) throw InputError("--window", 0, "", "expected T0:T1 (seconds; either may be empty)");
  // Each bound a whole finite decimal number ("5abc", "nan", "1e999" are bad input).
  auto bound = [&](std::size_t from, std::size_t to, double& t) {
    if (!parse_finite_number(std::string_view(w).substr(from, to - from), t))
      throw InputError("--window", 0, "", "expected T0:T1 (finite seconds), got '" + w + "'");
  };
  if (c > 0) bound(0, c, t0);
  if (c + 1 < w.size()) bound(c + 1, w.size(), t1);
  if (!(t1 > t0)) throw InputError("--window", 0, "", "T1 must be after T0");
  return {t0, t1};
}

// Identified drift models (--drift-models) into the filter's configuration; the JSON says which
// axes got a model and which kept the data-sheet default.
nlohmann::json apply_drift_models(const std::string& file, inmotion::InMotionConfig& cfg) {
  using namespace units;
  const AxisDriftModels m = assign_drift_models(read_drift_models(file), file);
  std::array<inmotion::DriftPrior, 3> g, acc;
  nlohmann::json axes = nlohmann::json::array();
  const char* ax = "xyz";
  for (int s = 0; s < 2; ++s)
    for (int i = 0; i < 3; ++i) {
      const TriadNoise& n = s == 0 ? cfg.noise.gyro : cfg.noise.accel;
      const auto& e = (s == 0 ? m.gyro : m.accel)[static_cast<std::size_t>(i)];
      inmotion::DriftPrior p{n.drift_sigma, n.drift_tau_s};
      const double unit = s == 0 ? kDegPerHour : kMilliG;
      nlohmann::json j = {{"sensor", s == 0 ? "gyro" : "accel"}, {"axis", std::string(1, ax[i])}};
      if (e) {
        p.sigma = e->model.sigma;
        p.tau_s = 1.0 / e->model.alpha;
        p.exp_cosine = e->model.kind == identification::DriftModelKind::exp_cosine;
        p.beta = p.exp_cosine ? e->model.beta : 0.0;
        j["source"] = "drift_models." + e->key;
        j["model"] = identification::drift_model_name(e->model.kind);
        j["equations"] = p.exp_cosine ? "eqs 35-36 (2 states)" : "eq 22";
      } else {
        j["source"] = "data-sheet default (no model for this axis in the file)";
        j["model"] = "exponential";
        j["equations"] = "eq 22";
      }
      j["sigma_si"] = p.sigma;
      j["sigma"] = p.sigma / unit;
      j["sigma_unit"] = s == 0 ? "deg/h" : "mg";
      j["T_s"] = p.tau_s;
      j["beta_rad_s"] = p.beta;
      (s == 0 ? g : acc)[static_cast<std::size_t>(i)] = p;
      axes.push_back(j);
    }
  cfg.gyro_drift = g;
  cfg.accel_drift = acc;
  return {{"file", file},
          {"layout", inmotion::needs_augmented_layout(cfg) ? "augmented (exp-cosine states)" : "default"},
          {"axes", axes}};
}

// Catalogue terms carried by the input coefficients (with σ), and what the drive filter does with them.
struct InputEffects {
  EffectTerms terms, sigma;
  bool present = false;
  nlohmann::json ignored = nlohmann::json::array();  // [{"key", "reason"}] decided before the run
  nlohmann::json drift;                              // correlated_drift as the filter's drift prior
};

// --coeffs: a coefficients.json, or an in-motion RESULT.json (its "coefficients" and its mounting
// estimate with σ: a second drive refines the first).
struct InputSet {
  CoefficientSet set;
  std::optional<std::pair<Vec3, Vec3>> mounting_deg;
  std::string recording_sha256;  // of the drive a RESULT.json was fitted on
};

InputSet read_input_set(const std::string& file) {
  const nlohmann::json j = read_json_file(file);
  InputSet in;
  if (!is_drive_result(j)) {
    in.set = coefficients_from_json(j, file);
    return in;
  }
  DriveResult r = drive_result_from_json(j, file);
  in.set = std::move(r.coefficients);
  in.recording_sha256 = r.recording.sha256;
  if (r.mounting) {  // it starts this fit's mounting, its σ the prior: a mounting without σ is no start
    if (!r.mounting->sigma_deg.array().isFinite().any())
      throw InputError(file, 0, "mounting_rpy_deg.sigma", "missing: the mounting of a RESULT.json input needs its sigma");
    in.mounting_deg = std::make_pair(r.mounting->value_deg, r.mounting->sigma_deg);
  }
  return in;
}

// Priors of the constant parameters (calibration/inmotion/priors.hpp) and how RESULT.json states them.
struct PriorChoice {
  inmotion::PriorReport report;
  nlohmann::json json;
  std::optional<Mat3> C_mb_start;  // a mounting carried by the input set
};

PriorChoice choose_priors(const FitDriveArgs& a, const std::optional<CoefficientSet>& bench, const ImuClass& cls) {
  using namespace units;
  PriorChoice pc;
  nlohmann::json j;
  if (bench) {
    inmotion::StabilityAllowance al = cls.allowance;
    j["device_class"] = al.device_class;
    nlohmann::json over = nlohmann::json::array(), shown = nlohmann::json::object();
    for (const AllowanceOption& o : allowance_options()) {
      const double v = a.allowance.*o.given;
      if (!std::isnan(v)) {
        if (!std::isfinite(v) || v < 0) throw InputError(o.option, 0, "", "expected a finite number >= 0");
        al.*o.field = v * o.unit;
        over.push_back(o.option);
      }
      shown[o.json_key] = al.*o.field / o.unit;
    }
    shown["overridden"] = over;
    j["allowance"] = shown;
    Vec3 mount_sigma = Vec3::Constant(kUnknownSigma);
    if (a.coeffs_mounting_deg) {
      mount_sigma = inmotion::mounting_sigma_from_rpy(a.coeffs_mounting_deg->first * kDeg, a.coeffs_mounting_deg->second * kDeg);
      pc.C_mb_start = ins::dcm_from_rpy(a.coeffs_mounting_deg->first * kDeg);
      j["mounting_from_input_deg"] = {{"value", to_json(a.coeffs_mounting_deg->first)},
                                      {"sigma", sigma_json(a.coeffs_mounting_deg->second)}};
    }
    pc.report = inmotion::priors_from_set(bench->errors, al, mount_sigma, cls.priors);
    // A σ far beyond anything a calibration of this class produces is a broken file, not a prior:
    // the filter would run with P of 1e300 and return nothing meaningful.
    const inmotion::ParameterPriors& ds = cls.priors;
    for (std::size_t k = 0; k < 24; ++k) {
      const double sgm = pc.report.set_sigma[k], lim = 100 * inmotion::prior_value(ds, k);
      if (std::isfinite(sgm) && sgm > lim) {
        // The set's key of parameter k (order of prior_parameter_names(): per triad 3 biases, 9 M).
        const std::size_t r = k % 12;
        const std::string tri = k < 12 ? "gyro" : "accel";
        const std::string key = r < 3 ? tri + ".sigma_bias[" + std::to_string(r) + "]"
                                      : tri + ".sigma_M[" + std::to_string((r - 3) / 3) + "][" + std::to_string((r - 3) % 3) + "]";
        std::ostringstream m;
        m << "sigma " << sgm << " is implausible for a " << al.device_class << " (more than 100x the data-sheet class "
          << inmotion::prior_value(ds, k) << "): not usable as a prior";
        throw InputError(a.coeffs.empty() ? "--coeffs" : a.coeffs, 0, key, m.str());
      }
    }
    j["mode"] = "input set";
    j["input"] = a.coeffs.empty() ? nlohmann::json("in memory") : nlohmann::json(a.coeffs);
  } else {
    pc.report = inmotion::priors_datasheet(cls.priors);
    j["mode"] = "data-sheet";
    j["input"] = nullptr;
  }
  // Options that cannot act here are named, not silently dropped.
  nlohmann::json without = nlohmann::json::array();
  for (const AllowanceOption& o : allowance_options()) {
    if (std::isnan(a.allowance.*o.given)) continue;
    std::string why;
    if (!bench) why = "no --coeffs: raw data take the data-sheet priors";
    else if (o.field == &inmotion::StabilityAllowance::mount && !a.coeffs_mounting_deg) why = "the input set carries no mounting";
    else if (o.field == &inmotion::StabilityAllowance::gyro_bias && a.prior_gyro_bias_dps > 0) why = "--prior-gyro-bias sets the gyro bias prior";
    else if (o.field == &inmotion::StabilityAllowance::accel_bias && a.prior_accel_bias_mg > 0)
      why = "--prior-accel-bias sets the accelerometer bias prior";
    if (why.empty()) continue;
    without.push_back({{"option", o.option}, {"reason", why}});
    input_warning(o.option, 0, "has no effect here: " + why);
  }
  if (!without.empty()) j["options_without_effect"] = without;
  // --prior-gyro-bias / --prior-accel-bias override the bias priors whatever their source.
  for (int s = 0; s < 2; ++s) {
    const double v = s == 0 ? a.prior_gyro_bias_dps * kDeg : a.prior_accel_bias_mg * kMilliG;
    if (!(v > 0)) continue;
    for (std::size_t k = 0; k < 3; ++k) {
      const std::size_t idx = (s == 0 ? 0 : 12) + k;
      inmotion::set_prior_value(pc.report.sigma, idx, v);
      inmotion::set_prior_value(pc.report.sigma_raw, idx, v);
      pc.report.source[idx] = inmotion::PriorSource::option;
    }
  }
  nlohmann::json params = nlohmann::json::object();
  const auto& names = inmotion::prior_parameter_names();
  auto num = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  for (std::size_t k = 0; k < names.size(); ++k) {
    const bool bias = names[k].find(".bias.") != std::string::npos, mount = k >= 24;
    const char* unit = mount ? "rad" : !bias ? "1" : k < 12 ? "rad/s" : "m/s^2";
    std::string src;
    switch (pc.report.source[k]) {
      case inmotion::PriorSource::datasheet:
        src = bench ? (mount ? "data-sheet class (the input carries no mounting)" : "data-sheet class (the input set's sigma is unknown)")
                    : "data-sheet class (raw data)";
        break;
      case inmotion::PriorSource::set_and_allowance: src = "input sigma combined with the stability allowance"; break;
      case inmotion::PriorSource::option: src = k < 12 ? "--prior-gyro-bias" : "--prior-accel-bias"; break;
    }
    params[names[k]] = {{"prior_sigma", inmotion::prior_value(pc.report.sigma_raw, k)},
                        {"input_sigma", num(pc.report.set_sigma[k])},
                        {"allowance", num(pc.report.allowance[k])},
                        {"unit", unit},
                        {"source", src}};
  }
  j["parameters"] = params;
  pc.json = j;
  return pc;
}

// Which stage determined each coefficient of the result: the drive's share of the information
// about it, 1 − (σ_posterior/σ_prior)², in the frame of the data the filter saw.
DeterminedBy determined_by(const inmotion::ParameterPriors& prior, const inmotion::ParameterPriors& post,
                           const std::optional<CoefficientSet>& bench) {
  DeterminedBy d;
  d.rule = "drive share of the information 1-(sigma_post/sigma_prior)^2: < 0.2 bench (prior when there is no "
           "input set or its sigma is unknown), > 0.8 drive, else both";
  const auto& names = inmotion::prior_parameter_names();
  const inmotion::ParameterPriors parent = bench ? inmotion::sigma_of(bench->errors) : inmotion::ParameterPriors{};
  for (std::size_t k = 0; k < names.size(); ++k) {
    const double p = inmotion::prior_value(prior, k), q = inmotion::prior_value(post, k);
    const double ratio = q / p, share = std::clamp(1.0 - ratio * ratio, 0.0, 1.0);
    const double ps = bench && k < 24 ? inmotion::prior_value(parent, k) : kUnknownSigma;
    // An input set's coefficient with σ unknown (null) gave no information: its prior was the class's.
    const char* stage = share > 0.8 ? "drive" : share >= 0.2 ? "both" : bench && (k >= 24 || std::isfinite(ps)) ? "bench" : "prior";
    (k < 24 ? d.coefficients : d.mounting)[names[k]] =
        CoefficientStage{stage, std::isfinite(ps) ? std::optional<double>(ps) : std::nullopt, p, q, ratio, share};
  }
  return d;
}

DriveResult run_fit(const FitDriveArgs& a, const inmotion::InMotionConfig& cfg, const std::optional<CoefficientSet>& bench,
                       double t0, double t1, const nlohmann::json& models, const InputEffects& fx, const PriorChoice& pc,
                       bool gnss, const nlohmann::json& unit, const LoggerCorrection& logger);

// "--sample-time" / "--gnss-vel-latency": auto (the measured value), off (0), or milliseconds.
double timing_option(const std::string& v, const char* opt, double measured) {
  if (v == "auto") return measured;
  if (v == "off") return 0.0;
  double ms = 0;
  if (!parse_finite_number(v, ms) || ms < 0 || ms > 1000) throw InputError(opt, 0, "", "expected auto, off, or milliseconds in 0 … 1000, got '" + v + "'");
  return ms * 1e-3;
}

nlohmann::json adaptive_events_json(const inmotion::AdaptiveNoise& an) {
  nlohmann::json ev = nlohmann::json::array();
  for (const inmotion::AdaptiveEvent& e : an.events())
    ev.push_back({{"t_s", e.t}, {"observation", inmotion::obs_type_name(e.type)}, {"from", e.q_from}, {"to", e.q_to}, {"nis_per_dof", e.nis_per_dof},
                  {"speed_m_s", e.speed}, {"turn_rate_deg_s", e.turn_rate / units::kDeg}, {"accel_m_s2", e.accel}});
  return ev;
}

nlohmann::json white_noise_json(const identification::NoiseMeasurement& m, bool scanned) {
  using namespace units;
  const identification::StandstillConfig sc;
  // Per axis: gyro x, y, z in deg/sqrt(h) (ARW), accelerometer x, y, z in m/s/sqrt(h) (VRW).
  auto three = [](const identification::AxisLevels& l, std::size_t from, double unit) {
    nlohmann::json a = nlohmann::json::array();
    for (std::size_t i = from; i < from + 3; ++i)
      a.push_back(std::isfinite(l.v[i]) ? nlohmann::json(l.v[i] / unit) : nlohmann::json(nullptr));
    return a;
  };
  auto split = [&](const identification::AxisLevels& l) {
    return nlohmann::json{{"gyro_deg_sqrt_h", three(l, 0, kDeg / kSqrtHour)}, {"accel_m_s_sqrt_h", three(l, 3, 1.0 / kSqrtHour)}};
  };
  nlohmann::json st = nlohmann::json::array();
  for (const auto& s : m.standstills) st.push_back({{"t_s", {s.t0, s.t1}}, {"samples", s.samples}, {"dt_s", s.dt}, {"level", split(s.level)}});
  std::ostringstream method;
  method << "standstills: windows of " << sc.window_s << " s whose sample sigma is at most " << sc.ratio
         << "x the class's white-noise sigma on all six axes, at least " << sc.min_duration_s
         << " s long; level per axis N = Allan deviation at tau = dt times sqrt(dt) (identification/allan), pooled over "
            "the standstills; used where an axis differs from the class by more than "
         << m.factor << "x (largest axis of the triad)";
  nlohmann::json j = {
      {"method", method.str()},
      {"scanned", scanned},
      {"class", split(m.cls)},
      {"measured", m.measured ? split(m.level) : nlohmann::json(nullptr)},
      {"ratio", m.measured ? nlohmann::json{{"gyro", three(m.ratio, 0, 1.0)}, {"accel", three(m.ratio, 3, 1.0)}}
                           : nlohmann::json(nullptr)},
      {"standstills", st},
      {"factor", m.factor}};
  const char* names[2] = {"gyro", "accel"};
  const double units_[2] = {kDeg / kSqrtHour, 1.0 / kSqrtHour};
  for (int k = 0; k < 2; ++k) {
    const std::string why = !scanned ? "class (--no-noise-scan)"
                            : !m.measured ? "class (no standstill found)"
                            : m.zero[static_cast<std::size_t>(k)] ? "class (an axis measured zero: a noise-free signal or noise below the LSB)"
                            : m.differs[static_cast<std::size_t>(k)] ? "measured (an axis differs from the class by more than 2x)"
                                                                     : "class (every axis within 2x of it)";
    j["used"][names[k]] = {{"value", m.used[static_cast<std::size_t>(k)] / units_[k]},
                           {"unit", k == 0 ? "deg/sqrt(h)" : "m/s/sqrt(h)"},
                           {"source", why}};
  }
  return j;
}

// RESULT.json "vehicle_constraints": the rule and settings, the standstills found, and the
// mounting's prior and posterior σ per axis (an axis the drive made observable: posterior below
// half the prior).
nlohmann::json vehicle_constraints_json(const inmotion::InMotionConfig& cfg, const inmotion::InMotionFilter& f, const Vec3& prior_mount) {
  using namespace units;
  nlohmann::json st = nlohmann::json::array();
  double total = 0;
  for (const inmotion::Standstill& s : f.standstills()) {
    st.push_back({s.t0, s.t1});
    total += s.t1 - s.t0;
  }
  nlohmann::json j = {
      {"nhc", cfg.obs_nhc},
      {"zupt", cfg.obs_zupt},
      {"zero_rate", cfg.obs_zupt && cfg.zupt_zero_rate},
      {"rate_hz", cfg.constraint_rate_hz},
      {"nhc_sigma_m_s", cfg.nhc_sigma},
      {"zupt_sigma_m_s", cfg.zupt_sigma},
      {"rule",
       {{"standstill", "IMU quiet over the window (every gyro and accelerometer axis's spread <= factor x its white-noise "
                       "variance q^2/dt + lsb^2/12) and INS speed and last fix's horizontal speed < max_speed: ZUPT"},
        {"moving", "no standstill, INS horizontal speed >= min_speed, |yaw rate| <= max_turn and speed x |yaw rate| <= "
                   "max_lateral_accel: NHC"},
        {"window_s", cfg.standstill_window_s},
        {"factor", cfg.standstill_factor},
        {"max_speed_m_s", cfg.standstill_max_speed},
        {"nhc_min_speed_m_s", cfg.nhc_min_speed},
        {"nhc_max_turn_dps", cfg.nhc_max_turn_rate / kDeg},
        {"nhc_max_lateral_accel_m_s2", cfg.nhc_max_lateral_accel}}},
      {"standstills_s", st},
      {"standstill_total_s", total}};
  const int mo = f.offset(inmotion::Block::mount);
  if (mo >= 0) {
    const Vec3 post = f.P().block<3, 3>(mo, mo).diagonal().cwiseSqrt();
    nlohmann::json obs = nlohmann::json::array();
    for (int i = 0; i < 3; ++i) obs.push_back(post(i) < 0.5 * prior_mount(i));
    j["mounting_sigma_deg"] = {{"axes", "roll, pitch, yaw (misalignment about the vehicle axes)"},
                               {"prior", to_json(Vec3(prior_mount / kDeg))},
                               {"posterior", to_json(Vec3(post / kDeg))},
                               {"observable", obs},
                               {"rule", "observable: posterior sigma below half the prior"}};
  }
  return j;
}

}  // namespace

DriveResult fit_drive(const FitDriveArgs& a) {
  if (!a.thresholds.empty()) approval_thresholds(a.thresholds);  // a bad file is bad input before the fit
  using namespace units;
  const auto [t0, t1] = parse_window(a.window);
  if (a.write_out) check_output_path(a.out);
  if (!a.series.empty()) check_output_path(a.series);
  FitDriveArgs args = a;  // the input set and its mounting, read once
  std::optional<CoefficientSet> bench = a.coeffs_set;
  if (!bench && !a.coeffs.empty()) {
    InputSet in = read_input_set(a.coeffs);
    bench = std::move(in.set);
    if (in.mounting_deg) args.coeffs_mounting_deg = in.mounting_deg;
    args.coeffs_recording_sha256 = in.recording_sha256;
  }
  // A drive refines only its own unit's coefficients: the set and the recording name one device.
  if (bench && !a.dir.empty()) check_same_unit(bench->device, a.coeffs.empty() ? "--coeffs" : a.coeffs, fs::path(a.dir));
  InputEffects fx;
  if (bench) {
    fx.terms = effects_from_json(bench->extra, a.coeffs.empty() ? "--coeffs" : a.coeffs, &fx.sigma);
    fx.present = fx.terms.any();
  }
  // The aiding source (docs/in-motion.md, "GNSS-only drives").
  const fs::path dir(a.dir);
  if (!a.aiding.empty() && a.aiding != "reference" && a.aiding != "gnss")
    throw InputError("--aiding", 0, "", "expected reference or gnss, got '" + a.aiding + "'");
  const bool gnss = a.aiding == "gnss" || (a.aiding.empty() && !recording_has_table(dir, "reference") && recording_has_table(dir, "gnss"));
  if (gnss && !recording_has_table(dir, "gnss"))
    throw InputError((dir / "gnss.csv").string(), 0, "", "--aiding gnss needs gnss.csv in the recording (no such file)");
  if (gnss) {
    if (!a.obs_given) args.obs = "pos,vel";
    std::stringstream ss(args.obs);
    std::string tok;
    while (std::getline(ss, tok, ','))
      if (tok == "att")
        throw InputError("--obs", 0, "att",
                         "GNSS aiding (gnss.csv) has no attitude: use pos or pos,vel (att needs a reference INS, reference.csv)");
  }
  // The device class (bench/imu_classes): --device-class, else meta.json device.model.
  const RecordingMeta meta0 = read_meta(dir);
  const ImuClassChoice cls = choose_imu_class(a.device_class, meta0.device.model, (dir / "meta.json").string());
  inmotion::InMotionConfig cfg;
  // The unit learned from the data: white noise measured on the standstills.
  // And the logger's: its stamps' scatter (sample_timing) and, on GNSS, the fix velocity's latency.
  RecordingScan scan;
  if (a.measure_noise) scan = scan_recording(dir, meta0, cls.cls.noise);
  else scan.noise = identification::measure_white_noise({}, cls.cls.noise);
  const identification::NoiseMeasurement& wn = scan.noise;
  cfg.noise = identification::apply_measured_noise(cls.cls.noise, wn);
  cfg.sample_time_sigma = timing_option(a.sample_time, "--sample-time", scan.scanned ? scan.timing.sigma_s : 0.0);
  // A logger that stamps at the read: its second reads are dropped (they repeat a sample already
  // read). Its stamps are left where they are: moving them by their measured mean lateness made the
  // innovations' likelihood lower on each of four simulated polling loggers (the lateness is
  // reported, not applied; docs/validation/inmotion-real-walk-cause.md). Not with --sample-time off,
  // nor for regular stamps (a simulator's are untouched) or increments (two equal increments are
  // two samples).
  LoggerCorrection logger;
  logger.drop_repeats = a.sample_time != "off" && scan.scanned && scan.rates && !scan.timing.regular;
  nlohmann::json unit = {{"device_class", imu_class_json(cls)},
                         {"white_noise", white_noise_json(wn, a.measure_noise)},
                         {"sample_timing", sample_timing_json(scan.timing, scan.scanned, cfg.sample_time_sigma, a.sample_time, logger)}};
  if (gnss) {
    const identification::GnssVelocityLatency lat = scan_gnss_velocity_latency(dir);
    cfg.gnss_vel_latency_s = timing_option(a.gnss_vel_latency, "--gnss-vel-latency", lat.latency_s);
    unit["gnss_velocity_latency"] = gnss_velocity_latency_json(lat, cfg.gnss_vel_latency_s, a.gnss_vel_latency);
  } else if (a.gnss_vel_latency != "auto") {
    timing_option(a.gnss_vel_latency, "--gnss-vel-latency", 0.0);  // bad input whatever the aiding
    input_warning("--gnss-vel-latency", 0, "has no effect here: the drive is aided by reference.csv, not GNSS fixes");
  }
  if (gnss) {  // GNSS defaults where gnss.csv has no sigma columns
    cfg.ref_sigma_pos = 2.0;
    cfg.ref_sigma_vel = 0.1;
  }
  cfg.obs_pos = cfg.obs_vel = cfg.obs_att = false;
  {
    std::stringstream ss(args.obs);
    std::string tok;
    while (std::getline(ss, tok, ',')) {
      if (tok == "pos") cfg.obs_pos = true;
      else if (tok == "vel") cfg.obs_vel = true;
      else if (tok == "att") cfg.obs_att = true;
      else if (tok == "nhc") cfg.obs_nhc = true;
      else if (tok == "zupt") cfg.obs_zupt = true;
      else throw InputError("--obs", 0, "", "unknown observation '" + tok + "' (pos, vel, att, nhc, zupt)");
    }
    if (!cfg.obs_pos && !cfg.obs_vel && !cfg.obs_att)
      throw InputError("--obs", 0, "",
                       cfg.obs_nhc || cfg.obs_zupt ? "nhc and zupt constrain the velocity only: add pos, vel or att"
                                                   : "no observation selected");
  }
  // Vehicle constraints (docs/in-motion.md, "Vehicle constraints"); their options act only with them.
  if (!(a.constraint_rate_hz > 0) || !std::isfinite(a.constraint_rate_hz))
    throw InputError("--constraint-rate", 0, "", "expected a finite rate > 0 Hz");
  cfg.constraint_rate_hz = a.constraint_rate_hz;
  for (const auto& [opt, given, on, field] :
       {std::tuple{"--nhc-sigma", a.nhc_sigma, cfg.obs_nhc, &inmotion::InMotionConfig::nhc_sigma},
        std::tuple{"--zupt-sigma", a.zupt_sigma, cfg.obs_zupt, &inmotion::InMotionConfig::zupt_sigma}}) {
    if (given == 0) continue;
    if (!(given > 0) || !std::isfinite(given)) throw InputError(opt, 0, "", "expected a finite sigma > 0 m/s");
    if (on) cfg.*field = given;
    else input_warning(opt, 0, std::string("has no effect here: --obs does not name ") + (opt[2] == 'n' ? "nhc" : "zupt"));
  }
  // Priors of the constant parameters: the input set's σ combined with the device class's
  // stability allowance, or the data-sheet class for raw data; --prior-* override the biases.
  const PriorChoice pc = choose_priors(args, bench, cls.cls);
  cfg.prior = pc.report.sigma;
  cfg.obs_rate_hz = a.obs_rate_hz;
  cfg.cov_dt = a.cov_dt;
  if (a.covariance == "dense") cfg.covariance = inmotion::InMotionConfig::Covariance::dense;
  else if (a.covariance == "joseph") cfg.covariance = inmotion::InMotionConfig::Covariance::joseph;
  else if (a.covariance != "structured")
    throw InputError("--covariance", 0, "", "expected structured, joseph or dense, got '" + a.covariance + "'");
  cfg.store_for_smoother = a.smooth;
  {  // the antenna blocks (--estimate)
    std::stringstream ss(a.estimate);
    std::string tok;
    while (std::getline(ss, tok, ',')) {
      if (tok == "lever") cfg.estimate_lever_arm = true;
      else if (tok == "time") cfg.estimate_time_offset = true;
      else throw InputError("--estimate", 0, "", "unknown block '" + tok + "' (lever, time)");
    }
    for (const auto& [opt, v] : {std::pair{"--lever-arm-sigma", a.lever_arm_sigma}, std::pair{"--time-offset-sigma", a.time_offset_sigma}})
      if (!(v > 0) || !std::isfinite(v)) throw InputError(opt, 0, "", "expected a finite sigma > 0");
    cfg.lever_arm_sigma = a.lever_arm_sigma;
    cfg.time_offset_sigma = a.time_offset_sigma;
  }
  if (a.adaptive != "auto" && a.adaptive != "on" && a.adaptive != "off")
    throw InputError("--adaptive", 0, "", "expected auto, on or off, got '" + a.adaptive + "'");
  cfg.adaptive.enabled = a.adaptive == "on" || (a.adaptive == "auto" && gnss);
  if (a.unobservable_rotation != "hold" && a.unobservable_rotation != "ekf")
    throw InputError("--unobservable-rotation", 0, "", "expected hold or ekf, got '" + a.unobservable_rotation + "'");
  cfg.hold_unobservable_rotation = a.unobservable_rotation == "hold";
  nlohmann::json models;
  if (!a.drift_models.empty()) models = apply_drift_models(a.drift_models, cfg);
  // correlated_drift (drift σ, τ beyond the data sheet's) becomes the filter's first-order drift
  // prior of that sensor, unless identified models were given.
  const EffectSpec& drift = noise_effect_spec();
  for (int s = 0; s < 2; ++s) {
    const double sigma = effect_value(drift, fx.terms, s, -1, 0), tau = effect_value(drift, fx.terms, s, -1, 1);
    if (!(sigma > 0)) continue;
    const char* sn = s == 0 ? "gyro" : "accel";
    if (!a.drift_models.empty()) {
      fx.ignored.push_back({{"key", std::string(drift.key) + "." + sn}, {"reason", "--drift-models given: they set the drift model"}});
      continue;
    }
    const TriadNoise& n = s == 0 ? cfg.noise.gyro : cfg.noise.accel;
    inmotion::DriftPrior p{sigma, tau > 0 ? tau : n.drift_tau_s};
    (s == 0 ? cfg.gyro_drift : cfg.accel_drift) = std::array<inmotion::DriftPrior, 3>{p, p, p};
    fx.drift[sn] = {{"sigma_si", p.sigma}, {"T_s", p.tau_s}};
  }
  return run_fit(args, cfg, bench, t0, t1, models, fx, pc, gnss, unit, logger);
}

namespace {

DriveResult run_fit(const FitDriveArgs& a, const inmotion::InMotionConfig& cfg, const std::optional<CoefficientSet>& bench,
                       double t0, double t1, const nlohmann::json& models, const InputEffects& fx, const PriorChoice& pc,
                       bool gnss, const nlohmann::json& unit, const LoggerCorrection& logger) {
  using namespace units;
  using Filter = inmotion::InMotionFilter;
  // The series columns of the layout this configuration gives (the filter builds the same one).
  const std::vector<std::string> columns = inmotion::column_names(inmotion::make_layout(cfg));
  DriveStream st(a.dir, bench ? std::optional<SensorErrors>(bench->errors) : std::nullopt, fx.present ? &fx.terms : nullptr,
                 gnss ? Aiding::gnss : Aiding::reference, a.shared_reference, /*digest=*/true);
  st.set_logger_correction(logger);
  // The reference epochs the QC will need, kept as they pass (the QC then reads no reference.csv;
  // memory bounded by its horizon): from the first epoch of the window over the horizon (in-sample),
  // and around the end of a finite window over the horizon (out-of-sample), each up to and with the
  // first epoch beyond it (the QC stops there).
  const bool capture = a.qc && !gnss && !a.shared_reference;
  std::vector<DriveRefRow> qc_in, qc_oos;
  AidingStats aiding_stats;  // for reference_system, gathered as the rows pass
  bool qc_in_full = false, qc_oos_full = false;
  auto keep_for_qc = [&](double t, bool started) {
    const DriveRefRow* row = st.last_reference_row();
    if (!capture || !row) return;
    if (started && !qc_in_full) {
      qc_in.push_back(*row);
      qc_in_full = t > qc_in.front().t + a.qc_horizon_s + 1e-9;
    }
    if (std::isfinite(t1) && !qc_oos_full && t >= t1 - 1.0) {
      qc_oos.push_back(*row);
      qc_oos_full = t > t1 + a.qc_horizon_s + 2.0;
    }
  };
  const bool used[3] = {cfg.obs_pos, cfg.obs_vel, cfg.obs_att};  // observations: position, velocity, attitude
  // Outage QC: the filter's state at every fix, recorded during this pass when it covers the whole
  // drive (no --window), else by a second pass over the whole drive after the fit (below).
  const bool outages = a.qc && gnss && a.outages.enabled;
  if (outages) check_outage_options(a.outages);
  const bool whole = !std::isfinite(t0) && !std::isfinite(t1);
  std::optional<OutageRecorder> record;
  if (outages && whole) record.emplace();
  std::unique_ptr<Filter> f;
  std::unique_ptr<DriveSeries> series;
  if (!a.series.empty() && !a.smooth)
    series = std::make_unique<DriveSeries>(a.series, columns, "in-motion filter estimates (forward pass), totals and 1-sigma");
  auto override_sigma = [&](inmotion::RefObs& r) {
    if (a.sigma_pos > 0) r.sigma_pos = a.sigma_pos;
    if (a.sigma_vel > 0) r.sigma_vel = a.sigma_vel;
    if (a.sigma_att_deg > 0) r.sigma_att = a.sigma_att_deg * kDeg;
  };
  // One series row of the filter's state now (reading it leaves the filter as it was).
  auto series_row = [&](double t) {
    Filter::Vec x, s;
    Filter::Vec6 tx, ts;
    f->state_si(x, s);
    f->total_drift_si(tx, ts);
    series->row_si(t, f->layout(), x, s, ts);
  };
  double next_series_t = -std::numeric_limits<double>::infinity();
  double t_first = 0, t_last = 0, t_data_end = 0;
  long n_imu = 0;
  DriveStream::Event e;
  while (st.next(e)) {
    // Where the IMU data end: a QC after the fit window needs IMU rows there (a reference that goes
    // on past a cut imu.csv is no out-of-sample data).
    if (!e.is_ref) t_data_end = std::max(t_data_end, e.t);
    if (e.is_ref) {
      keep_for_qc(e.t, f != nullptr || (e.t >= t0 - 1e-9 && e.t <= t1 + 1e-9));
      if (const DriveRefRow* r = st.last_reference_row()) aiding_stats.add(*r);
      else if (const GnssRow* g = st.last_gnss_row()) aiding_stats.add(*g);
    }
    if (e.t < t0 - 1e-9) continue;
    if (e.t > t1 + 1e-9) continue;  // keep reading to learn where the data end
    if (e.is_ref) {
      override_sigma(e.ref);
      if (!f) {
        f = std::make_unique<Filter>(cfg, pc.C_mb_start.value_or(st.nominal_mounting()), st.lever_arm(), e.ref);
        t_first = e.t;
        continue;
      }
      const bool took = f->reference(e.ref);
      if (record) record->epoch(*f, e.ref, took);
      if (a.on_epoch) a.on_epoch(*f, e.ref, took);
      if (took && a.on_innovation) {
        for (int k = 0; k < 3; ++k)
          if (used[k]) a.on_innovation(k, f->last_innovation(k));
      }
      if (took && series) series_row(e.t);
    } else if (f) {
      double dt = e.dt;
      Vec3 dth = e.dtheta, dv = e.dv;
      if (e.t - dt < f->time()) {  // the first interval straddles the start epoch
        const double part = e.t - f->time();
        if (part <= 0) continue;
        dth *= part / dt;
        dv *= part / dt;
        dt = part;
      }
      f->imu(e.t, dth, dv, dt);
      ++n_imu;
      t_last = e.t;
      if (series && a.series_every_s > 0 && e.t >= next_series_t - 1e-9) {
        series_row(e.t);
        next_series_t = std::floor(e.t / a.series_every_s + 1e-9) * a.series_every_s + a.series_every_s;
      }
    }
  }
  if (!f) throw InputError(a.dir, 0, gnss ? "gnss.csv" : "reference.csv", gnss ? "no GNSS fix inside the fit window" : "no reference epoch inside the fit window");
  if (n_imu < 10) throw InputError(a.dir, 0, "imu.csv", "too few IMU samples inside the fit window");
  if (series) series->close();
  if (a.smooth) {
    const auto sm = f->smooth();
    if (!a.series.empty()) {
      DriveSeries w(a.series, columns, "in-motion estimates after the RTS smoother (sensor states smoothed; navigation states from the forward pass)");
      for (const auto& ep : sm) w.row_si(ep.t, f->layout(), ep.x, ep.sigma, ep.total_sigma);
      w.close();
    }
  }

  const SensorErrors corr = f->estimate();
  {
    const auto finite = [](const TriadErrors& t) {
      return t.bias.allFinite() && t.M.allFinite() && t.sigma_bias.allFinite() && t.sigma_M.allFinite();
    };
    if (!finite(corr.gyro) || !finite(corr.accel) || !f->P().allFinite())
      throw std::runtime_error("the in-motion filter broke down numerically (a non-finite estimate or covariance): "
                               "check the priors and the reference sigma; nothing written");
  }
  // The fused estimate: the filter's priors already hold the input set's σ (choose_priors), so the
  // combined set's σ are the posterior σ, never more than hypot(input σ, allowance).
  const SensorErrors total = bench ? compose_fused(bench->errors, corr) : corr;
  const RecordingMeta& meta = st.meta();
  DeviceId dev = bench ? bench->device : meta.device;
  if (dev.serial.empty()) dev.serial = meta.device.serial;

  // RESULT.json through its codec (common/drive_result.hpp): the typed parts in r, the free-form
  // sections in j (r.extra).
  DriveResult r;
  nlohmann::json& j = r.extra;
  r.format = kDriveResultFormat;
  r.device = dev;
  const fs::path dir(a.dir);
  // Digests of the files as they were read (computed while reading; a file the stream did not
  // read to its end is hashed here).
  const auto digest = [](std::optional<std::string> d, const fs::path& file) { return d ? *d : sha256_file(file); };
  const fs::path imu_file = table_file(dir, "imu"), ref_file = table_file(dir, "reference");
  const bool h5 = imu_file.filename() == kHdf5RecordingFile, has_ref = recording_has_table(dir, "reference");
  // (An HDF5 recording is one file: every table's digest is that of recording.h5, computed once.)
  const std::string imu_digest = digest(st.imu_sha256(), imu_file);
  nlohmann::json ref_digest = nullptr;
  if (a.shared_reference) ref_digest = a.shared_reference->sha256;
  else if (has_ref) ref_digest = h5 ? imu_digest : gnss ? sha256_file(ref_file) : digest(st.aiding_sha256(), ref_file);
  r.recording.path = fs::absolute(dir).lexically_normal().string();
  r.recording.sha256 = imu_digest;
  if (ref_digest.is_string()) r.recording.sha256_reference = ref_digest.get<std::string>();
  r.recording.sha256_meta = sha256_file(dir / "meta.json");
  // An HDF5 recording: the digests are of recording.h5 (every table), not of CSV files.
  if (h5) r.recording.format = "hdf5";
  if (gnss) r.recording.sha256_gnss = h5 ? imu_digest : digest(st.aiding_sha256(), table_file(dir, "gnss"));
  r.recording.device = meta.device;  // the unit that drove
  // Where it is for a central store, as for bench runs (docs/database.md "recording locations"):
  // file://HOST/absolute/path and the SHA-256 of all its files.
  r.recording.uri = file_uri(dir);
  r.recording.digest = folder_digest(dir);
  j["device_class"] = unit["device_class"];
  j["white_noise"] = unit["white_noise"];
  j["sample_timing"] = unit["sample_timing"];
  j["sample_timing"]["applied"]["rows_dropped"] = st.dropped_repeats();  // as the filter's pass read them
  if (unit.contains("gnss_velocity_latency")) j["gnss_velocity_latency"] = unit["gnss_velocity_latency"];
  r.reference_system = describe_reference(dir, meta, a, cfg, gnss, aiding_stats);
  r.window_s = std::make_pair(t_first, t_last);
  r.observations = a.obs;
  if (gnss) j["aiding"] = "gnss";
  // How the heading was found and kept (GNSS-only start, re-alignments, forced recoveries):
  // always with GNSS aiding, otherwise only when something happened.
  if (gnss || !f->recoveries().empty() || f->alignment().course_updates + f->alignment().course_rejected > 0) {
    const inmotion::AlignmentReport& al = f->alignment();
    nlohmann::json aj = {{"mode", al.mode}};
    if (al.mode == "gnss") {
      aj["level"] = {{"t_s", {al.level_t0, al.level_t1}},
                     {"roll_pitch_deg", {al.level_rpy(0) / kDeg, al.level_rpy(1) / kDeg}},
                     {"accel_std_m_s2", al.level_accel_std},
                     {"gyro_mean_dps", al.level_gyro_mean / kDeg},
                     {"quiet", al.level_quiet},
                     {"gyro_bias_observed", al.level_gyro_bias},
                     {"assumes", "a standstill over the levelling window"}};
      aj["heading"] = al.heading_t >= 0
                          ? nlohmann::json{{"t_s", al.heading_t},
                                           {"source", al.heading_hypotheses > 0
                                                          ? "hypotheses: " + std::to_string(al.heading_hypotheses) +
                                                                " headings round the circle, the most likely by the fixes (no forward motion assumed)"
                                                          : std::string("course over ground of the fixes (forward motion, nominal mounting)")}}
                          : nlohmann::json{{"t_s", nullptr}, {"source", "none: the vehicle never drove straight far enough"}};
      aj["epochs_skipped_before_heading"] = al.skipped_unaligned;
      aj["heading_known_at_end"] = f->heading_known();
    }
    nlohmann::json rj = nlohmann::json::array();
    long realigned = 0, widened = 0;
    for (const auto& r : f->recoveries()) {
      rj.push_back({{"t_s", r.t}, {"reason", r.reason}, {"action", r.action}});
      (r.action.rfind("heading", 0) == 0 ? realigned : widened) += 1;
    }
    aj["realignments"] = realigned;
    aj["covariance_widenings"] = widened;
    aj["course_updates"] = {{"used", f->alignment().course_updates}, {"rejected", f->alignment().course_rejected}};
    j["alignment"] = aj;
    j["recoveries"] = rj;
  }
  r.smoothed = a.smooth;
  j["covariance"] = a.covariance;
  r.coefficients.device = dev;
  r.coefficients.errors = total;
  r.correction = CoefficientSet{dev, corr, nlohmann::json::object(), std::nullopt};
  j["input_coefficients"] = a.coeffs.empty() ? nlohmann::json(nullptr) : nlohmann::json(a.coeffs);
  if (!a.coeffs.empty() && fs::is_regular_file(a.coeffs)) j["input_coefficients_sha256"] = sha256_file(a.coeffs);
  r.priors = pc.json;
  if (!a.coeffs_recording_sha256.empty() && a.coeffs_recording_sha256 == r.recording.sha256) {
    const std::string w = "the input set was fitted on this same recording (imu.csv SHA-256 equal): its information is "
                          "counted twice, and the result's sigma are too small";
    input_warning(a.coeffs, 0, w);
    r.priors["warning"] = w;
  }
  // In raw-data coefficients: the combined set's σ against hypot(set σ, allowance).
  const int mo = f->offset(inmotion::Block::mount);
  const Vec3 mount_sigma = mo >= 0 ? Vec3(f->P().block<3, 3>(mo, mo).diagonal().cwiseSqrt()) : Vec3::Zero();
  r.determined_by = determined_by(pc.report.sigma_raw, inmotion::sigma_of(total, mount_sigma), bench);
  if (fx.present) {
    // The catalogue terms are part of the sensor model of the result too (qc applies them).
    effects_to_json(fx.terms, fx.sigma, r.coefficients.extra);
    const EffectUse use = drive_effect_use(fx.terms, st.rows_with_temperature() > 0);
    nlohmann::json applied = use.applied, ignored = fx.ignored;
    for (const auto& [k, why] : use.ignored) ignored.push_back({{"key", k}, {"reason", why}});
    if (fx.drift.contains("gyro") || fx.drift.contains("accel")) applied.push_back(noise_effect_spec().key);
    nlohmann::json ej = {{"source", a.coeffs.empty() ? "in memory" : a.coeffs},
                         {"applied", applied},
                         {"ignored", ignored},
                         {"how", "output terms removed from the raw IMU samples before the set's correction; time stamps "
                                 "t -> t - time_offset; correlated_drift as the filter's drift prior"}};
    if (time_stamp_offset(fx.terms) != 0) ej["time_offset_s"] = time_stamp_offset(fx.terms);
    if (!fx.drift.is_null()) ej["drift_prior"] = fx.drift;
    j["effects"] = ej;
  }
  Vec3 mr, ms;
  f->mounting_rpy(mr, ms);
  r.mounting = DriveMounting{Vec3(mr / kDeg), Vec3(ms / kDeg),
                             {{"nominal", to_json(meta.mounting->rpy_deg)}, {"lever_arm_m", to_json(meta.mounting->lever_arm_m)}}};
  // The antenna blocks (--estimate): estimate with σ and prior; observable when σ < prior / 2.
  {
    Eigen::VectorXd x, sg;
    f->state_si(x, sg);
    if (const int o = f->layout().L.offset(static_cast<int>(inmotion::kLeverArmBlock)); o >= 0) {
      const Vec3 d = x.segment<3>(o), s3 = sg.segment<3>(o);
      nlohmann::json obs = nlohmann::json::array();
      for (int i = 0; i < 3; ++i) obs.push_back(s3(i) < 0.5 * cfg.lever_arm_sigma);
      j["lever_arm_m"] = {{"value", to_json(Vec3(meta.mounting->lever_arm_m + d))}, {"sigma", to_json(s3)},
                          {"prior", cfg.lever_arm_sigma}, {"nominal", to_json(meta.mounting->lever_arm_m)},
                          {"correction", to_json(d)}, {"observable", obs},
                          {"how", "MEMS origin relative to the reference body origin (the GNSS antenna), reference body axes, "
                                  "as meta.json mounting.lever_arm_m; observable: sigma below half the prior"}};
    }
    if (const int o = f->layout().L.offset(static_cast<int>(inmotion::kTimeOffsetBlock)); o >= 0)
      j["time_offset_s"] = {{"value", x(o)}, {"sigma", sg(o)}, {"prior", cfg.time_offset_sigma}, {"observable", sg(o) < 0.5 * cfg.time_offset_sigma},
                            {"how", "aiding time stamp minus the true time of the fix (the fix stamped t describes the antenna at t - value)"}};
  }
  // The in-run drift at the end of the window (shaping-filter states), and the σ of the total
  // gyro drift (constant + in-run), which is what the drive determines best.
  j["in_run_drift_end"] = {{"gyro_rad_s", to_json(f->gyro_drift())}, {"accel_m_s2", to_json(f->accel_drift())},
                           {"gyro_total_sigma_rad_s", to_json(f->gyro_total_drift_sigma())}};
  nlohmann::json cons;
  const char* eqs[3] = {"13", "14", "15"};
  for (int i = 0; i < 3; ++i) {
    if (!used[i]) continue;
    const auto& c = f->consistency(i);
    cons[inmotion::obs_type_name(i)] = {{"equation", eqs[i]}, {"epochs", c.used}, {"rejected", c.rejected}, {"forced", c.forced}, {"mean_nis", c.mean_nis()},
                      {"expected_nis", 3.0},
                      {"fraction_within_95pct", c.used ? static_cast<double>(c.within95) / static_cast<double>(c.used) : 0.0}};
  }
  if (cfg.obs_nhc || cfg.obs_zupt) {
    const char* ce[3] = {"obs_nhc.cpp", "obs_zupt.cpp (velocity)", "obs_zupt.cpp (angular rate)"};
    const bool on[3] = {cfg.obs_nhc, cfg.obs_zupt, cfg.obs_zupt && cfg.zupt_zero_rate};
    const int dof[3] = {2, 3, 3};
    for (int i = 0; i < 3; ++i) {
      if (!on[i]) continue;
      const auto& c = f->consistency(inmotion::kObsNhc + i);
      cons[inmotion::obs_type_name(inmotion::kObsNhc + i)] = {{"equation", ce[i]}, {"epochs", c.used}, {"rejected", c.rejected}, {"forced", c.forced}, {"mean_nis", c.mean_nis()},
                     {"expected_nis", static_cast<double>(dof[i])},
                     {"fraction_within_95pct", c.used ? static_cast<double>(c.within95) / static_cast<double>(c.used) : 0.0}};
    }
    j["vehicle_constraints"] = vehicle_constraints_json(cfg, *f, cfg.prior.mount);
  }
  r.consistency = cons;
  {
    const inmotion::AdaptiveNoise& an = f->adaptive_noise();
    j["adaptive_noise"] = {
        {"enabled", cfg.adaptive.enabled},
        {"option", a.adaptive},
        {"method", "covariance matching of the innovations (Mehra 1972; Mohamed & Schwarz 1999; scale form of Ding et al. 2007): "
                   "the navigation states' white-noise variances scaled when a 10 s block's NIS is beyond its chi-square quantile at p = 1e-5"},
        {"scale_end", an.scale()},
        {"scale_max", an.max_scale_reached()},
        {"increases", an.increases()},
        {"decreases", an.decreases()},
        {"fail_scale", inmotion::AdaptiveNoise::kFailScale},
        {"failed", an.scale() > inmotion::AdaptiveNoise::kFailScale},
        {"events", adaptive_events_json(an)}};
    if (const inmotion::AdaptiveEvent* e = an.above_fail_since())
      j["adaptive_noise"]["above_fail_since"] = {{"t_s", e->t}, {"observation", inmotion::obs_type_name(e->type)}, {"nis_per_dof", e->nis_per_dof},
                                                 {"speed_m_s", e->speed}, {"turn_rate_deg_s", e->turn_rate / units::kDeg}};
  }
  {
    const Vec3 se = f->unobservable_rotation_sigma(), sp = f->unobservable_rotation_sigma_prior();
    if (se.any())
      j["unobservable_rotation"] = {
          {"option", a.unobservable_rotation},
          {"what", "a common rotation of both triads (M's antisymmetric parts) against the mounting and the MEMS attitude: "
                   "no in-motion observation tells it, only the priors (docs/in-motion.md, \"The triads' common rotation\")"},
          {"sigma_deg", {se(0) / kDeg, se(1) / kDeg, se(2) / kDeg}},
          {"sigma_prior_deg", {sp(0) / kDeg, sp(1) / kDeg, sp(2) / kDeg}}};
  }
  if (!models.is_null()) j["drift_models"] = models;

  // QC: out-of-sample inertial-only navigation after the window, with the input set and with
  // the result, when the recording continues; otherwise in-sample from the window start.
  nlohmann::json qj;
  nlohmann::json oj;  // outage QC (GNSS aiding)
  if (outages) {
    const bool oos = !whole && t_data_end > t_last + 10.0;
    std::string aided_by = "the fit's filter pass (input set, priors and observations as the fit), its state recorded at every fix";
    if (!whole) {  // the same filter over the whole drive, to have its state after the window
      FitDriveArgs b = a;
      b.window.clear();
      b.qc = false;
      b.write_out = false;
      b.series.clear();
      b.smooth = false;
      b.on_innovation = nullptr;
      b.coeffs_set = bench;
      record.emplace();
      b.on_epoch = [&record](const Filter& g, const inmotion::RefObs& r, bool took) { record->epoch(g, r, took); };
      fit_drive(b);
      aided_by = "a second pass of the fit's filter (input set, priors and observations as the fit) over the whole "
                 "drive, its state recorded at every fix";
    }
    OutageOptions oo = a.outages;
    oo.logger = logger;
    if (oos) oo.request.earliest_s = t_last;
    std::optional<Vec3> before_mount;
    if (a.coeffs_mounting_deg) before_mount = a.coeffs_mounting_deg->first;
    std::vector<QcSet> sets;
    if (bench) sets.push_back(QcSet{"none", SensorErrors{}, std::nullopt, std::nullopt, EffectTerms{}, std::nullopt});
    sets.push_back(QcSet{bench ? "input" : "none", bench ? bench->errors : SensorErrors{}, before_mount, std::nullopt, fx.terms, std::nullopt});
    sets.push_back(QcSet{"in-motion", total, Vec3(mr / kDeg), std::nullopt, fx.terms, std::nullopt});
    oj = run_outage_qc(a.dir, sets, record->epochs(), oo, aided_by,
                       oos ? "out-of-sample (outages after the fit window)" : "in-sample (outages inside the data the fit used)");
  }
  if (a.qc && !has_ref) {
    if (outages) qj = {{"sample", oj["sample"]}, {"outages", oj}};
    else qj = {{"sample", "not run (no reference.csv: a GNSS-only recording has no reference to navigate against)"}};
  } else if (a.qc) {
    const bool oos = t_data_end > t_last + 10.0;
    const double from = oos ? t_last : t_first;
    std::optional<Vec3> before_mount;
    if (a.coeffs_mounting_deg) before_mount = a.coeffs_mounting_deg->first;
    QcSet before{bench ? "input" : "none", bench ? bench->errors : SensorErrors{}, before_mount, std::nullopt, fx.terms, std::nullopt};
    QcSet after{"in-motion", total, Vec3(mr / kDeg), std::nullopt, fx.terms, std::nullopt};
    std::shared_ptr<const SharedReference> qc_ref = a.shared_reference;
    if (capture) {  // the epochs kept while fitting (the digest is the file's, from the fit's read)
      auto kept = std::make_shared<SharedReference>();
      kept->file = ref_file;
      kept->rows = std::move(oos ? qc_oos : qc_in);
      kept->sha256 = ref_digest.is_string() ? ref_digest.get<std::string>() : std::string();
      qc_ref = std::move(kept);
    }
    const QcOutcome q = run_qc(a.dir, {before, after}, from, a.qc_horizon_s, qc_ref);
    qj = qc_json(q);
    qj["sample"] = oos ? "out-of-sample (after the fit window)" : "in-sample (no data after the fit window)";
    if (outages) qj["outages"] = oj;
  } else {
    qj = {{"sample", "not run"}};
  }
  r.qc = qj;
  read_typed_sections(r, "fit drive result");
  r.extra["approval_preview"] = approval_preview(r, bench, a.thresholds);  // what db approve will say (issue 35 item 6)
  if (a.write_out) write_text_atomic(a.out, drive_result_to_json(r).dump(2) + "\n");
  return r;
}

}  // namespace

}  // namespace calbench
