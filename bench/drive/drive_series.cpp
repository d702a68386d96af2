#include "bench/drive/drive_series.hpp"

#include <algorithm>

#include "calibration/inmotion/state_layout.hpp"

namespace calbench {

namespace {
std::vector<std::string> series_columns(int n_states) {
  std::vector<std::string> state_cols(inmotion::state_names().begin(), inmotion::state_names().end());
  if (n_states == inmotion::kStatesAug)
    state_cols.insert(state_cols.end(), inmotion::aux_state_names().begin(), inmotion::aux_state_names().end());
  std::vector<std::string> cols(1, "t_s");
  for (const auto& n : state_cols) cols.push_back(n);
  for (const auto& n : state_cols) cols.push_back("sigma_" + n);
  for (const auto& n : inmotion::total_drift_names()) cols.push_back(n);
  for (const auto& n : inmotion::total_drift_names()) cols.push_back("sigma_" + n);
  return cols;
}
}  // namespace

DriveSeries::DriveSeries(const std::string& path, int n_states, const std::string& comment)
    : n_(n_states), w_(std::make_unique<CsvWriter>(path, series_columns(n_states), comment)), row_(w_->columns()) {}

void DriveSeries::row(double t, const double* x, const double* sigma, const double* total, const double* total_sigma) {
  row_[0] = t;
  std::copy(x, x + n_, row_.begin() + 1);
  std::copy(sigma, sigma + n_, row_.begin() + 1 + n_);
  std::copy(total, total + 6, row_.begin() + 1 + 2 * n_);
  std::copy(total_sigma, total_sigma + 6, row_.begin() + 1 + 2 * n_ + 6);
  w_->row(row_.data(), row_.size());
}

}  // namespace calbench
