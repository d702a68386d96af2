// The one gnuplot runner of every report (db report, in-motion section, diagnose bench and drive,
// identify): gnuplot (gnuplot-nox) run on a script and data files in a temporary folder; PNG or
// SVG out, embedded in the page (a PNG as a base64 data URI), or written where the script says.
#pragma once
#include <map>
#include <string>
#include <vector>


namespace calbench::report {

// Run gnuplot on `script` with `files` (name → content) in a fresh temporary folder (its working
// directory, removed afterwards). Returns the bytes of the file `output` the script writes there
// ("plot.png" by default; "" when the script writes its outputs elsewhere and nothing is read
// back). Throws std::runtime_error with gnuplot's message when it fails or is missing.
std::string run_gnuplot(const std::string& script, const std::map<std::string, std::string>& files,
                        const std::string& output = "plot.png");

std::string base64(const std::string& bytes);
std::string png_data_uri(const std::string& png);

}  // namespace calbench::report
