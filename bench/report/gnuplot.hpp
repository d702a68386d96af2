// Plots for the HTML reports: gnuplot (gnuplot-nox) run on a script and data files in a
// temporary folder, PNG out, embedded in the page as a base64 data URI.
#pragma once
#include <map>
#include <string>
#include <vector>

namespace calbench::report {

// Run gnuplot on `script` with `files` (name → content) in a fresh temporary folder; the script
// must write "plot.png" there. Returns the PNG bytes. Throws std::runtime_error with gnuplot's
// message when it fails or is missing.
std::string run_gnuplot(const std::string& script, const std::map<std::string, std::string>& files);

std::string base64(const std::string& bytes);
std::string png_data_uri(const std::string& png);
std::string html_escape(const std::string& s);

}  // namespace calbench::report
