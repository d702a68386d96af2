// The in-motion filter's observation types by name (ObsType's order, inmotion_filter.hpp): the keys
// of RESULT.json "consistency" and of the adaptive noise's events, and the words of its messages.
#pragma once

namespace calbench::inmotion {

inline const char* obs_type_name(int type) {
  static const char* const kNames[] = {"position", "velocity", "attitude", "nhc", "zupt", "zero_rate"};
  return type >= 0 && type < 6 ? kNames[type] : "other";
}

}  // namespace calbench::inmotion
