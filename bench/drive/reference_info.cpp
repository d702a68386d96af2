#include "bench/drive/reference_info.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>

#include "common/units.hpp"

namespace calbench {
namespace {

std::string g(double v) {
  std::ostringstream s;
  s.precision(4);
  s << v;
  return s.str();
}

// The '#' lines before the header of a CSV file, joined.
std::string leading_comment(const fs::path& file) {
  std::ifstream in(file);
  std::string line, out;
  while (std::getline(in, line) && !line.empty() && line[0] == '#') {
    const auto b = line.find_first_not_of("# \t");
    if (b == std::string::npos) continue;
    std::string t = line.substr(b);
    while (!t.empty() && (t.back() == '\r' || t.back() == ' ')) t.pop_back();
    out += (out.empty() ? "" : " ") + t;
  }
  return out;
}

struct Range {
  double lo = std::numeric_limits<double>::infinity(), hi = -std::numeric_limits<double>::infinity();
  void add(double v) {
    if (!std::isfinite(v)) return;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  bool any() const { return lo <= hi; }
};

// "0.02 m (sigma_pos_m of reference.csv)" and the like: which σ the filter used for one type.
std::string sigma_text(double override_v, const Range& column, const char* column_name, double fallback,
                       const char* option, const char* unit) {
  if (override_v > 0) return g(override_v) + unit + " (" + option + ")";
  if (column.any())
    return (column.lo == column.hi ? g(column.lo) : g(column.lo) + "–" + g(column.hi)) + unit + " (" +
           column_name + " of reference.csv)";
  return g(fallback) + unit + " (default: reference.csv has no " + column_name + ")";
}

}  // namespace

namespace {
// GNSS-only aiding: the receiver's fixes are the reference (gnss.csv, antenna = reference origin).
std::string describe_gnss(const fs::path& dir, const RecordingMeta& meta, const inmotion::InMotionConfig& cfg) {
  const fs::path file = dir / "gnss.csv";
  const std::string kind = leading_comment(file);
  GnssReader rd(file);
  GnssRow r;
  long n = 0, with_vel = 0;
  double t0 = 0, t1 = 0;
  Range sh, sv;
  while (rd.next(r)) {
    if (n++ == 0) t0 = r.t;
    t1 = r.t;
    sh.add(r.sigma_h_m);
    sv.add(r.sigma_v_m);
    with_vel += r.v_ned && std::isfinite(r.sigma_vel_m_s) && r.sigma_vel_m_s < 1e3;
  }
  std::ostringstream s;
  s << "GNSS receiver only, no reference INS" << (kind.empty() ? "" : " (" + kind + ")") << " (gnss.csv: " << n
    << " fixes over " << g(t1 - t0) << " s";
  if (n > 1 && t1 > t0) s << ", " << g(static_cast<double>(n - 1) / (t1 - t0)) << " Hz";
  s << "; " << with_vel << " with a velocity)";
  s << "; observations used: position (eq 13)";
  auto range = [](const Range& r) { return r.lo == r.hi ? g(r.lo) : g(r.lo) + "–" + g(r.hi); };
  if (sh.any()) s << ", σ horizontal " << range(sh) << " m";
  if (sv.any()) s << ", vertical " << range(sv) << " m";
  if (cfg.obs_vel) s << "; velocity (eq 14) where gnss.csv has it";
  if (!meta.notes.empty()) s << "; recording notes: " << meta.notes;
  return s.str();
}
}  // namespace

std::string describe_reference(const fs::path& dir, const RecordingMeta& meta, const FitDriveArgs& a,
                               const inmotion::InMotionConfig& cfg, bool gnss) {
  if (gnss) return describe_gnss(dir, meta, cfg);
  const fs::path file = dir / "reference.csv";
  const std::string kind = leading_comment(file);
  DriveRefReader rd(file);
  DriveRefRow r;
  long n = 0;
  double t0 = 0, t1 = 0;
  Range sp, sv, sa;
  while (rd.next(r)) {
    if (n++ == 0) t0 = r.t;
    t1 = r.t;
    sp.add(r.sigma_pos_m);
    sv.add(r.sigma_vel_m_s);
    sa.add(r.sigma_att_deg);
  }
  std::ostringstream s;
  s << (kind.empty() ? "reference system not described in reference.csv" : kind) << " (reference.csv: " << n
    << " epochs over " << g(t1 - t0) << " s";
  if (n > 1 && t1 > t0) s << ", " << g(static_cast<double>(n - 1) / (t1 - t0)) << " Hz";
  s << ")";
  std::string used;
  if (cfg.obs_pos)
    used += "position (eq 13), σ " + sigma_text(a.sigma_pos, sp, "sigma_pos_m", cfg.ref_sigma_pos, "--sigma-pos", " m");
  if (cfg.obs_vel)
    used += std::string(used.empty() ? "" : "; ") + "velocity (eq 14), σ " +
            sigma_text(a.sigma_vel, sv, "sigma_vel_m_s", cfg.ref_sigma_vel, "--sigma-vel", " m/s");
  if (cfg.obs_att)
    used += std::string(used.empty() ? "" : "; ") + "attitude (eq 15), σ " +
            sigma_text(a.sigma_att_deg, sa, "sigma_att_deg", cfg.ref_sigma_att / units::kDeg, "--sigma-att", "°");
  s << "; observations used, at most " << g(cfg.obs_rate_hz) << " epochs/s: " << used;
  if (!meta.notes.empty()) s << "; recording notes: " << meta.notes;
  return s.str();
}

}  // namespace calbench
