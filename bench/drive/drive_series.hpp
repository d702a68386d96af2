// The --series file of `fit drive`: t_s, every state of the layout in use (series units, names from
// the block declarations, calibration/inmotion/state_blocks.hpp), their sigma_, then the total drift
// per axis (constant + in-run state: what `calbench identify` identifies) and its sigma_. One writer
// for the forward pass and the smoother, so the column layout is stated once.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "bench/io/csv.hpp"
#include "calibration/inmotion/state_blocks.hpp"

namespace calbench {

class DriveSeries {
 public:
  // state_columns: the series names of the filter's layout (InMotionFilter::column_names()).
  DriveSeries(const std::string& path, const std::vector<std::string>& state_columns, const std::string& comment);
  // x, sigma: one value per state column; total, total_sigma: 6 values each.
  void row(double t, const double* x, const double* sigma, const double* total, const double* total_sigma);
  // One row from the filter's SI output (InMotionFilter::state_si, total_drift_si's σ): converted
  // to series units here, at the output (inmotion::series_display, series_total_drift).
  void row_si(double t, const inmotion::StateLayout& layout, Eigen::VectorXd x, Eigen::VectorXd sigma,
              const Eigen::Matrix<double, 6, 1>& total_sigma_si);
  void close() { w_->close(); }

 private:
  int n_;
  std::unique_ptr<CsvWriter> w_;
  std::vector<double> row_;
};

}  // namespace calbench
