#include "bench/io/plan_toml.hpp"

#include <cmath>
#include <toml++/toml.h>

#include "bench/io/toml_read.hpp"
#include "bench/io/toml_text.hpp"
#include "common/input_error.hpp"
#include "bench/io/message_text.hpp"
#include "common/units.hpp"

namespace calbench {
namespace {

struct Ctx : TomlReader {
  int axis(const toml::table& t, const std::string& prefix, const char* key, int def) const {
    const toml::node* n = t.get(key);
    if (!n) return def;
    const auto s = n->value<std::string>();
    if (const int m = s ? mount_from_name(*s) : -1; m >= 0) return m;
    fail(n, prefix + key,
         "expected an IMU axis: \"x\", \"y\" or \"z\", or a face diagonal (45° wedge fixture): \"xy\", \"yz\" or "
         "\"zx\"");
  }
};

}  // namespace

StationPlan load_plan(const std::filesystem::path& file) {
  using namespace units;
  Ctx c{{file.string()}};
  const toml::table root = parse_toml_file(file);
  c.check_keys(root, "", {"plan", "site", "table", "step", "temperature"});
  StationPlan p;
  int repeat = 1;
  if (const auto* t = root["plan"].as_table()) {
    c.check_keys(*t, "plan.", {"name", "description", "repeat", "fixture", "kind"});
    const std::string pk = c.str(*t, "plan.", "kind", std::string("rates"));
    if (pk != "rates" && pk != "positions")
      c.fail(t->get("kind"), "plan.kind",
             "must be \"rates\" (a rate table) or \"positions\" (a position-only table: static steps only)");
    p.position_only = pk == "positions";
    p.name = c.str(*t, "plan.", "name", std::string(file.stem()));
    p.description = c.str(*t, "plan.", "description", std::string());
    // A multi-unit fixture (bench/fixtures/*.toml), relative to the plan's folder; read by the station.
    if (t->get("fixture")) {
      const std::filesystem::path f = c.str(*t, "plan.", "fixture", std::nullopt);
      if (f.empty()) c.fail(t->get("fixture"), "plan.fixture", "expected the path of a fixture file");
      p.fixture_file = (f.is_absolute() ? f : file.parent_path() / f).lexically_normal().string();
      if (!std::filesystem::is_regular_file(p.fixture_file))
        c.fail(t->get("fixture"), "plan.fixture", "no such fixture file: " + p.fixture_file);
    }
    repeat = static_cast<int>(c.num(*t, "plan.", "repeat", 1.0, 1, 1000));
    if (const toml::node* r = t->get("repeat"); r && !r->is_integer()) c.fail(r, "plan.repeat", "expected an integer");
  } else {
    p.name = file.stem().string();
  }
  if (const auto* t = root["site"].as_table()) {
    c.check_keys(*t, "site.", {"lat_deg", "lon_deg", "h_m"});
    p.site.lat_deg = c.num(*t, "site.", "lat_deg", std::nullopt, -90, 90);
    p.site.lon_deg = c.num(*t, "site.", "lon_deg", std::nullopt, -360, 360);
    p.site.h_m = c.num(*t, "site.", "h_m", 0.0, -500, 10000);
  } else {
    c.fail(root, "site", "missing table [site] (bench latitude/longitude/height)");
  }
  toml::table empty;
  const toml::table* tt = root["table"].as_table();
  const toml::table& t = tt ? *tt : empty;
  c.check_keys(t, "table.", {"max_rate_dps", "max_accel_dps2", "slew_rate_dps", "settle_s", "remount_s",
                              "rate_accuracy_ppm", "position_accuracy_arcsec", "axis_wobble_arcsec"});
  p.table.max_rate = c.num(t, "table.", "max_rate_dps", 500.0, 1, 5000) * kDeg;
  p.table.max_accel = c.num(t, "table.", "max_accel_dps2", 200.0, 1, 10000) * kDeg;
  p.table.slew_rate = c.num(t, "table.", "slew_rate_dps", 60.0, 1, 5000) * kDeg;
  p.table.settle_s = c.num(t, "table.", "settle_s", 2.0, 0, 600);
  p.table.remount_s = c.num(t, "table.", "remount_s", 60.0, 0, 3600);
  p.table.rate_accuracy_rel = c.num(t, "table.", "rate_accuracy_ppm", 1.0, 0, 1e5) * kPpm;
  p.table.position_accuracy = c.num(t, "table.", "position_accuracy_arcsec", 2.0, 0, 36000) * kDeg / 3600.0;
  p.table.axis_wobble = c.num(t, "table.", "axis_wobble_arcsec", 1.0, 0, 36000) * kDeg / 3600.0;

  const toml::array* steps = root["step"].as_array();
  if (!steps || steps->empty()) c.fail(root, "step", "a plan needs at least one [[step]]");
  int mount = 2;
  for (std::size_t i = 0; i < steps->size(); ++i) {
    const std::string pre = "step[" + std::to_string(i + 1) + "].";
    const toml::table* s = (*steps)[i].as_table();
    if (!s) c.fail(&(*steps)[i], "step[" + std::to_string(i + 1) + "]", "expected a table");
    // An operator prompt (issue 38): asked before the next table step, answered from the store.
    if (const auto k = s->get("kind"); k && k->value<std::string>() == std::string("prompt")) {
      c.check_keys(*s, pre, {"kind", "text", "slot", "timeout_s"});
      PlanPrompt pr;
      pr.before_step = p.steps.size();
      pr.text = c.str(*s, pre, "text", std::nullopt);
      if (pr.text.empty() || pr.text.size() > 500) c.fail(s->get("text"), pre + "text", "expected 1 to 500 characters");
      if (pr.text.find_first_not_of(" \t") == std::string::npos)
        c.fail(s->get("text"), pre + "text", "says nothing (only spaces): say what the operator is to do");
      for (const unsigned char ch : pr.text)
        if (ch < 0x20 || ch == 0x7f)
          c.fail(s->get("text"), pre + "text", "contains a control character (a line break, tab, bell…): one line of text");
      pr.slot = c.str(*s, pre, "slot", std::string());
      pr.timeout_s = c.num(*s, pre, "timeout_s", 600.0, 1, 86400);
      pr.line = static_cast<int>(s->source().begin.line);
      p.prompts.push_back(pr);
      continue;
    }
    c.check_keys(*s, pre, {"kind", "label", "mount", "axis", "outer_deg", "inner_deg", "rpy_deg", "rate_dps", "dwell_s"});
    PlanStep st;
    st.line = static_cast<int>(s->source().begin.line);
    const std::string kind = c.str(*s, pre, "kind", std::nullopt);
    st.dwell_s = c.num(*s, pre, "dwell_s", std::nullopt, 0.1, 86400);
    if (kind == "rate" && p.position_only)
      c.fail(s->get("kind"), pre + "kind",
             "a rate step in a positions plan ([plan] kind = \"positions\"): a position-only table has no rate "
             "mode; give static steps only");
    if (kind == "rate") {
      st.kind = StepKind::rate;
      if (!s->get("axis")) c.fail(*s, pre + "axis", "missing key (IMU axis of the rotation: x, y or z)");
      st.mount = c.axis(*s, pre, "axis", 2);
      if (s->get("mount") && c.axis(*s, pre, "mount", st.mount) != st.mount)
        c.fail(s->get("mount"), pre + "mount", "a rate step about an IMU axis needs that axis on the inner (rate) axis");
      st.rate = c.num(*s, pre, "rate_dps", std::nullopt, -1e5, 1e5) * kDeg;
      if (std::abs(st.rate) > p.table.max_rate)
        c.fail(s->get("rate_dps"), pre + "rate_dps", "exceeds the table's max_rate_dps");
      if (st.rate == 0) c.fail(s->get("rate_dps"), pre + "rate_dps", "a rate step needs a non-zero rate (use kind = \"static\")");
      st.outer = c.num(*s, pre, "outer_deg", 0.0, -360, 360) * kDeg;
      st.inner = c.num(*s, pre, "inner_deg", 0.0, -360, 360) * kDeg;
      if (s->get("rpy_deg")) c.fail(s->get("rpy_deg"), pre + "rpy_deg", "not allowed for a rate step");
    } else if (kind == "static") {
      st.kind = StepKind::static_position;
      st.mount = c.axis(*s, pre, "mount", mount);
      if (const toml::node* r = s->get("rpy_deg")) {
        if (s->get("outer_deg") || s->get("inner_deg"))
          c.fail(r, pre + "rpy_deg", "give either rpy_deg or outer_deg/inner_deg, not both");
        const toml::array* a = r->as_array();
        if (!a || a->size() != 3) c.fail(r, pre + "rpy_deg", "expected [roll, pitch, yaw] in degrees");
        double v[3];
        for (int k = 0; k < 3; ++k) {
          auto d = (*a)[static_cast<std::size_t>(k)].value<double>();
          if (!d || !std::isfinite(*d)) c.fail(r, pre + "rpy_deg", "expected three numbers");
          v[k] = *d * kDeg;
        }
        const Mat3 C = (Eigen::AngleAxisd(v[2], Vec3::UnitZ()) * Eigen::AngleAxisd(v[1], Vec3::UnitY()) *
                        Eigen::AngleAxisd(v[0], Vec3::UnitX())).toRotationMatrix();
        if (!solve_table_angles(C, st.mount, st.outer, st.inner, 1e-6))
          c.fail(r, pre + "rpy_deg",
                 "orientation not reachable with this mount: the IMU axis on the inner axis must be perpendicular to "
                 "the outer axis (north)");
      } else {
        st.outer = c.num(*s, pre, "outer_deg", 0.0, -360, 360) * kDeg;
        st.inner = c.num(*s, pre, "inner_deg", 0.0, -360, 360) * kDeg;
      }
      if (s->get("rate_dps")) c.fail(s->get("rate_dps"), pre + "rate_dps", "not allowed for a static step");
    } else {
      c.fail(s->get("kind"), pre + "kind", "must be \"static\", \"rate\" or \"prompt\"");
    }
    // A positions plan is one continuous recording whose fit integrates the gyros between poses: a
    // re-mount by hand between steps is a rotation nobody records.
    if (p.position_only && i > 0 && st.mount != mount)
      c.fail(s->get("mount"), pre + "mount",
             "a positions plan keeps one mount (a re-mount between poses is a rotation the recording misses)");
    st.label = c.str(*s, pre, "label", kind + " " + std::to_string(i + 1));
    mount = st.mount;
    p.steps.push_back(st);
  }
  // [plan] repeat = N: the step list N times (e.g. one cycle per stretch of a temperature ramp).
  if (p.steps.empty()) c.fail(root, "step", "a plan needs at least one table step (static or rate), not only prompts");
  const std::size_t cycle = p.steps.size();
  const std::size_t prompts = p.prompts.size();
  for (int r = 1; r < repeat; ++r) {
    for (std::size_t i = 0; i < cycle; ++i) p.steps.push_back(p.steps[i]);
    for (std::size_t i = 0; i < prompts; ++i) {
      PlanPrompt pr = p.prompts[i];
      pr.before_step += static_cast<std::size_t>(r) * cycle;
      p.prompts.push_back(pr);
    }
  }
  if (const toml::node* tn = root.get("temperature")) {
    const toml::table* tt2 = tn->as_table();
    if (!tt2) c.fail(tn, "temperature", "expected a table [temperature]");
    const toml::table& T = *tt2;
    c.check_keys(T, "temperature.", {"start_c", "chamber", "lag_s", "self_heating_k", "self_heating_tau_s"});
    TemperatureProfile& tp = p.temperature;
    tp.set = true;
    const double start = c.num(T, "temperature.", "start_c", 25.0, -60, 150);
    tp.chamber.push_back({0.0, start});
    if (const toml::node* ch = T.get("chamber")) {
      const toml::array* a = ch->as_array();
      if (!a) c.fail(ch, "temperature.chamber", "expected an array of [time_s, temperature_c] pairs");
      for (std::size_t k = 0; k < a->size(); ++k) {
        const std::string key = "temperature.chamber[" + std::to_string(k + 1) + "]";
        const toml::array* pt = (*a)[k].as_array();
        std::optional<double> ts, tc;
        if (pt && pt->size() == 2) {
          ts = (*pt)[0].value<double>();
          tc = (*pt)[1].value<double>();
        }
        if (!ts || !tc || !std::isfinite(*ts) || !std::isfinite(*tc))
          c.fail(&(*a)[k], key, "expected [time_s, temperature_c] (two numbers)");
        if (*ts < tp.chamber.back().first) c.fail(&(*a)[k], key, "times must not decrease");
        if (*tc < -60 || *tc > 150) c.fail(&(*a)[k], key, "temperature out of range [-60, 150] °C");
        tp.chamber.push_back({*ts, *tc});
      }
    }
    tp.lag_s = c.num(T, "temperature.", "lag_s", 0.0, 0, 86400);
    tp.self_heating_k = c.num(T, "temperature.", "self_heating_k", 0.0, -20, 50);
    tp.self_heating_tau_s = c.num(T, "temperature.", "self_heating_tau_s", 900.0, 1, 86400);
  }
  return p;
}

}  // namespace calbench
