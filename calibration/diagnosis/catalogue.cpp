#include "calibration/diagnosis/catalogue.hpp"

#include <cmath>

namespace calbench {

void predict_extra(const EffectTerms& e, const SubBlock& s, Vec3& dg, Vec3& da) {
  EffectContext c;
  c.w = s.w;
  c.f = s.f;
  c.dw = s.dw;
  c.df = s.df;
  c.temp_c = std::isfinite(s.temp_c) ? s.temp_c : e.t0_c;
  c.dtemp_k_s = std::isfinite(s.temp_c) ? s.dtemp : 0.0;
  c.angle = s.angle;
  c.angle_rate = s.angle_rate;
  c.inner_axis = s.inner_axis;
  sensor_side_terms(e, c, dg, da);
  reference_side_terms(e, c, dg, da);  // time offset, table tilt, wobble (effect_specs.cpp)
}

}  // namespace calbench
