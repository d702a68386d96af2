// Harness: what the web console parses itself (bench/console/request_parse.*): a form body or query
// string (parse_form) and a Cookie header (parse_cookies). Input: the bytes, given to both.
// Checks beyond crashes and exceptions other than InputError: a form that parses has at most
// kMaxFields fields, names of 1 to 64 bytes, values of at most kMaxValueBytes without control
// characters other than tab, CR and LF; cookies at most kMaxFields, values bounded.
#include <cstdint>
#include <string>

#include "bench/console/request_parse.hpp"
#include "common/input_error.hpp"
#include "tests/fuzz/fuzz_util.hpp"

using namespace calbench;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view in(reinterpret_cast<const char*>(data), size);
  try {
    const auto form = console::parse_form(in);
    if (form.size() > console::kMaxFields) fuzz::finding("console_request", "too many form fields", std::to_string(form.size()));
    for (const auto& [k, v] : form) {
      if (k.empty() || k.size() > 64) fuzz::finding("console_request", "form field name length", std::to_string(k.size()));
      if (v.size() > console::kMaxValueBytes) fuzz::finding("console_request", "form value too long", k);
      for (const unsigned char c : v)
        if ((c < 0x20 && c != '\t' && c != '\r' && c != '\n') || c == 0x7f)
          fuzz::finding("console_request", "control character in a form value", k);
    }
  } catch (const InputError&) {
  }
  const auto cookies = console::parse_cookies(in);
  if (cookies.size() > console::kMaxFields) fuzz::finding("console_request", "too many cookies", std::to_string(cookies.size()));
  for (const auto& [k, v] : cookies)
    if (v.size() > console::kMaxValueBytes) fuzz::finding("console_request", "cookie value too long", k);
  return 0;
}
