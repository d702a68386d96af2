// The --series file of `fit drive`: t_s, every state of the layout in use (series units, names from
// the block declarations, calibration/inmotion/state_blocks.hpp), their sigma_, then the total drift
// per axis (constant + in-run state: what `calbench identify` identifies) and its sigma_. One writer
// for the forward pass and the smoother, so the column layout is stated once.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "bench/io/csv.hpp"

namespace calbench {

class DriveSeries {
 public:
  // state_columns: the series names of the filter's layout (InMotionFilter::column_names()).
  DriveSeries(const std::string& path, const std::vector<std::string>& state_columns, const std::string& comment);
  // x, sigma: one value per state column; total, total_sigma: 6 values each.
  void row(double t, const double* x, const double* sigma, const double* total, const double* total_sigma);
  void close() { w_->close(); }

 private:
  int n_;
  std::unique_ptr<CsvWriter> w_;
  std::vector<double> row_;
};

}  // namespace calbench
