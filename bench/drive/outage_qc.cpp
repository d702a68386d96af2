#include "bench/drive/outage_qc.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <iomanip>
#include <ostream>
#include <sstream>

#include "calibration/effects/effect_registry.hpp"
#include "calibration/inmotion/state_layout.hpp"
#include "calibration/qc/inertial_qc.hpp"
#include "common/input_error.hpp"
#include "common/number_parse.hpp"
#include "common/statistics.hpp"
#include "common/units.hpp"

namespace calbench {

void parse_outage_lengths(const std::string& text, OutageOptions& o) {
  if (text == "none") {
    o.enabled = false;
    return;
  }
  o.enabled = true;
  o.request.lengths_s.clear();
  std::size_t from = 0;
  while (from <= text.size()) {
    const std::size_t c = std::min(text.find(',', from), text.size());
    double v = 0;
    if (!parse_finite_number(std::string_view(text).substr(from, c - from), v) || !(v > 0) || v > 3600)
      throw InputError("--outages", 0, "",
                       "expected outage lengths in seconds, each > 0 and at most 3600, separated by commas (e.g. "
                       "15,30,60), or none; got '" + text + "'");
    o.request.lengths_s.push_back(v);
    from = c + 1;
  }
}

void check_outage_options(const OutageOptions& o) {
  if (o.request.count < 1) throw InputError("--outage-count", 0, "", "expected a whole number >= 1");
  if (!(o.request.gap_s >= 0) || !std::isfinite(o.request.gap_s))
    throw InputError("--outage-gap", 0, "", "expected a finite number of seconds >= 0");
  if (o.nhc)
    throw InputError("--outage-nhc", 0, "",
                     "the non-holonomic constraint is not in this build (issue 34 item 4): outages are navigated "
                     "inertial-only");
}

void OutageRecorder::epoch(const inmotion::InMotionFilter& f, const inmotion::RefObs& r, bool took) {
  double speed = 0;
  if (r.has_vel) speed = r.v_ned.head<2>().norm();
  else if (have_prev_ && r.t > prev_.t)
    speed = ins::geodetic_diff_ned(r.lat, r.lon, r.h, prev_.lat, prev_.lon, prev_.h).head<2>().norm() / (r.t - prev_.t);
  have_prev_ = true;
  prev_ = r;
  const int yaw = f.offset(inmotion::Block::att) + 2;
  const double heading_sigma = std::sqrt(std::max(0.0, f.P()(yaw, yaw)));
  const bool eligible = took && f.heading_known() && heading_sigma <= kOutageMaxHeadingSigmaDeg * units::kDeg &&
                        speed >= kOutageMinSpeed;
  epochs_.push_back({r.t, eligible, f.nav()});
}

namespace {

struct OutageRun {
  std::vector<double> max_m, end_m;
  long fixes = 0;
  std::vector<double> sigma_h;  // the fixes' stated horizontal σ (where gnss.csv gives one)
};

// One pass over the recording for the sets idx (one time offset), every planned outage in turn.
// The start states carry the aided filter's time stamps (its input set's time offset, if any); a
// group with another offset starts at the same state a few milliseconds of its own data apart.
void outage_pass(const std::filesystem::path& dir, const std::vector<QcSet>& sets, const std::vector<std::size_t>& idx,
                 const std::vector<OutageEpoch>& epochs, const qc::OutagePlan& plan, const LoggerCorrection& logger,
                 std::vector<OutageRun>& out) {
  const EffectTerms shift = time_stamp_terms(sets[idx[0]].effects);
  DriveStream st(dir, std::nullopt, time_stamp_offset(shift) != 0 ? &shift : nullptr, Aiding::gnss);
  st.set_logger_correction(logger);
  const Mat3 C_nom = st.nominal_mounting();
  const Vec3 lever = st.lever_arm();
  std::vector<std::optional<ImuEffectCompensator>> comp = qc_compensators(sets, idx);
  std::vector<std::unique_ptr<qc::InertialRun>> runs(idx.size());
  std::size_t next = 0;  // the next outage of the plan
  bool active = false;
  DriveStream::Event e;
  while (st.next(e)) {
    if (!e.is_ref) {
      if (!active && next < plan.outages.size() && e.t > epochs[plan.outages[next].epoch].nav.t + 1e-9) {
        for (std::size_t i = 0; i < idx.size(); ++i) {
          const QcSet& s = sets[idx[i]];
          const Mat3 C = s.mounting_rpy_deg ? ins::dcm_from_rpy(*s.mounting_rpy_deg * units::kDeg) : C_nom;
          runs[i] = std::make_unique<qc::InertialRun>(s.errors, C, lever, epochs[plan.outages[next].epoch].nav);
        }
        active = true;
      }
      if (active)
        for (std::size_t i = 0; i < idx.size(); ++i) qc_imu(*runs[i], comp[i], e);
      continue;
    }
    if (!active) continue;
    const qc::PlannedOutage& po = plan.outages[next];
    if (e.t > po.start_s + po.length_s + 1e-9) {  // past the outage: the next one may start
      active = false;
      ++next;
      continue;
    }
    if (e.t <= po.start_s + 1e-9 || e.t > runs[0]->time() + 1e-6) continue;
    OutageRun& o = out[next];
    ++o.fixes;
    if (e.ref.sigma_pos > 0 && idx[0] == 0) o.sigma_h.push_back(e.ref.sigma_pos);
    for (std::size_t i = 0; i < idx.size(); ++i) {
      const double d = runs[i]->cpe(e.ref);
      o.max_m[idx[i]] = std::max(o.max_m[idx[i]], d);
      o.end_m[idx[i]] = d;
    }
  }
}

double round_mm(double v) { return std::round(v * 1e3) / 1e3; }

}  // namespace

nlohmann::json run_outage_qc(const std::filesystem::path& dir, const std::vector<QcSet>& sets,
                             const std::vector<OutageEpoch>& epochs, const OutageOptions& o, const std::string& aided_by,
                             const std::string& sample) {
  check_outage_options(o);
  if (epochs.size() < 2) throw InputError((dir / "gnss.csv").string(), 0, "", "too few fixes for an outage QC");
  const double span = epochs.back().t - epochs.front().t;
  for (double L : o.request.lengths_s)
    if (L > span && o.lengths_given) {
      std::ostringstream m;
      m << "an outage of " << L << " s is longer than the drive (fixes from " << epochs.front().t << " to "
        << epochs.back().t << " s: " << span << " s)";
      throw InputError("--outages", 0, "", m.str());
    }
  std::vector<double> t(epochs.size());
  std::vector<bool> eligible(epochs.size());
  for (std::size_t k = 0; k < epochs.size(); ++k) {
    t[k] = epochs[k].t;
    eligible[k] = epochs[k].eligible;
  }
  const qc::OutagePlan plan = qc::plan_outages(t, eligible, epochs.back().t, o.request);
  std::vector<OutageRun> runs(plan.outages.size(), OutageRun{std::vector<double>(sets.size(), 0.0), std::vector<double>(sets.size(), 0.0), 0, {}});
  if (!plan.outages.empty())
    for (const auto& g : time_offset_groups(sets)) outage_pass(dir, sets, g, epochs, plan, o.logger, runs);

  nlohmann::json j;
  j["sample"] = sample;
  j["aided_by"] = aided_by;
  j["rule"] = "the lengths cycled count times (in the order given), spread evenly (equal slack before, between and "
              "after them) from the first fix where the aided filter had converged (fix used, heading sigma <= 1 deg) "
              "while moving (>= 1 m/s) to the last fix, gap_s at least between outages; each starts at the first such "
              "fix at or after its planned time";
  j["lengths_s"] = o.request.lengths_s;
  j["count_per_length"] = o.request.count;
  j["gap_s"] = o.request.gap_s;
  j["earliest_s"] = o.request.earliest_s > -1e299 ? nlohmann::json(o.request.earliest_s) : nlohmann::json(nullptr);
  j["start_condition"] = {{"min_speed_m_s", kOutageMinSpeed}, {"max_heading_sigma_deg", kOutageMaxHeadingSigmaDeg}};
  j["nhc"] = o.nhc;
  // The fixes' own noise: the median stated horizontal σ of the fixes the errors were measured
  // against (null: gnss.csv states none). An error below a few σ is the fixes', not the navigation's.
  std::vector<double> sig;
  for (const OutageRun& r : runs) sig.insert(sig.end(), r.sigma_h.begin(), r.sigma_h.end());
  j["fix_sigma_h_m"] = sig.empty() ? nlohmann::json(nullptr) : nlohmann::json(median_of(sig));
  j["error"] = "horizontal distance of the antenna (MEMS position - C_nb * lever arm) from each fix during the outage, "
               "m: the largest (max_m) and at the outage's last fix (end_m)";
  nlohmann::json names = nlohmann::json::array();
  for (const QcSet& s : sets) names.push_back(s.name);
  j["set_names"] = names;
  nlohmann::json list = nlohmann::json::array();
  for (std::size_t k = 0; k < plan.outages.size(); ++k) {
    const qc::PlannedOutage& po = plan.outages[k];
    nlohmann::json mx = nlohmann::json::object(), en = nlohmann::json::object();
    for (std::size_t i = 0; i < sets.size(); ++i) {
      mx[sets[i].name] = round_mm(runs[k].max_m[i]);
      en[sets[i].name] = round_mm(runs[k].end_m[i]);
    }
    list.push_back({{"start_s", std::round(po.start_s * 1e3) / 1e3}, {"length_s", po.length_s}, {"fixes", runs[k].fixes},
                    {"max_m", mx}, {"end_m", en}});
  }
  j["outages"] = list;
  nlohmann::json per_set = nlohmann::json::array();
  for (std::size_t i = 0; i < sets.size(); ++i) {
    nlohmann::json pl = nlohmann::json::array();
    for (double L : o.request.lengths_s) {
      std::vector<double> mx, en;
      for (std::size_t k = 0; k < plan.outages.size(); ++k)
        if (plan.outages[k].length_s == L && runs[k].fixes > 0) {
          mx.push_back(runs[k].max_m[i]);
          en.push_back(runs[k].end_m[i]);
        }
      if (mx.empty()) continue;
      pl.push_back({{"length_s", L}, {"count", mx.size()}, {"median_max_m", round_mm(median_of(mx))},
                    {"max_max_m", round_mm(*std::max_element(mx.begin(), mx.end()))}, {"median_end_m", round_mm(median_of(en))},
                    {"max_end_m", round_mm(*std::max_element(en.begin(), en.end()))}});
    }
    per_set.push_back({{"name", sets[i].name}, {"per_length", pl}});
  }
  j["sets"] = per_set;
  nlohmann::json np = nlohmann::json::array();
  for (const auto& s : plan.not_placed) np.push_back({{"length_s", s.length_s}, {"reason", s.reason}});
  j["not_placed"] = np;
  return j;
}

void print_outage_summary(const nlohmann::json& o, std::ostream& os) {
  os << "  outage QC (" << o["sample"].get<std::string>() << "): " << o["outages"].size() << " simulated GNSS outage(s)";
  if (!o["not_placed"].empty()) os << ", " << o["not_placed"].size() << " not placed (" << o["not_placed"][0]["reason"].get<std::string>() << ")";
  std::size_t rows = 0;
  for (const auto& s : o["sets"]) rows += s["per_length"].size();
  if (rows == 0) {  // nothing to list: say so instead of ending the line with an empty list
    os << "; no outage placed, so no horizontal error to report\n";
    return;
  }
  os << "; horizontal error at the antenna, median / largest of the per-outage maxima:\n";
  for (const auto& s : o["sets"])
    for (const auto& p : s["per_length"])
      os << "    " << std::setw(4) << p["length_s"].get<double>() << " s x" << p["count"].get<long>() << "  set '"
         << s["name"].get<std::string>() << "': " << std::setprecision(3) << p["median_max_m"].get<double>() << " / "
         << p["max_max_m"].get<double>() << " m" << std::setprecision(6) << "\n";
}

}  // namespace calbench
