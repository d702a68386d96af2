// UTF-8 decoding and the Unicode character classes input checks need (TOML text, operator names).
// Header-only, in the common base.
#pragma once
#include <cstdio>
#include <string>

namespace calbench::utf8 {

// Decodes the character at byte `i` of `s` into `cp` and returns its length in bytes; 0 when the
// bytes there are not valid UTF-8 (bad lead or continuation byte, overlong form, surrogate, beyond
// U+10FFFF, truncated).
inline std::size_t decode(const std::string& s, std::size_t i, unsigned& cp) {
  const auto* p = reinterpret_cast<const unsigned char*>(s.data());
  const std::size_t n = s.size();
  const unsigned c = p[i];
  if (c < 0x80) {
    cp = c;
    return 1;
  }
  const std::size_t len = c >= 0xF5 ? 0 : c >= 0xF0 ? 4 : c >= 0xE0 ? 3 : c >= 0xC2 && c <= 0xDF ? 2 : 0;
  if (len == 0 || i + len > n) return 0;
  cp = len == 2 ? (c & 0x1F) : len == 3 ? (c & 0x0F) : (c & 0x07);
  for (std::size_t k = 1; k < len; ++k) {
    if ((p[i + k] & 0xC0) != 0x80) return 0;
    cp = (cp << 6) | (p[i + k] & 0x3F);
  }
  if ((len == 3 && cp < 0x800) || (len == 4 && (cp < 0x10000 || cp > 0x10FFFF)) || (cp >= 0xD800 && cp <= 0xDFFF)) return 0;
  return len;
}

// "U+00A0".
inline std::string code_point_name(unsigned cp) {
  char b[16];
  std::snprintf(b, sizeof b, "U+%04X", cp);
  return b;
}

// Unicode spaces other than ASCII space (category Zs): they look like a space.
inline bool space_like(unsigned cp) {
  return cp == 0xA0 || cp == 0x1680 || (cp >= 0x2000 && cp <= 0x200A) || cp == 0x202F || cp == 0x205F || cp == 0x3000;
}

// Characters that show nothing or steer the display: C1 controls, line and paragraph separators,
// format characters (soft hyphen, zero-width spaces and joiners, direction marks and overrides,
// word joiner, invisible operators, byte-order mark), fillers, variation selectors and tags.
inline bool invisible(unsigned cp) {
  return (cp >= 0x80 && cp <= 0x9F) || cp == 0xAD || cp == 0x34F || cp == 0x61C || cp == 0x115F || cp == 0x1160 ||
         cp == 0x17B4 || cp == 0x17B5 || cp == 0x180E || (cp >= 0x180B && cp <= 0x180F) || (cp >= 0x200B && cp <= 0x200F) ||
         (cp >= 0x2028 && cp <= 0x202E) || (cp >= 0x2060 && cp <= 0x206F) || cp == 0x3164 || (cp >= 0xFE00 && cp <= 0xFE0F) ||
         cp == 0xFEFF || cp == 0xFFA0 || (cp >= 0xFFF0 && cp <= 0xFFFB) || (cp >= 0xE0000 && cp <= 0xE0FFF);
}

// The script of a letter among those that share look-alike letters (UTS #39 confusables): Latin,
// Greek, Cyrillic; other characters have none here.
enum class Script { none, latin, greek, cyrillic };
inline Script script_of(unsigned cp) {
  if ((cp >= 'A' && cp <= 'Z') || (cp >= 'a' && cp <= 'z') || cp == 0xAA || cp == 0xBA ||
      (cp >= 0xC0 && cp <= 0x24F && cp != 0xD7 && cp != 0xF7) || (cp >= 0x1E00 && cp <= 0x1EFF) ||
      (cp >= 0x2C60 && cp <= 0x2C7F) || (cp >= 0xA720 && cp <= 0xA7FF) || (cp >= 0xFF21 && cp <= 0xFF3A) ||
      (cp >= 0xFF41 && cp <= 0xFF5A))
    return Script::latin;
  if ((cp >= 0x370 && cp <= 0x3FF && cp != 0x37E && cp != 0x387) || (cp >= 0x1F00 && cp <= 0x1FFF)) return Script::greek;
  if ((cp >= 0x400 && cp <= 0x52F) || (cp >= 0x1C80 && cp <= 0x1C8F) || (cp >= 0x2DE0 && cp <= 0x2DFF) ||
      (cp >= 0xA640 && cp <= 0xA69F))
    return Script::cyrillic;
  return Script::none;
}
inline const char* script_name(Script s) {
  switch (s) {
    case Script::latin: return "Latin";
    case Script::greek: return "Greek";
    case Script::cyrillic: return "Cyrillic";
    case Script::none: break;
  }
  return "";
}

}  // namespace calbench::utf8
