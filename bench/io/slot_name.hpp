// The name of a unit's slot (a fixture on the table, a unit on a vehicle): it names the unit's output
// folder, so 1 to 32 letters, digits, '-' or '_'.
#pragma once
#include <cctype>
#include <string>

namespace calbench {

inline constexpr const char* kSlotNameRule = "1 to 32 letters, digits, '-' or '_' (it names a folder)";

inline bool valid_slot_name(const std::string& s) {
  if (s.empty() || s.size() > 32) return false;
  for (const char ch : s)
    if (!(std::isalnum(static_cast<unsigned char>(ch)) || ch == '-' || ch == '_')) return false;
  return true;
}

}  // namespace calbench
