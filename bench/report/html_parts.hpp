// Pieces shared by the report pages (the one HTML helper): escaping, page head, number formatting
// in display units, QC tables, digests.
#pragma once
#include <string>
#include <vector>

#include "db/store.hpp"

namespace calbench::report {

// Text for HTML content and attribute values: & < > " ' escaped.
std::string html_escape(const std::string& s);
// "<!DOCTYPE html>…<title>title</title><style>css</style></head><body>\n" (title escaped).
std::string html_page_start(const std::string& title, const std::string& css);

// v with `sig` significant digits, fixed-point between 1e-4 and 1e7 (else exponent), whole numbers
// without decimals; "–" if not finite.
std::string num(double v, int sig = 4);
// "v ± σ" (SI × k) with σ to two significant digits and v to the same decimal place; "σ unknown"
// when σ is not finite.
std::string pm(double v, double sigma, double k);
// Display unit of a coefficient name and the factor from SI: "°/h", "mg" or "ppm".
void coefficient_unit(const std::string& name, std::string& unit, double& k);
// A SHA-256 digest in full, in a span that wraps anywhere instead of being cut.
std::string digest(const std::string& hex);
// QC results: metric, value, unit, threshold, criterion, in-/out-of-sample, result
// (informative / pass / FAIL). Rows carry data-sample and data-threshold for checks.
std::string qc_table(const std::vector<db::QcResult>& qc, const std::string& id);

}  // namespace calbench::report
