#include "bench/io/drift_models_json.hpp"

#include <cmath>

#include "common/input_error.hpp"
#include "bench/io/json_util.hpp"
#include "common/units.hpp"

namespace calbench {

namespace {
namespace id = identification;
using nlohmann::json;

json matrix_json(const Eigen::Matrix2d& M, int n) {
  json j = json::array();
  for (int i = 0; i < n; ++i) {
    json row = json::array();
    for (int k = 0; k < n; ++k) row.push_back(M(i, k));
    j.push_back(row);
  }
  return j;
}
template <class V>
json vector_json(const V& v, int n) {
  json j = json::array();
  for (int i = 0; i < n; ++i) j.push_back(v(i));
  return j;
}
}  // namespace

json drift_model_json(const id::DriftModel& m, double dt, const std::string& sensor, int axis,
                      const std::string& unit) {
  const id::ShapingFilter f = id::shaping_filter(m);
  const id::DiscreteShapingFilter d = id::discretise(f, dt);
  json j;
  j["model"] = id::drift_model_name(m.kind);
  if (!sensor.empty()) j["sensor"] = sensor;
  if (axis >= 0) j["axis"] = axis;
  j["unit"] = unit;
  j["sigma"] = m.sigma;
  j["alpha"] = m.alpha;
  j["beta"] = m.beta;
  j["T_s"] = 1.0 / m.alpha;
  j["n_states"] = f.n;
  j["equations"] = m.kind == id::DriftModelKind::exponential ? "paper eq 22" : "paper eqs 35-36 (vector-matrix form)";
  j["A"] = matrix_json(f.A, f.n);
  j["G"] = vector_json(f.G, f.n);
  j["H"] = vector_json(f.H, f.n);
  j["P_inf"] = matrix_json(f.P_inf, f.n);
  j["discrete"] = {{"dt_s", dt}, {"Phi", matrix_json(d.Phi, d.n)}, {"Qd", matrix_json(d.Qd, d.n)}};
  return j;
}

std::vector<DriftModelEntry> drift_models_from_json(const json& j, const std::string& file) {
  if (!j.is_object()) throw InputError(file, 0, "", "not a JSON object");
  const json& dm = jreq(j, "drift_models", file, "drift_models");
  if (!dm.is_object()) throw InputError(file, 0, "drift_models", "must be an object");
  std::vector<DriftModelEntry> out;
  for (auto it = dm.begin(); it != dm.end(); ++it) {
    const std::string k = "drift_models." + it.key();
    const json& e = it.value();
    if (!e.is_object()) throw InputError(file, 0, k, "must be an object");
    DriftModelEntry d;
    d.key = it.key();
    const std::string model = jstr(jreq(e, "model", file, k + ".model"), file, k + ".model");
    if (model == "exponential") {
      d.model.kind = id::DriftModelKind::exponential;
    } else if (model == "exp_cosine") {
      d.model.kind = id::DriftModelKind::exp_cosine;
    } else {
      throw InputError(file, 0, k + ".model", "must be \"exponential\" or \"exp_cosine\", not \"" + model + "\"");
    }
    d.model.sigma = jnum(jreq(e, "sigma", file, k + ".sigma"), file, k + ".sigma");
    d.model.alpha = jnum(jreq(e, "alpha", file, k + ".alpha"), file, k + ".alpha");
    d.model.beta = e.contains("beta") ? jnum(e["beta"], file, k + ".beta") : 0.0;
    if (!(d.model.sigma > 0)) throw InputError(file, 0, k + ".sigma", "must be positive");
    if (!(d.model.alpha > 0)) throw InputError(file, 0, k + ".alpha", "must be positive");
    if (!(d.model.beta >= 0)) throw InputError(file, 0, k + ".beta", "must not be negative");
    if (d.model.kind == id::DriftModelKind::exponential) d.model.beta = 0;
    if (e.contains("sensor")) {
      d.sensor = jstr(e["sensor"], file, k + ".sensor");
      if (d.sensor != "gyro" && d.sensor != "accel")
        throw InputError(file, 0, k + ".sensor", "must be \"gyro\" or \"accel\"");
    }
    if (e.contains("axis")) {
      const double a = jnum(e["axis"], file, k + ".axis");
      if (a != 0 && a != 1 && a != 2) throw InputError(file, 0, k + ".axis", "must be 0, 1 or 2");
      d.axis = static_cast<int>(a);
    }
    if (e.contains("unit")) d.unit = jstr(e["unit"], file, k + ".unit");
    out.push_back(std::move(d));
  }
  return out;
}

std::vector<DriftModelEntry> read_drift_models(const std::filesystem::path& file) {
  return drift_models_from_json(read_json_file(file), file.string());
}

std::optional<DriftModelEntry> find_drift_model(const std::vector<DriftModelEntry>& v, const std::string& sensor,
                                                int axis) {
  for (const auto& e : v)
    if (e.sensor == sensor && e.axis == axis) return e;
  return std::nullopt;
}

std::optional<ColumnSensor> column_sensor(const std::string& name) {
  ColumnSensor c;
  const char* rec[6] = {"gx_rad_s", "gy_rad_s", "gz_rad_s", "ax_m_s2", "ay_m_s2", "az_m_s2"};
  for (int k = 0; k < 6; ++k)
    if (name == rec[k]) {
      c.sensor = k < 3 ? "gyro" : "accel";
      c.axis = k % 3;
      c.unit = k < 3 ? "rad/s" : "m/s^2";
      return c;
    }
  const char* ax = "xyz";
  for (const char* part : {"total", "bias", "drift"})
    for (int i = 0; i < 3; ++i) {
      if (name == std::string("gyro_") + part + "_" + ax[i] + "_dph") {
        c.sensor = "gyro";
        c.axis = i;
        c.unit = "deg/h";
        c.si_per_unit = units::kDegPerHour;
        return c;
      }
      if (name == std::string("accel_") + part + "_" + ax[i] + "_mg") {
        c.sensor = "accel";
        c.axis = i;
        c.unit = "mg";
        c.si_per_unit = units::kMilliG;
        return c;
      }
    }
  return std::nullopt;
}

AxisDriftModels assign_drift_models(const std::vector<DriftModelEntry>& v, const std::string& file) {
  AxisDriftModels out;
  for (const DriftModelEntry& e0 : v) {
    DriftModelEntry e = e0;
    const std::string k = "drift_models." + e.key;
    const std::optional<ColumnSensor> cs = column_sensor(e.key);
    if (e.sensor.empty() && cs) e.sensor = cs->sensor;
    if (e.axis < 0 && cs && cs->sensor == e.sensor) e.axis = cs->axis;
    if (e.sensor.empty() || e.axis < 0)
      throw InputError(file, 0, k,
                       "cannot tell which sensor axis this model is for: name the key gx_rad_s … az_m_s2 or "
                       "gyro_total_x_dph … accel_total_z_mg, or give \"sensor\" (gyro|accel) and \"axis\" (0-2)");
    const bool gyro = e.sensor == "gyro";
    double si = 0;
    std::string unit = e.unit;
    if (unit.empty() || unit == "signal") {
      if (!cs)
        throw InputError(file, 0, k + ".unit",
                         "no unit (\"" + e.unit + "\") and the key does not tell it: give \"unit\" (rad/s, m/s^2, deg/h or mg)");
      unit = cs->unit;
    }
    if (unit == "rad/s") si = gyro ? 1.0 : 0.0;
    else if (unit == "deg/h") si = gyro ? units::kDegPerHour : 0.0;
    else if (unit == "m/s^2" || unit == "m/s2") si = gyro ? 0.0 : 1.0;
    else if (unit == "mg") si = gyro ? 0.0 : units::kMilliG;
    else
      throw InputError(file, 0, k + ".unit", "unknown unit \"" + unit + "\" (rad/s, deg/h for gyro; m/s^2, mg for accel)");
    if (si == 0) throw InputError(file, 0, k + ".unit", "unit \"" + unit + "\" does not fit sensor \"" + e.sensor + "\"");
    e.model.sigma *= si;
    e.unit = gyro ? "rad/s" : "m/s^2";
    auto& slot = (gyro ? out.gyro : out.accel)[static_cast<std::size_t>(e.axis)];
    if (slot)
      throw InputError(file, 0, k,
                       "a second model for " + e.sensor + " axis " + std::string(1, "xyz"[e.axis]) + " (also \"" +
                           slot->key + "\"); keep one");
    slot = std::move(e);
  }
  return out;
}

}  // namespace calbench
