// Exponential-cosine in-run drift of one sensor axis as two augmented states (paper eq 32 →
// eqs 34–36, the vector-matrix form; shaping_filter.hpp builds A, G and P∞, discretise() gives
// the exact Φ and Qd). State pair (aux, drift) = (Δμ, Δμ̃) = (x[0], x[1]); the drift entering the
// sensor model y = (I+M)·true + b + d is d = H·x = x[1] (see shaping_filter.hpp for why it is the
// second state, not the first as the paper's text says).
//   δẋ = A·δx + G·ξ,  A = [[−2α, −b²], [1, 0]],  b² = α² + β².
#include "calibration/inmotion/error_model.hpp"

namespace calbench::inmotion {

void expcos_drift_block(const identification::ShapingFilter& f, int aux, int drift, FRef F) {
  const int idx[2] = {aux, drift};
  for (int r = 0; r < 2; ++r)
    for (int c = 0; c < 2; ++c) F(idx[r], idx[c]) = f.A(r, c);
}

void expcos_drift_noise(const identification::DiscreteShapingFilter& d, int aux, int drift, FRef Q) {
  const int idx[2] = {aux, drift};
  for (int r = 0; r < 2; ++r)
    for (int c = 0; c < 2; ++c) Q(idx[r], idx[c]) = d.Qd(r, c);
}

}  // namespace calbench::inmotion
