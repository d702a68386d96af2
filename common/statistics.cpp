#include "common/statistics.hpp"

#include <algorithm>
#include <cmath>

namespace calbench {

double median_of(std::vector<double> v) {
  if (v.empty()) return NAN;
  const std::size_t m = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<long>(m), v.end());
  const double hi = v[m];
  if (v.size() % 2) return hi;
  const double lo = *std::max_element(v.begin(), v.begin() + static_cast<long>(m));
  return 0.5 * (lo + hi);
}

}  // namespace calbench
