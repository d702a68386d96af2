#include "db/approval_quality.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "calibration/imu_class.hpp"
#include "common/coefficients_codec.hpp"
#include "common/input_error.hpp"
#include "common/json_parse.hpp"
#include "calibration/inmotion/adaptive_noise.hpp"
#include "common/units.hpp"

namespace calbench::db {
namespace {
using nlohmann::json;
using namespace calbench::units;

// The observations of an in-motion fit's "consistency" that a band may name (fit drive writes these).
const std::vector<std::string>& nis_observations() {
  static const std::vector<std::string> names = {"position", "velocity", "attitude", "nhc", "zupt", "zero_rate"};
  return names;
}
const char* const kDefaultBand = "default";

std::string fmt(double v, int precision = 4) {
  std::ostringstream s;
  s.precision(precision);
  s << v;
  return s.str();
}
const char* axis_name(int i) { return i == 0 ? "x" : i == 1 ? "y" : "z"; }

double limit_number(const json& v, const std::string& f, const std::string& key) {
  if (!v.is_number()) throw InputError(f, 0, key, std::string("expected a number, got ") + v.type_name());
  const double x = v.get<double>();
  if (!std::isfinite(x) || x < 0) throw InputError(f, 0, key, "expected a finite non-negative number");
  return x;
}
void require_object(const json& v, const std::string& f, const std::string& key) {
  if (!v.is_object()) throw InputError(f, 0, key, std::string("expected an object, got ") + v.type_name());
}
[[noreturn]] void unknown(const std::string& f, const std::string& key, const std::string& expected) {
  throw InputError(f, 0, key, "unknown key (expected " + expected + ")");
}

void parse_bench(const json& v, const std::string& f, FitQualityLimits& q) {
  require_object(v, f, "bench");
  for (auto it = v.begin(); it != v.end(); ++it) {
    const std::string k = "bench." + it.key();
    if (it.key() == "max_chi2_dof") {
      require_object(*it, f, k);
      for (auto e = it->begin(); e != it->end(); ++e) {
        if (e.key() == "gyro") q.max_chi2_dof_gyro = limit_number(*e, f, k + ".gyro");
        else if (e.key() == "accel") q.max_chi2_dof_accel = limit_number(*e, f, k + ".accel");
        else unknown(f, k + "." + e.key(), "gyro, accel");
      }
    } else if (it.key() == "max_systematic_residual") {
      require_object(*it, f, k);
      for (auto kind = it->begin(); kind != it->end(); ++kind) {
        const std::string kk = k + "." + kind.key();
        if (kind.key() != kStepStatic && kind.key() != kStepRate) unknown(f, kk, "static, rate");
        require_object(*kind, f, kk);
        for (auto e = kind->begin(); e != kind->end(); ++e) {
          if (e.key() == "gyro_dph") q.max_residual_gyro[kind.key()] = limit_number(*e, f, kk + ".gyro_dph") * kDegPerHour;
          else if (e.key() == "accel_mg") q.max_residual_accel[kind.key()] = limit_number(*e, f, kk + ".accel_mg") * kMilliG;
          else unknown(f, kk + "." + e.key(), "gyro_dph, accel_mg");
        }
      }
    } else if (it.key() == "require_fit_quality") {
      if (!it->is_boolean()) throw InputError(f, 0, k, "expected true or false");
      q.require_fit_quality = it->get<bool>();
    } else {
      unknown(f, k, "max_chi2_dof, max_systematic_residual, require_fit_quality");
    }
  }
}

void parse_inmotion(const json& v, const std::string& f, FitQualityLimits& q) {
  require_object(v, f, "inmotion");
  for (auto it = v.begin(); it != v.end(); ++it) {
    const std::string k = "inmotion." + it.key();
    if (it.key() != "mean_nis_per_dof") unknown(f, k, "mean_nis_per_dof");
    require_object(*it, f, k);
    for (auto e = it->begin(); e != it->end(); ++e) {
      const std::string kk = k + "." + e.key();
      const auto& names = nis_observations();
      if (e.key() != kDefaultBand && std::find(names.begin(), names.end(), e.key()) == names.end())
        unknown(f, kk, "default, position, velocity, attitude, nhc, zupt, zero_rate");
      if (!e->is_array() || e->size() != 2) throw InputError(f, 0, kk, "expected a band [LOW, HIGH] of mean NIS per degree of freedom");
      const double lo = limit_number((*e)[0], f, kk + "[0]"), hi = limit_number((*e)[1], f, kk + "[1]");
      if (!(lo < hi)) throw InputError(f, 0, kk, "expected LOW < HIGH, got [" + fmt(lo) + ", " + fmt(hi) + "]");
      q.nis_band[e.key()] = {lo, hi};
    }
  }
}

void parse_combined(const json& v, const std::string& f, FitQualityLimits& q) {
  require_object(v, f, "combined");
  for (auto it = v.begin(); it != v.end(); ++it) {
    const std::string k = "combined." + it.key();
    if (it.key() == "max_move_sigmas") q.max_move_sigmas = limit_number(*it, f, k);
    else if (it.key() == "max_sigma_growth") {
      q.max_sigma_growth = limit_number(*it, f, k);
      if (q.max_sigma_growth < 1) throw InputError(f, 0, k, "expected a factor ≥ 1 (a σ that does not grow is never refused)");
    } else unknown(f, k, "max_move_sigmas, max_sigma_growth");
  }
}

// ---- the checks ----
void bench_reasons(const BenchFitQuality& b, const FitQualityLimits& q, std::vector<std::string>& why) {
  for (const bool gyro : {true, false}) {
    const char* triad = gyro ? "gyro" : "accel";
    const Vec3& chi2 = gyro ? b.gyro_chi2_dof : b.accel_chi2_dof;
    const double lim = gyro ? q.max_chi2_dof_gyro : q.max_chi2_dof_accel;
    for (int i = 0; i < 3; ++i)
      if (chi2(i) > lim)
        why.push_back(std::string("bench fit ") + triad + " " + axis_name(i) + ": χ²/dof = " + fmt(chi2(i), 3) +
                      " exceeds " + fmt(lim) + " (the residuals are larger than the noise model: an effect the model "
                      "lacks, or a bench fault; calbench diagnose names the effect)");
    const double unit = gyro ? kDegPerHour : kMilliG;
    const char* un = gyro ? "°/h" : "mg";
    const auto& limits = gyro ? q.max_residual_gyro : q.max_residual_accel;
    for (const auto& L : largest_residuals(b, gyro)) {
      const auto it = limits.find(L.kind);
      if (it == limits.end() || L.value <= it->second) continue;
      why.push_back(std::string("bench fit ") + triad + ": largest systematic residual of the " +
                    (L.kind == kStepStatic ? "static positions" : "rate steps") + " = " + fmt(L.value / unit, 3) + " " +
                    un + " (step " + std::to_string(L.step) + ", axis " + axis_name(L.axis) + ") exceeds " +
                    fmt(it->second / unit) + " " + un);
    }
  }
}

void nis_reasons(const std::map<std::string, NisConsistency>& nis, const FitQualityLimits& q, std::vector<std::string>& why) {
  for (const auto& [obs, c] : nis) {
    if (!c.mean_nis || !c.epochs || *c.epochs <= 0) continue;  // no epochs: nothing to judge
    auto band = q.nis_band.find(obs);
    if (band == q.nis_band.end()) band = q.nis_band.find(kDefaultBand);
    if (band == q.nis_band.end()) continue;
    const double dof = c.expected_nis && *c.expected_nis > 0 ? *c.expected_nis : 3.0;  // eqs 13–15: three components
    const double per = *c.mean_nis / dof;
    const auto [lo, hi] = band->second;
    if (per >= lo && per <= hi) continue;
    why.push_back("in-motion NIS " + obs + ": mean " + fmt(*c.mean_nis, 3) + " over " + std::to_string(*c.epochs) +
                  " epochs = " + fmt(per, 3) + " per degree of freedom, outside the band " + fmt(lo) + " – " + fmt(hi) +
                  (per > hi ? " (innovations larger than the filter predicts: assumed noise too small, or an error the "
                              "model lacks)"
                            : " (innovations smaller than predicted: the assumed noise is too large, the σ overstated)"));
  }
}

// A run whose filter scaled the IMU's noise beyond the limit is no calibration: its consistent NIS
// was bought by following the fixes (calibration/inmotion/adaptive_noise.hpp).
void adaptive_reasons(const AdaptiveNoiseSummary& a, std::vector<std::string>& why) {
  if (!(a.scale_end > inmotion::AdaptiveNoise::kFailScale)) return;
  why.push_back("in-motion filter: the navigation noise variance was scaled ×" + fmt(a.scale_end, 3) +
                " at the end of the fit (limit " + fmt(inmotion::AdaptiveNoise::kFailScale) +
                "): the filter followed the fixes with the IMU's noise scaled away, so its coefficients and NIS do not "
                "rest on the IMU (RESULT.json adaptive_noise; docs/in-motion.md, \"Adaptive process noise\")");
}

struct Display {
  double unit;
  const char* name;
};
Display display_of(const std::string& coefficient) {
  if (coefficient.find(".M.") != std::string::npos) return {kPpm, "ppm"};
  return coefficient.rfind("gyro", 0) == 0 ? Display{kDegPerHour, "°/h"} : Display{kMilliG, "mg"};
}
double allowance_of(const inmotion::StabilityAllowance& a, const std::string& coefficient) {
  const bool gyro = coefficient.rfind("gyro", 0) == 0;
  if (coefficient.find(".bias.") != std::string::npos) return gyro ? a.gyro_bias : a.accel_bias;
  const std::string ij = coefficient.substr(coefficient.size() - 2);
  const bool diag = ij[0] == ij[1];
  return gyro ? (diag ? a.gyro_scale : a.gyro_skew) : (diag ? a.accel_scale : a.accel_skew);
}

void parent_reasons(const CoefficientSetRecord& set, const CoefficientSetRecord& p, const FitQualityLimits& q,
                    std::vector<std::string>& why) {
  const auto cls = q.allowances.find(normalized_model_name(set.model));
  const inmotion::StabilityAllowance none{};
  const inmotion::StabilityAllowance& a = cls == q.allowances.end() ? none : cls->second;
  const std::string whose = cls == q.allowances.end() ? "no device class for model '" + set.model + "': allowance 0"
                                                      : a.device_class + " allowance";
  const std::string ref = p.id > 0 ? "parent set " + std::to_string(p.id) : std::string("input set");  // id 0: fit drive's --coeffs
  for (const auto& name : coefficient_names()) {
    const double vp = coefficient_value(p.errors, name), sp = coefficient_sigma(p.errors, name);
    const double vc = coefficient_value(set.errors, name), sc = coefficient_sigma(set.errors, name);
    if (!std::isfinite(sp)) continue;  // the parent does not know it: nothing to compare against
    const Display d = display_of(name);
    const auto pm = [&](double v, double s) {
      return fmt(v / d.unit) + " ± " + (std::isfinite(s) ? fmt(s / d.unit, 3) : std::string("unknown")) + " " + d.name;
    };
    const double al = allowance_of(a, name), bound = q.max_move_sigmas * std::hypot(sp, al);
    if (std::abs(vc - vp) > bound)
      why.push_back("combined " + name + " moved " + fmt((vc - vp) / d.unit) + " " + d.name + " from the " + ref + " (" +
                    pm(vp, sp) + " → " + pm(vc, sc) + "), more than " + fmt(q.max_move_sigmas) + "·√(σ_parent² + allowance²) = " +
                    fmt(bound / d.unit) + " " + d.name + " (" + whose + " " + fmt(al / d.unit) + " " + d.name + ")");
    if (!std::isfinite(sc))
      why.push_back("combined " + name + ": σ unknown where the " + ref + " states " + pm(vp, sp));
    else if (sc > q.max_sigma_growth * sp)
      why.push_back("combined " + name + ": σ grew from " + fmt(sp / d.unit, 3) + " to " + fmt(sc / d.unit, 3) + " " + d.name +
                    " (" + fmt(sc / sp, 3) + "× the " + ref + "'s, limit " + fmt(q.max_sigma_growth) + "×): " + pm(vp, sp) +
                    " → " + pm(vc, sc) + "; the drive knows it less well than the bench did");
  }
}
}  // namespace

FitQualityLimits default_fit_quality_limits() {
  FitQualityLimits q;
  // Measured (docs/database.md, "Fit quality"): factory-plan simulations of good units give χ²/dof
  // 0.89–1.10 and systematic residuals up to 22 °/h and 0.24 mg (in-run drift inside a step); an
  // unmodelled g-sensitivity of 33 °/h/g gives χ²/dof 81 and 413 °/h.
  for (const char* kind : {kStepStatic, kStepRate}) {
    q.max_residual_gyro[kind] = 60 * kDegPerHour;
    q.max_residual_accel[kind] = 1 * kMilliG;
  }
  // Mean NIS per degree of freedom: 1 for a consistent filter; the real drives give 0.62–1.72.
  q.nis_band[kDefaultBand] = {0.1, 2.0};
  return q;
}

bool parse_fit_quality_key(const std::string& key, const json& v, const std::string& f, FitQualityLimits& q) {
  if (key == "bench") parse_bench(v, f, q);
  else if (key == "inmotion") parse_inmotion(v, f, q);
  else if (key == "combined") parse_combined(v, f, q);
  else return false;
  return true;
}

std::vector<std::string> describe_fit_quality(const FitQualityLimits& q) {
  std::vector<std::string> out;
  std::string r;
  for (const auto& [kind, lim] : q.max_residual_gyro) r += (r.empty() ? "" : ", ") + kind + " gyro ≤ " + fmt(lim / kDegPerHour, 6) + " °/h";
  for (const auto& [kind, lim] : q.max_residual_accel) r += (r.empty() ? "" : ", ") + kind + " accel ≤ " + fmt(lim / kMilliG, 6) + " mg";
  out.push_back("bench fit: χ²/dof per axis ≤ " + fmt(q.max_chi2_dof_gyro, 6) + " (gyro), " + fmt(q.max_chi2_dof_accel, 6) +
                " (accel); largest systematic residual per step kind: " + r +
                (q.require_fit_quality ? "; a bench set must carry these figures" : "; checked where the set carries them"));
  std::string b;
  for (const auto& [obs, band] : q.nis_band) b += (b.empty() ? "" : ", ") + obs + " " + fmt(band.first, 6) + " – " + fmt(band.second, 6);
  out.push_back("in-motion NIS, mean per degree of freedom inside: " + b + " (where the run records it)");
  out.push_back("combined set against its parent: every move ≤ " + fmt(q.max_move_sigmas, 6) +
                "·√(σ_parent² + allowance²) (device class stability allowance), every σ ≤ " + fmt(q.max_sigma_growth, 6) +
                "× the parent's");
  return out;
}

FitEvidence fit_evidence(Store& store, const CoefficientSetRecord& set) {
  FitEvidence ev;
  const std::string where = "set " + std::to_string(set.id);
  try {
    const CoefficientSet c = coefficients_from_json(parse_json_text(set.payload_json, where), where);
    ev.bench = c.fit_quality;
    if (const auto m = c.extra.find("multipos"); m != c.extra.end()) {
      const auto num = [&](const char* k) {
        if (!m->is_object() || !m->contains(k) || !(*m)[k].is_number() || !std::isfinite((*m)[k].get<double>()))
          throw InputError(where, 0, std::string("multipos.") + k, "missing or not a finite number");
        return (*m)[k].get<double>();
      };
      ev.multipos_chi2 = std::make_pair(num("accel_chi2_dof_class"), num("gyro_chi2_dof_class"));
    }
  } catch (const InputError& e) {
    ev.problems.push_back(std::string("fit quality of the set unreadable: ") + e.what());
  }
  if (set.inmotion_run_id) {
    if (const auto run = store.inmotion_run(*set.inmotion_run_id); run && !run->consistency_json.empty()) {
      const std::string rw = "in-motion run " + std::to_string(run->id) + " consistency";
      try {
        ev.nis = nis_consistency_from_json(parse_json_text(run->consistency_json, rw), rw);
        if (!run->result_json.empty()) {
          const DriveResult dr = drive_result_from_json(parse_json_text(run->result_json, "in-motion run " + std::to_string(run->id)),
                                                        "in-motion run " + std::to_string(run->id));
          if (dr.adaptive_noise) ev.adaptive = dr.adaptive_noise;
        }
      } catch (const InputError& e) {
        ev.problems.push_back(std::string("innovation consistency unreadable: ") + e.what());
      }
    }
  }
  if (set.parent_id) ev.parent = store.find_set(*set.parent_id);
  return ev;
}

std::vector<std::string> fit_quality_reasons(const CoefficientSetRecord& set, const FitEvidence& ev, const FitQualityLimits& q) {
  std::vector<std::string> why = ev.problems;
  if (ev.multipos_chi2) {
    const auto [a, g] = *ev.multipos_chi2;
    if (!(a <= q.max_chi2_dof_accel))
      why.push_back("multipos fit: accelerometer χ²/dof " + fmt(a, 3) + " above " + fmt(q.max_chi2_dof_accel) +
                    " (gravity-magnitude residuals beyond the class's noise and drift: diagnose the recording)");
    if (!(g <= q.max_chi2_dof_gyro))
      why.push_back("multipos fit: gyro χ²/dof " + fmt(g, 3) + " above " + fmt(q.max_chi2_dof_gyro) +
                    " (the gravity direction after the rotations is predicted worse than the noise allows: fit multipos --json "
                    "lists each rotation's residual_deg; a bad turn can be left out with --exclude-rotation K, a wrong gyro "
                    "conversion shows in every turn)");
  }
  if (ev.bench) bench_reasons(*ev.bench, q, why);
  else if (q.require_fit_quality && set.source == SetSource::bench && !ev.multipos_chi2)
    why.push_back("bench fit quality not recorded with the set (no fit_quality in its coefficients: refit with calbench fit bench)");
  if (ev.nis) nis_reasons(*ev.nis, q, why);
  if (ev.adaptive) adaptive_reasons(*ev.adaptive, why);
  if (ev.parent && set.source == SetSource::combined) parent_reasons(set, *ev.parent, q, why);
  return why;
}

}  // namespace calbench::db
