#include "calibration/effects/effect_registry.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>


namespace calbench {

namespace {

// Slots of an effect in EffectTerms::values, by shape.
int value_slots(const EffectSpec& s) {
  switch (s.shape) {
    // A triad term is a row of one component: both lay out sensor·3·n + p·3 + axis.
    case EffectShape::triad_axis:
    case EffectShape::axis_rows: return 6 * s.nparams;
    case EffectShape::gyro_matrix: return 9;  // p·3 + axis (column-major, as Mat3)
    case EffectShape::vector: return s.nparams;
    case EffectShape::noise: return 4;  // sensor·2 + p
  }
  return 0;
}

struct Registry {
  std::vector<EffectSpec> specs = make_effect_specs();
  std::vector<const EffectSpec*> by_id;
  std::vector<const EffectSpec*> triad_rows, output_rows, reference_rows, time_rows, angle_rows, level_rows;
  Registry() {
    by_id.assign(specs.size(), nullptr);
    int next = 0;
    for (EffectSpec& s : specs) {
      s.offset = next;
      next += value_slots(s);
    }
    if (next > static_cast<int>(std::tuple_size<decltype(EffectTerms::values)>::value))
      throw std::logic_error("effect registry: EffectTerms::values is too small for the catalogue");
    for (const EffectSpec& s : specs) {
      by_id.at(static_cast<std::size_t>(s.id)) = &s;
      if (s.axis_output) triad_rows.push_back(&s);
      if (s.sensor_output) output_rows.push_back(&s);
      if (s.reference_output) reference_rows.push_back(&s);
      if (s.truth_time) time_rows.push_back(&s);
      if (s.truth_table_angle) angle_rows.push_back(&s);
      if (s.truth_level_frame) level_rows.push_back(&s);
    }
    for (const EffectSpec* s : by_id)
      if (!s) throw std::logic_error("effect registry: an EffectId without a spec");
  }
};

const Registry& registry() {
  static const Registry r;
  return r;
}

}  // namespace

double* effect_param(const EffectSpec& s, EffectTerms& e, int sensor, int axis, int p) {
  if (!effect_allows_sensor(s, sensor)) return nullptr;
  int k = -1;
  switch (s.shape) {
    case EffectShape::triad_axis:
    case EffectShape::axis_rows:
      k = axis >= 0 && axis < 3 && p >= 0 && p < s.nparams ? sensor * 3 * s.nparams + p * 3 + axis : -1;
      break;
    case EffectShape::gyro_matrix: k = axis >= 0 && axis < 3 && p >= 0 && p < 3 ? p * 3 + axis : -1; break;
    case EffectShape::vector: k = p >= 0 && p < s.nparams ? p : -1; break;
    case EffectShape::noise: k = p >= 0 && p < 2 ? sensor * 2 + p : -1; break;
  }
  return k < 0 ? nullptr : &e.values[static_cast<std::size_t>(s.offset + k)];
}

namespace {
// First value of a typed view, after checking that the effect has that shape and size.
double* view_base(EffectTerms& e, EffectId id, EffectShape shape, int sensor, int n) {
  const EffectSpec& s = effect_spec(id);
  if (s.shape != shape || (shape == EffectShape::vector && s.nparams != n) || !effect_allows_sensor(s, sensor))
    throw std::logic_error(std::string("effect registry: no such view of ") + s.key);
  return effect_param(s, e, sensor, shape == EffectShape::vector ? -1 : 0, 0);
}
}  // namespace

Eigen::Map<Vec3> effect_triad(EffectTerms& e, EffectId id, int sensor) {
  return Eigen::Map<Vec3>(view_base(e, id, EffectShape::triad_axis, sensor, 3));
}
Eigen::Map<const Vec3> effect_triad(const EffectTerms& e, EffectId id, int sensor) {
  return Eigen::Map<const Vec3>(view_base(const_cast<EffectTerms&>(e), id, EffectShape::triad_axis, sensor, 3));
}
template <int N>
Eigen::Map<Eigen::Matrix<double, N, 1>> effect_vector(EffectTerms& e, EffectId id) {
  return Eigen::Map<Eigen::Matrix<double, N, 1>>(view_base(e, id, EffectShape::vector, effect_spec(id).sensor, N));
}
template <int N>
Eigen::Map<const Eigen::Matrix<double, N, 1>> effect_vector(const EffectTerms& e, EffectId id) {
  return Eigen::Map<const Eigen::Matrix<double, N, 1>>(
      view_base(const_cast<EffectTerms&>(e), id, EffectShape::vector, effect_spec(id).sensor, N));
}
template Eigen::Map<Eigen::Matrix<double, 1, 1>> effect_vector<1>(EffectTerms&, EffectId);
template Eigen::Map<Eigen::Matrix<double, 2, 1>> effect_vector<2>(EffectTerms&, EffectId);
template Eigen::Map<Eigen::Matrix<double, 3, 1>> effect_vector<3>(EffectTerms&, EffectId);
template Eigen::Map<const Eigen::Matrix<double, 1, 1>> effect_vector<1>(const EffectTerms&, EffectId);
template Eigen::Map<const Eigen::Matrix<double, 2, 1>> effect_vector<2>(const EffectTerms&, EffectId);
template Eigen::Map<const Eigen::Matrix<double, 3, 1>> effect_vector<3>(const EffectTerms&, EffectId);
Eigen::Map<Mat3> effect_matrix(EffectTerms& e, EffectId id) {
  return Eigen::Map<Mat3>(view_base(e, id, EffectShape::gyro_matrix, 0, 9));
}
Eigen::Map<const Mat3> effect_matrix(const EffectTerms& e, EffectId id) {
  return Eigen::Map<const Mat3>(view_base(const_cast<EffectTerms&>(e), id, EffectShape::gyro_matrix, 0, 9));
}

bool effect_per_sensor(const EffectSpec& s) {
  return s.shape == EffectShape::triad_axis || s.shape == EffectShape::axis_rows || s.shape == EffectShape::noise;
}

const char* effect_excited_by(const EffectSpec& s) { return s.excited_by ? s.excited_by : s.condition; }

std::string effect_component_name(const EffectSpec& s, int axis, int p) {
  if (s.components_other_axes) return std::string(1, "xyz"[(axis + 1 + p) % 3]);
  std::string keys = s.inject_keys ? s.inject_keys : "";
  for (int k = 0; k < p; ++k) keys = keys.substr(keys.find(',') + 1);
  return keys.substr(0, keys.find(','));
}

void effect_clear(const EffectSpec& s, EffectTerms& e) {
  const auto first = e.values.begin() + s.offset;
  std::fill(first, first + value_slots(s), 0.0);
}

double truth_time(const EffectTerms& e, double t) {
  for (const EffectSpec* s : registry().time_rows) t = s->truth_time(e, t);
  return t;
}

void truth_table_angle(const EffectTerms& e, double& angle, double& rate) {
  for (const EffectSpec* s : registry().angle_rows) s->truth_table_angle(e, angle, rate);
}

void truth_level_frame(const EffectTerms& e, const Mat3& C_b_l, const Vec3& f_b, const Vec3& w_ie_b, Vec3& f, Vec3& w) {
  for (const EffectSpec* s : registry().level_rows) s->truth_level_frame(e, C_b_l, f_b, w_ie_b, f, w);
}

bool needs_rate_derivative(const EffectTerms& e) {
  for (const EffectSpec& s : effect_specs())
    if (s.needs_rate_derivative && effect_present(s, e)) return true;
  return false;
}

double time_stamp_offset(const EffectTerms& e) { return -truth_time(e, 0.0); }

EffectTerms time_stamp_terms(const EffectTerms& e) {
  EffectTerms out = e;
  for (const EffectSpec& s : effect_specs())
    if (s.compensation != DriveCompensation::time_stamp) effect_clear(s, out);
  return out;
}

double effect_value(const EffectSpec& s, const EffectTerms& e, int sensor, int axis, int p) {
  const double* v = effect_param(s, const_cast<EffectTerms&>(e), sensor, axis, p);
  return v ? *v : 0.0;
}

const std::vector<EffectSpec>& effect_specs() { return registry().specs; }
const EffectSpec& effect_spec(EffectId e) { return *registry().by_id.at(static_cast<std::size_t>(e)); }
const char* effect_name(EffectId e) { return effect_spec(e).key; }
int effect_count() { return static_cast<int>(registry().specs.size()); }

bool effect_from_name(const std::string& s, EffectId& e) {
  for (const EffectSpec& x : effect_specs())
    if (s == x.key) {
      e = x.id;
      return true;
    }
  return false;
}

bool effect_allows_sensor(const EffectSpec& s, int sensor) {
  if (effect_per_sensor(s))
    return sensor >= 0 && sensor < 2 && (s.sensors >> sensor & 1u);
  return sensor == s.sensor;
}

bool effect_present(const EffectSpec& s, const EffectTerms& e) {
  switch (s.shape) {
    case EffectShape::triad_axis:
    case EffectShape::axis_rows:
      for (int k = 0; k < 2; ++k)
        if (effect_allows_sensor(s, k))
          for (int a = 0; a < 3; ++a)
            for (int p = 0; p < s.nparams; ++p)
              if (effect_value(s, e, k, a, p) != 0) return true;
      return false;
    case EffectShape::gyro_matrix:
      for (int a = 0; a < 3; ++a)
        for (int p = 0; p < 3; ++p)
          if (effect_value(s, e, s.sensor, a, p) != 0) return true;
      return false;
    case EffectShape::vector:
      for (int p = 0; p < s.nparams; ++p)
        if (effect_value(s, e, s.sensor, -1, p) != 0) return true;
      return false;
    case EffectShape::noise:
      for (int k = 0; k < 2; ++k)
        if (effect_allows_sensor(s, k) && effect_value(s, e, k, -1, 0) > 0) return true;
      return false;
  }
  return false;
}

std::vector<std::string> effect_ids_present(const EffectTerms& e) {
  std::vector<std::string> out;
  for (const EffectSpec& s : effect_specs())
    if (effect_present(s, e)) out.push_back(s.key);
  return out;
}

int Term::nparams() const { return effect_spec(effect).nparams; }

bool Term::touches(int s, int a) const {
  const EffectSpec& x = effect_spec(effect);
  switch (x.shape) {
    case EffectShape::triad_axis:
    case EffectShape::axis_rows:
    case EffectShape::gyro_matrix: return s == sensor && a == axis;
    case EffectShape::vector: return x.shows_on < 0 || s == x.shows_on;
    case EffectShape::noise: return false;
  }
  return false;
}

std::string Term::label() const {
  std::string l = effect_name(effect);
  l += sensor == 0 ? " gyro" : sensor == 1 ? " accel" : " reference";
  if (axis >= 0) l += std::string(" ") + "xyz"[axis];
  return l;
}

void Term::add_param(EffectTerms& e, int p, double v) const {
  if (double* x = effect_param(effect_spec(effect), e, sensor, axis, p)) *x += v;
}

double Term::get_param(const EffectTerms& e, int p) const { return effect_value(effect_spec(effect), e, sensor, axis, p); }

std::vector<Term> candidate_terms() {
  std::vector<Term> out;
  // Per (sensor, axis) terms: the one-parameter triad rows first, then the rows of components.
  for (EffectShape shape : {EffectShape::triad_axis, EffectShape::axis_rows})
    for (int s = 0; s < 2; ++s)
      for (int a = 0; a < 3; ++a)
        for (const EffectSpec& x : effect_specs())
          if (x.shape == shape && effect_allows_sensor(x, s)) out.push_back({x.id, s, a});
  for (const EffectSpec& x : effect_specs()) {
    if (x.shape == EffectShape::gyro_matrix)
      for (int a = 0; a < 3; ++a) out.push_back({x.id, x.sensor, a});
    if (x.shape == EffectShape::vector) out.push_back({x.id, x.sensor, -1});
  }
  return out;
}

std::string term_unit(const Term& t) { return effect_spec(t.effect).si_unit[t.sensor == 0 ? 0 : 1]; }

const EffectSpec& noise_effect_spec() {
  const EffectSpec* found = nullptr;
  for (const EffectSpec& s : effect_specs())
    if (s.shape == EffectShape::noise) {
      if (found) throw std::logic_error("effect registry: more than one noise-model effect");
      found = &s;
    }
  if (!found) throw std::logic_error("effect registry: no noise-model effect");
  return *found;
}

NoiseSpec noise_with_effects(NoiseSpec n, const EffectTerms& e) {
  for (const EffectSpec& s : effect_specs()) {
    if (s.compensation != DriveCompensation::noise_model) continue;
    for (int k = 0; k < 2; ++k) {
      TriadNoise& t = k == 0 ? n.gyro : n.accel;
      const double sigma = effect_value(s, e, k, -1, 0), tau = effect_value(s, e, k, -1, 1);
      if (sigma > 0) {
        t.drift_sigma = sigma;
        if (tau > 0) t.drift_tau_s = tau;
      }
    }
  }
  return n;
}

const char* separation_note(EffectId finding, EffectId alternative) {
  const EffectSpec& f = effect_spec(finding);
  const EffectSpec& a = effect_spec(alternative);
  if (a.lookalike == static_cast<int>(finding)) return a.separation;
  if (f.lookalike == static_cast<int>(alternative)) return f.separation;
  return nullptr;
}

// Sensor-side output of all effects: the per-axis triad terms in catalogue order, then the others.
void sensor_side_terms(const EffectTerms& e, const EffectContext& c, Vec3& dgyro, Vec3& daccel) {
  const double dT = c.temp_c - e.t0_c;
  const Registry& r = registry();
  auto triad_out = [&](int k, const Vec3& x) {
    Vec3 d = Vec3::Zero();
    for (const EffectSpec* s : r.triad_rows) {
      if (!(s->sensors >> k & 1u)) continue;
      // The three axes of a sensor are contiguous (sensor·3 + axis).
      const double* p = &e.values[static_cast<std::size_t>(s->offset + 3 * k)];
      for (int i = 0; i < 3; ++i)
        if (p[i] != 0) d(i) += s->axis_output(p[i], x(i), dT, c);  // a zero term adds nothing
    }
    return d;
  };
  dgyro = triad_out(0, c.w);
  daccel = triad_out(1, c.f);
  for (const EffectSpec* s : r.output_rows) s->sensor_output(e, c, dgyro, daccel);
}

void reference_side_terms(const EffectTerms& e, const EffectContext& c, Vec3& dgyro, Vec3& daccel) {
  for (const EffectSpec* s : registry().reference_rows) s->reference_output(e, c, dgyro, daccel);
}

}  // namespace calbench
