// Blocks of the in-motion error state, each declared once (name, size, SI and display units,
// series column names, whether the smoother corrects it); the offsets are computed from the order
// of the list, not typed by hand. The idea follows open_vins' ov_core Type blocks: a block knows
// its own size and place, the filter asks for them.
//
// Order = the paper's state order (section IV, eq 11); the exp-cosine aux blocks (eqs 35–36) come
// after the default layout so that the default layout is a prefix of the augmented one.
#pragma once
#include <array>
#include <cstddef>

namespace calbench::inmotion {

enum class Block { pos, vel, att, bg, ba, Mg, Ma, mount, dg, da, dg_aux, da_aux, count };

struct BlockSpec {
  Block id;
  const char* name;
  int size;
  const char* const* columns;  // `size` series column names, in state order within the block
  const char* si_unit;       // unit of the estimated error state
  const char* display_unit;  // unit of the series/RESULT columns
  // SI per display unit (e.g. rad/s per °/h): series value = SI / si_per_display. 1 for blocks whose
  // series value is not a linear scaling of the state (position as lat/lon, attitude and mounting as
  // Euler angles are converted by their own code at the output).
  double si_per_display;
  bool sensor;  // a sensor-error block: the smoother corrects its series value (nav blocks it leaves)
  bool aux;     // only in the augmented (exp-cosine) layout
};

// The declarations (state_blocks.cpp); index = static_cast<int>(Block).
const std::array<BlockSpec, static_cast<std::size_t>(Block::count)>& block_specs();

// Offsets from a list of sizes: offset of entry i = sum of the sizes before it. constexpr so that
// the filter's fixed-size layout and a test's extra block use the same rule.
template <std::size_t K>
constexpr std::array<int, K + 1> offsets_from_sizes(const std::array<int, K>& sizes) {
  std::array<int, K + 1> o{};
  for (std::size_t i = 0; i < K; ++i) o[i + 1] = o[i] + sizes[i];
  return o;
}

// Sizes of the blocks in Block order (compile time, for the fixed-size layout).
inline constexpr std::array<int, static_cast<std::size_t>(Block::count)> kBlockSizes = {3, 3, 3, 3, 3, 9, 9, 3, 3, 3, 3, 3};
inline constexpr auto kBlockOffsets = offsets_from_sizes(kBlockSizes);

constexpr int offset_of(Block b) { return kBlockOffsets[static_cast<std::size_t>(b)]; }
constexpr int size_of(Block b) { return kBlockSizes[static_cast<std::size_t>(b)]; }

}  // namespace calbench::inmotion
