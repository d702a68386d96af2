#include "bench/multipos/fit_multipos_run.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "bench/io/coefficients_json.hpp"
#include "bench/io/imu_class_toml.hpp"
#include "bench/io/json_util.hpp"
#include "bench/io/message_text.hpp"
#include "bench/io/hdf5_recording.hpp"
#include "calibration/diagnosis/multipos_diagnose.hpp"
#include "bench/io/recording.hpp"
#include "bench/report/svg_plot.hpp"
#include "calibration/earth.hpp"
#include "common/input_error.hpp"
#include "common/units.hpp"

namespace calbench {
namespace {

using namespace units;

nlohmann::json vec_json(const Vec3& v, double k = 1) { return {v(0) * k, v(1) * k, v(2) * k}; }

std::string plot_svg(const multipos::MultiposInput& in, const multipos::MultiposFit& fit) {
  report::PlotCurve gyro{"|ω| (°/s)", {}, {}}, acc{"|f| − g (m/s²) × 10", {}, {}}, stat{"static pose (detected)", {}, {}};
  const std::size_t step = std::max<std::size_t>(1, in.t.size() / 4000);
  std::vector<char> is_static(in.t.size(), 0);
  for (const auto& s : fit.statics)
    for (std::size_t i = s.i0; i < s.i1; ++i) is_static[i] = 1;
  for (std::size_t i = 0; i < in.t.size(); i += step) {
    gyro.x.push_back(in.t[i]);
    gyro.y.push_back(in.gyro[i].norm() / kDeg);
    acc.x.push_back(in.t[i]);
    acc.y.push_back(10 * (in.accel[i].norm() - in.gravity));
    stat.x.push_back(in.t[i]);
    stat.y.push_back(is_static[i] ? 0.0 : std::nan(""));
  }
  report::PlotSpec spec;
  spec.title = "Static poses found (" + std::to_string(fit.statics.size()) + ") and the motion between them";
  spec.x_label = "t [s]";
  spec.y_label = "|ω| [°/s]; (|f| − g)·10 [m/s²]";
  spec.width = 900;
  return report::svg_line_plot({gyro, acc, stat}, spec);
}

// Which figures came from the recording and which from a class (issue 55 item 3).
nlohmann::json figures_from(const MultiposRecording& rec, const multipos::MultiposFit& fit) {
  const std::string cls = "class " + class_name(rec);
  return {{"white_noise", "the recording: gyro from the " + fit.gyro_noise.source + ", accelerometer from the " +
                              fit.accel_noise.source + (rec.class_known ? " (" + cls + ": cross-check)" : std::string())},
          {"static_test", "the recording's white noise"},
          {"bias_stability", rec.class_known ? cls : std::string("wide prior (no device class)")},
          {"gravity", rec.gravity_source}};
}

nlohmann::json fit_json(const MultiposRecording& rec, const multipos::MultiposFit& fit) {
  nlohmann::json j;
  j["method"] = "gravity magnitude (accelerometer) and gravity direction after each rotation (gyro); docs/multipos.md";
  j["frame"] = "x along the accelerometer x axis, y in the accelerometer x-y plane";
  j["gauge_fixed"] = {"accel.M[0][1]", "accel.M[0][2]", "accel.M[1][2]"};
  j["gravity_m_s2"] = rec.input.gravity;
  j["gravity_source"] = rec.gravity_source;
  j["device_class"] = rec.device_class;
  auto noise = [](const multipos::NoiseLevel& n, double k) {
    return nlohmann::json{{"class_per_sample", n.class_sigma > 0 ? nlohmann::json(n.class_sigma * k) : nlohmann::json(nullptr)},
                          {"measured_per_sample", n.used_sigma * k}, {"used_per_sample", n.used_sigma * k},
                          {"source", n.source}, {"quietest_windows_per_sample", n.quiet_sigma * k},
                          {"differs_from_class_2x", n.differs}};
  };
  j["noise"] = {{"gyro_deg_s", noise(fit.gyro_noise, 1 / kDeg)}, {"accel_m_s2", noise(fit.accel_noise, 1)}};
  const multipos::MultiposOptions defaults;
  j["static_test"] = {{"window_samples", fit.window_samples}, {"variance_limit_factor", fit.threshold_factor},
                      {"margin", defaults.margin}, {"alpha", defaults.alpha}, {"min_pose_s", defaults.min_static_s}};
  j["distinct_directions"] = fit.distinct_directions;
  j["figures_from"] = figures_from(rec, fit);
  nlohmann::json st = nlohmann::json::array();
  for (std::size_t k = 0; k < fit.statics.size(); ++k) {
    const auto& s = fit.statics[k];
    st.push_back({{"pose", k}, {"t0_s", s.t0}, {"t1_s", s.t1}, {"samples", s.i1 - s.i0}, {"used", s.used},
                  {"f_mean_m_s2", vec_json(s.f_mean)}, {"w_mean_deg_h", vec_json(s.w_mean, 1 / kDegPerHour)},
                  {"g_residual_raw_m_s2", s.g_residual_raw}, {"g_residual_m_s2", s.g_residual}});
  }
  j["statics"] = st;
  nlohmann::json rt = nlohmann::json::array();
  for (std::size_t k = 0; k < fit.rotations.size(); ++k) {
    const auto& r = fit.rotations[k];
    rt.push_back({{"rotation", k}, {"from_pose", r.from}, {"to_pose", r.to}, {"t0_s", r.t0}, {"t1_s", r.t1},
                  {"used", r.used}, {"angle_raw_deg", vec_json(r.angle_raw, 1 / kDeg)},
                  {"residual_deg", r.residual_rad / kDeg}});
  }
  j["rotations"] = rt;
  j["accel_chi2_dof"] = fit.accel_chi2_dof;
  j["accel_dof"] = fit.accel_dof;
  j["gyro_chi2_dof"] = fit.gyro_chi2_dof;
  j["gyro_dof"] = fit.gyro_dof;
  j["g_spread_raw_m_s2"] = fit.g_spread_raw;
  j["g_spread_m_s2"] = fit.g_spread;
  j["g_loo_rms_m_s2"] = fit.g_loo_rms;
  j["rotation_rms_deg"] = fit.rotation_rms_rad / kDeg;
  j["notes"] = fit.notes;
  // The statics under the class's whole noise model (its drift between poses too): what the
  // approval judges (db/approval_quality.hpp); the fit's own χ²/dof weighs white noise only.
  const MultiposNoiseCheck nc = multipos_noise_check(rec.input, fit, fit.coeffs, rec.noise);
  j["accel_chi2_dof_class"] = nc.accel_chi2_dof;
  j["gyro_chi2_dof_class"] = fit.gyro_chi2_dof_class;
  j["gyro_static_chi2_dof_class"] = {nc.gyro_chi2_dof[0], nc.gyro_chi2_dof[1], nc.gyro_chi2_dof[2]};
  // The QC figure a store of this set can carry (db store-bench --qc): the held-out gravity residual
  // against 3× what a pose of a sound unit of this class shows (white noise of the pose's mean and
  // the class's bias drift).
  {
    double n_mean = 0;
    int nu = 0;
    for (const auto& st : fit.statics)
      if (st.used) n_mean += double(st.i1 - st.i0), ++nu;
    n_mean /= std::max(nu, 1);
    const double pose_sigma = std::sqrt(std::pow(fit.accel_noise.used_sigma, 2) / std::max(n_mean, 1.0) +
                                        std::pow(rec.noise.accel.drift_sigma, 2));
    j["qc_g_loo_limit_m_s2"] = 3 * pose_sigma;
  }
  j["class_noise_note"] =
      "accel_chi2_dof_class: gravity-magnitude residuals over the static poses (N - 9 dof) under white noise plus the "
      "class's bias drift between poses; gyro_static_chi2_dof_class: each gyro's static mean rate (N - 1 dof) with the "
      "Earth rate as noise (calibration/diagnosis/multipos_diagnose.hpp); gyro_chi2_dof_class: the gravity direction after "
      "the rotations under white noise and the class's bias wander (calibration/multipos/multipos_fit.cpp)";
  return j;
}

std::string coeff_text(const SensorErrors& e) {
  std::ostringstream os;
  os << std::fixed;
  auto triad = [&](const char* name, const TriadErrors& t, double kb, const char* ub) {
    os << "  " << name << " bias [" << ub << "]:";
    for (int i = 0; i < 3; ++i) os << " " << std::setprecision(2) << t.bias(i) * kb << " ± " << t.sigma_bias(i) * kb;
    os << "\n  " << name << " M [ppm] (row i: axis i towards x, y, z):\n";
    for (int i = 0; i < 3; ++i) {
      os << "   ";
      for (int j = 0; j < 3; ++j) {
        if (t.sigma_M(i, j) == 0 && t.M(i, j) == 0) os << "  " << std::setw(20) << "0 (frame)";
        else
          os << "  " << std::setw(9) << std::setprecision(0) << t.M(i, j) * 1e6 << " ± " << std::setw(6)
             << t.sigma_M(i, j) * 1e6;
      }
      os << "\n";
    }
  };
  triad("gyro", e.gyro, 1 / kDegPerHour, "°/h");
  triad("accel", e.accel, 1 / kMilliG, "mg");
  return os.str();
}

// The class of the recording (--device-class, else meta.json device.model), or none for a model no
// class knows: a unit of no known class is normal (issue 55) — its noise is measured on the recording
// (filled in after the fit, fit_multipos_set) and its drift priors are wide.
void choose_multipos_class(const std::string& option, const std::string& model, const std::string& mf, MultiposRecording& r) {
  auto& in = r.input;
  if (option.empty() && !find_builtin_imu_class(model)) {
    r.class_known = false;
    r.device_class = {{"name", nullptr},
                      {"chosen_by", "none: meta.json device.model '" + model +
                                        "' names no device class (--device-class NAME|FILE gives one)"},
                      {"priors", "wide: gyro bias stability " + number_text(multipos::kWideGyroBiasStability / kDegPerHour) +
                                     " °/h, accelerometer " + number_text(multipos::kWideAccelBiasStability / kMilliG) +
                                     " mg, " + number_text(multipos::kWideBiasTau) + " s"}};
    r.noise = NoiseSpec{};
    r.noise.gyro.drift_sigma = multipos::kWideGyroBiasStability;
    r.noise.accel.drift_sigma = multipos::kWideAccelBiasStability;
    r.noise.gyro.drift_tau_s = r.noise.accel.drift_tau_s = multipos::kWideBiasTau;
    return;
  }
  const ImuClassChoice cls = choose_imu_class(option, model, mf);
  r.device_class = imu_class_json(cls);
  r.noise = cls.cls.noise;
  in.gyro_density = cls.cls.noise.gyro.white_density;
  in.accel_density = cls.cls.noise.accel.white_density;
  in.gyro_bias_stability = cls.cls.noise.gyro.drift_sigma;
  in.accel_bias_stability = cls.cls.noise.accel.drift_sigma;
}

}  // namespace

std::string class_name(const MultiposRecording& r) {
  return r.class_known ? r.device_class.value("name", std::string("?")) : std::string("none (noise measured on the recording)");
}

MultiposRecording read_multipos_recording(const std::string& dir, const std::string& device_class_option) {
  MultiposRecording r;
  const fs::path d(dir);
  const RecordingMeta meta = read_meta(d);
  const std::string mf = (d / "meta.json").string();
  if (meta.kind != RecordingKind::multipos)
    throw InputError(mf, 0, "kind", std::string("expected a multipos recording, got \"") + kind_name(meta.kind) +
                                        "\" (fit bench / fit drive read those)");
  r.device = meta.device;
  choose_multipos_class(device_class_option, meta.device.model, mf, r);
  auto& in = r.input;
  in.rate_hz = meta.imu_rate_hz;
  if (meta.extra.contains("gravity_m_s2")) {
    const auto& g = meta.extra["gravity_m_s2"];
    if (!g.is_number() || !(g.get<double>() >= 9.7 && g.get<double>() <= 9.9))
      throw InputError(mf, 0, "gravity_m_s2", "must be a number within 9.7–9.9 m/s² (gravity on Earth)");
    in.gravity = g.get<double>();
    r.gravity_source = "meta.json gravity_m_s2";
  } else if (meta.site) {
    in.gravity = normal_gravity_ned(meta.site->lat_deg * kDeg, meta.site->h_m).norm();
    r.gravity_source = "meta.json site (WGS-84 normal gravity)";
  } else {
    in.gravity = 9.80665;
    r.gravity_source = "standard gravity 9.80665 m/s² (meta.json has neither site nor gravity_m_s2)";
  }
  if (meta.site) in.lat_rad = meta.site->lat_deg * kDeg;
  ImuReader imu(d / "imu.csv", meta.imu_rate_hz);
  ImuRecord rec;
  while (imu.next(rec)) {
    if (!in.t.empty() && !(rec.t > in.t.back()))
      throw InputError(imu.path(), imu.line(), "t_s", "time does not increase");
    in.t.push_back(rec.t);
    if (imu.form() == ImuForm::increments) {
      if (!(rec.dt > 0)) throw InputError(imu.path(), imu.line(), "t_s", "increment over a non-positive interval");
      in.gyro.push_back(rec.gyro / rec.dt);
      in.accel.push_back(rec.accel / rec.dt);
    } else {
      in.gyro.push_back(rec.gyro);
      in.accel.push_back(rec.accel);
    }
  }
  return r;
}

MultiposSetResult fit_multipos_set(const FitMultiposArgs& a) {
  MultiposSetResult r{read_multipos_recording(a.dir, a.device_class), {}, {}};
  multipos::MultiposOptions opt;
  opt.earth_rate = a.earth_rate;
  opt.exclude_poses = a.exclude_poses;
  opt.exclude_rotations = a.exclude_rotations;
  try {
    r.fit = multipos::fit_multipos(r.rec.input, opt);
  } catch (const multipos::MultiposRefusal& e) {
    throw InputError((fs::path(a.dir) / "imu.csv").string(), 0, "", std::string("cannot calibrate from this recording: ") + e.what());
  } catch (const std::invalid_argument& e) {
    throw InputError(a.dir, 0, "", e.what());
  }
  if (!r.rec.class_known) {  // the white noise the recording showed (the wide drift priors stay)
    r.rec.noise.gyro.white_density = r.fit.gyro_noise.used_sigma / std::sqrt(r.rec.input.rate_hz);
    r.rec.noise.accel.white_density = r.fit.accel_noise.used_sigma / std::sqrt(r.rec.input.rate_hz);
    r.rec.noise.output_rate_hz = r.rec.input.rate_hz;
  }
  r.set.device = r.rec.device;
  r.set.errors = r.fit.coeffs;
  r.set.extra["source"] = {{"kind", "multipos"},
                           {"recording", a.dir},
                           {"imu_sha256", sha256_file(table_file(a.dir, "imu"))}};  // db store-bench checks it
  r.set.extra["multipos"] = fit_json(r.rec, r.fit);
  return r;
}

void run_fit_multipos(const FitMultiposArgs& a, std::ostream& out) {
  const MultiposSetResult r = fit_multipos_set(a);
  const MultiposRecording& rec = r.rec;
  const multipos::MultiposFit& fit = r.fit;
  const CoefficientSet& c = r.set;
  if (!a.plot.empty() && !a.out.empty() && fs::weakly_canonical(a.plot) == fs::weakly_canonical(a.out))
    throw InputError("--plot", 0, "", a.plot + " is also --out: the plot and the coefficients need two files");
  if (!a.plot.empty()) write_text_atomic(a.plot, plot_svg(rec.input, fit) + "\n");  // before --out: a bad path writes nothing
  if (!a.out.empty()) write_coefficients(a.out, c);  // read back before it is renamed into place (write_text_atomic)
  if (a.json) {
    nlohmann::json j = coefficients_to_json(c);
    out << j.dump(2) << "\n";
    return;
  }
  const auto& m = c.extra["multipos"];
  out << "multi-position fit of " << a.dir << " (" << rec.input.t.size() << " samples, " << rec.input.rate_hz << " Hz; "
      << (rec.class_known ? "class " + class_name(rec) : std::string("no device class: noise measured, drift priors wide"))
      << ")\n";
  out << "gravity " << rec.input.gravity << " m/s² from " << rec.gravity_source << "\n";
  out << std::setprecision(4) << "noise per sample, from the recording: gyro " << fit.gyro_noise.used_sigma / kDeg << " °/s ("
      << fit.gyro_noise.source << "), accel " << fit.accel_noise.used_sigma << " m/s² (" << fit.accel_noise.source << ")";
  if (rec.class_known && fit.gyro_noise.class_sigma > 0)
    out << "; the class says " << fit.gyro_noise.class_sigma / kDeg << " °/s and " << fit.accel_noise.class_sigma
        << " m/s² (" << std::setprecision(2) << fit.gyro_noise.used_sigma / fit.gyro_noise.class_sigma << "× and "
        << fit.accel_noise.used_sigma / fit.accel_noise.class_sigma << "×: a cross-check, not the test)";
  out << "\n" << std::setprecision(3) << "static test: " << fit.window_samples << "-sample windows, variance below σ²·"
      << fit.threshold_factor << " (" << m["static_test"].value("margin", 0.0) << "× the χ² bound at α = 1e-4 per window "
      << "and axis); poses of " << m["static_test"].value("min_pose_s", 0.0) << " s or more\n";
  const std::string judged = rec.class_known ? "the class's noise and drift" : "the measured noise and wide drift priors (no class)";
  out << std::fixed << fit.statics.size() << " static poses:";
  for (std::size_t k = 0; k < fit.statics.size(); ++k)
    out << (k % 6 == 0 ? "\n " : "") << " #" << k << " " << std::setprecision(1) << fit.statics[k].t0 << "–"
        << fit.statics[k].t1 << " s" << (fit.statics[k].used ? "" : " (left out)");
  out << "\n" << fit.distinct_directions << " distinct gravity directions among the used poses (within 10° counted once); "
      << fit.rotations.size() << " rotations between consecutive poses\n";
  out << std::setprecision(2) << "gravity magnitude over the poses (RMS of |f| − g): raw " << fit.g_spread_raw * 1e3
      << " mm/s² → calibrated " << fit.g_spread * 1e3 << " mm/s²; χ²/dof " << fit.accel_chi2_dof << " ("
      << fit.accel_dof << " dof, white noise only); under " << judged << " between poses "
      << m.value("accel_chi2_dof_class", 0.0) << " (what the approval judges)\n";
  out << "held out (each pose left out of the fit that judges it): |f| − g RMS " << std::setprecision(2)
      << fit.g_loo_rms * 1e3 << " mm/s²; 3× a sound pose of this class: " << m.value("qc_g_loo_limit_m_s2", 0.0) * 1e3
      << " mm/s²\n";
  out << "gravity direction after each rotation: RMS error " << std::setprecision(3) << fit.rotation_rms_rad / kDeg
      << "°; χ²/dof " << std::setprecision(2) << fit.gyro_chi2_dof << " (" << fit.gyro_dof
      << " dof, white noise only); under " << judged << " " << fit.gyro_chi2_dof_class
      << " (what the approval judges)\n";
  out << coeff_text(fit.coeffs);
  out << "frame: " << m["frame"].get<std::string>() << " (accel M[0][1], M[0][2], M[1][2] are 0 by that definition)\n";
  if (std::max(fit.accel_chi2_dof, fit.gyro_chi2_dof) > 1)
    out << "σ scaled by √(χ²/dof) where χ²/dof > 1: the residual exceeds what the static noise explains\n";
  for (const auto& n : fit.notes) out << "note: " << n << "\n";
  if (!a.out.empty()) out << "coefficients written to " << a.out << "\n";
  if (!a.plot.empty()) out << "plot written to " << a.plot << "\n";
  if (!a.out.empty())
    out << "to store it with its QC (the approval requires one by default): calbench db store-bench --coeffs " << a.out
        << " --recording " << a.dir << " --qc g_loo_rms=" << std::setprecision(6) << fit.g_loo_rms << ":"
        << m.value("qc_g_loo_limit_m_s2", 0.0) << ":m/s2:out-of-sample\n";
}

}  // namespace calbench
