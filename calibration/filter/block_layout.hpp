// Layout of a filter state made of blocks (as open_vins' ov_core Type blocks: a block knows its
// size, the layout gives it its place). Both filters use it: the in-motion EKF
// (calibration/inmotion/state_blocks.hpp, blocks chosen at run time by the configuration) and the
// bench EKF (calibration/bench_fit_ekf.cpp, a fixed list at compile time). Offsets are computed
// from the sizes, never typed by hand.
#pragma once
#include <array>
#include <cstddef>
#include <stdexcept>
#include <vector>

namespace calbench::filter {

// Offsets from a list of sizes: offset of entry i = sum of the sizes before it (entry K: the total).
template <std::size_t K>
constexpr std::array<int, K + 1> offsets_from_sizes(const std::array<int, K>& sizes) {
  std::array<int, K + 1> o{};
  for (std::size_t i = 0; i < K; ++i) o[i + 1] = o[i] + sizes[i];
  return o;
}

// A run-time layout: blocks appended in order, each identified by a small integer id.
class BlockLayout {
 public:
  // Appends a block; returns its offset. An id may appear once.
  int add(int id, int size) {
    if (id < 0 || size < 0) throw std::invalid_argument("BlockLayout: negative id or size");
    if (static_cast<std::size_t>(id) >= offset_.size()) offset_.resize(static_cast<std::size_t>(id) + 1, -1);
    if (offset_[static_cast<std::size_t>(id)] >= 0) throw std::invalid_argument("BlockLayout: a block added twice");
    offset_[static_cast<std::size_t>(id)] = size_;
    ids_.push_back(id);
    size_ += size;
    return offset_[static_cast<std::size_t>(id)];
  }
  // Offset of a block, −1 when it is not in the layout.
  int offset(int id) const {
    return id >= 0 && static_cast<std::size_t>(id) < offset_.size() ? offset_[static_cast<std::size_t>(id)] : -1;
  }
  bool has(int id) const { return offset(id) >= 0; }
  int size() const { return size_; }
  const std::vector<int>& ids() const { return ids_; }  // in layout order

 private:
  std::vector<int> offset_, ids_;
  int size_ = 0;
};

}  // namespace calbench::filter
