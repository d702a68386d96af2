// Reading a TOML file for toml++: the text is checked before the library sees it. Debian 12's
// toml++ 3.3.0 reaches __builtin_unreachable (undefined behaviour, a crash in practice) on some
// inputs — a file that starts with a non-ASCII space, or "[" followed by a NUL byte — so bytes
// that TOML forbids outside strings anyway are refused here with the file and line: NUL and other
// control characters (tab, CR, LF allowed), malformed UTF-8, and Unicode spaces and separators.
#pragma once
#include <filesystem>
#include <string>
#include <toml++/toml.h>

namespace calbench {

// Reads the file; InputError (exit 2) naming the file, line and character for what is refused.
std::string read_toml_text(const std::filesystem::path& file);
// The same check on text already in memory.
void check_toml_text(const std::string& text, const std::string& file);
// Reads, checks and parses the file (plans, routes, fixtures); a syntax error is an InputError
// "invalid TOML: ..." with the file and line.
toml::table parse_toml_file(const std::filesystem::path& file);
// The same on text already in memory (checked here), `file` naming it in messages.
toml::table parse_toml_text(const std::string& text, const std::string& file);

}  // namespace calbench
