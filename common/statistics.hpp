// Small order statistics shared by the layers above (fleet statistics, outage QC).
#pragma once
#include <vector>

namespace calbench {

// The median (the mean of the middle two for an even count); NaN for none.
double median_of(std::vector<double> v);

}  // namespace calbench
