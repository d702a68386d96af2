// What the web console parses itself (issue 38), rather than leaving it to cpp-httplib: form bodies
// (application/x-www-form-urlencoded), query strings and the Cookie header. Strict: a malformed
// escape, a NUL or control character, a repeated field, too many fields or an overlong value is an
// InputError naming the field, and nothing is acted on (fuzzed by tests/fuzz/console_request.cpp).
#pragma once
#include <map>
#include <string>
#include <string_view>

namespace calbench::console {

inline constexpr std::size_t kMaxFields = 32;
inline constexpr std::size_t kMaxValueBytes = 4096;  // the store's bound on a text field (db/input_errors.hpp)

// "a=1&b=x%20y" -> {a: "1", b: "x y"} ('+' is a space). Empty input: no fields.
std::map<std::string, std::string> parse_form(std::string_view text);
// "calbench_session=…; other=…" -> {calbench_session: …}. Malformed pairs are skipped (a browser
// may send other sites' cookies for the host); values are not decoded.
std::map<std::string, std::string> parse_cookies(std::string_view header);

}  // namespace calbench::console
