#include "bench/drive/reference_info.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>

#include "bench/io/hdf5_recording.hpp"
#include "common/units.hpp"

namespace calbench {
namespace {

std::string g(double v) {
  std::ostringstream s;
  s.precision(4);
  s << v;
  return s.str();
}

// The '#' lines before the header of table `name` of the recording (its CSV file, or the
// "comments" attribute of its HDF5 dataset), joined.
std::string leading_comment(const fs::path& dir, const std::string& name) {
  std::vector<std::string> lines;
  const fs::path file = table_file(dir, name);
  if (file.filename() == kHdf5RecordingFile) {
    lines = hdf5_table_info(file, name).comments;
  } else {
    std::ifstream in(file);
    std::string line;
    while (std::getline(in, line) && !line.empty() && line[0] == '#') lines.push_back(line);
  }
  std::string out;
  for (const std::string& line : lines) {
    const auto b = line.find_first_not_of("# \t");
    if (b == std::string::npos) continue;
    std::string t = line.substr(b);
    while (!t.empty() && (t.back() == '\r' || t.back() == ' ')) t.pop_back();
    out += (out.empty() ? "" : " ") + t;
  }
  return out;
}

using Range = AidingStats::Range;

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

void AidingStats::Range::add(double v) {
  if (!std::isfinite(v)) return;
  lo = std::min(lo, v);
  hi = std::max(hi, v);
}

void AidingStats::add(const DriveRefRow& r) {
  if (n++ == 0) t0 = r.t;
  t1 = r.t;
  sp.add(r.sigma_pos_m);
  sv.add(r.sigma_vel_m_s);
  sa.add(r.sigma_att_deg);
}

void AidingStats::add(const GnssRow& r) {
  if (n++ == 0) t0 = r.t;
  t1 = r.t;
  sp.add(r.sigma_h_m);
  sv.add(r.sigma_v_m);
  with_vel += r.v_ned && std::isfinite(r.sigma_vel_m_s) && r.sigma_vel_m_s < 1e3;
}

namespace {
// GNSS-only aiding: the receiver's fixes are the reference (gnss.csv, antenna = reference origin).
std::string describe_gnss(const fs::path& dir, const RecordingMeta& meta, const inmotion::InMotionConfig& cfg,
                          const AidingStats& st) {
  const std::string kind = leading_comment(dir, "gnss");
  const long n = st.n, with_vel = st.with_vel;
  const double t0 = st.t0, t1 = st.t1;
  const Range &sh = st.sp, &sv = st.sv;
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
                               const inmotion::InMotionConfig& cfg, bool gnss, const AidingStats& st) {
  if (gnss) return describe_gnss(dir, meta, cfg, st);
  const std::string kind = leading_comment(dir, "reference");
  const long n = st.n;
  const double t0 = st.t0, t1 = st.t1;
  const Range &sp = st.sp, &sv = st.sv, &sa = st.sa;
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
