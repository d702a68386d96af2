#include "bench/drive/drive_series.hpp"

#include <algorithm>

#include "calibration/inmotion/state_layout.hpp"

namespace calbench {

namespace {
std::vector<std::string> series_columns(const std::vector<std::string>& state_cols) {
  std::vector<std::string> cols(1, "t_s");
  for (const auto& n : state_cols) cols.push_back(n);
  for (const auto& n : state_cols) cols.push_back("sigma_" + n);
  for (const auto& n : inmotion::total_drift_names()) cols.push_back(n);
  for (const auto& n : inmotion::total_drift_names()) cols.push_back("sigma_" + n);
  return cols;
}
}  // namespace

DriveSeries::DriveSeries(const std::string& path, const std::vector<std::string>& state_columns, const std::string& comment)
    : n_(static_cast<int>(state_columns.size())),
      w_(std::make_unique<CsvWriter>(path, series_columns(state_columns), comment)),
      row_(w_->columns()) {}

void DriveSeries::row_si(double t, const inmotion::StateLayout& layout, Eigen::VectorXd x, Eigen::VectorXd sigma,
                         const Eigen::Matrix<double, 6, 1>& total_sigma_si) {
  Eigen::Matrix<double, 6, 1> total, total_sigma;
  inmotion::series_display(layout, x, sigma);
  inmotion::series_total_drift(layout, x, total_sigma_si, total, total_sigma);
  row(t, x.data(), sigma.data(), total.data(), total_sigma.data());
}

void DriveSeries::row(double t, const double* x, const double* sigma, const double* total, const double* total_sigma) {
  row_[0] = t;
  std::copy(x, x + n_, row_.begin() + 1);
  std::copy(sigma, sigma + n_, row_.begin() + 1 + n_);
  std::copy(total, total + 6, row_.begin() + 1 + 2 * n_);
  std::copy(total_sigma, total_sigma + 6, row_.begin() + 1 + 2 * n_ + 6);
  w_->row(row_.data(), row_.size());
}

}  // namespace calbench
