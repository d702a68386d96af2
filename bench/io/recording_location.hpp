// Where a recording is, for a central store (issue 35 item 8): an absolute URI naming the station's
// host, and one digest of all its files, so that a store far from the station can tell which
// recording a set was fitted on and whether a copy of it is whole.
#pragma once
#include <filesystem>
#include <string>

#include "db/store.hpp"

namespace calbench {

// file://HOST/ABSOLUTE/PATH of `p` (made absolute and normal; HOST: this machine's host name;
// characters outside RFC 3986's unreserved set and '/' percent-encoded).
std::string file_uri(const std::filesystem::path& p);
// SHA-256 over every regular file under `folder`, in the byte order of their paths relative to it
// ('/'-separated): for each file, its relative path, a NUL, its size in decimal, a NUL, its bytes.
// A renamed, added, removed or changed file changes it. InputError when the folder cannot be read.
std::string folder_digest(const std::filesystem::path& folder);
// The location fields of a bench run's recording: the path as given, its URI and, when the folder
// is here to read, its digest (folder_digest; else "").
void describe_recording(db::BenchRunInput& run, const std::filesystem::path& folder);

}  // namespace calbench
