// HTML reports from the coefficient database: one printable page per device, and the fleet page
// (docs/database.md "Reports"). Plots are inline SVG (bench/report/svg_plot.hpp) and the bench fit's
// PNG made with gnuplot, embedded as data URIs, so the page is one self-contained file. The page marks
// itself `data-images="LOADED/TOTAL"` on <body> once the browser has decoded its images (used by the
// headless-browser test).
#pragma once
#include <string>

#include "db/approval.hpp"
#include "db/store.hpp"

namespace calbench::report {

// Throws InputError for an unknown serial. The verdict on the current set is checked against
// `thresholds` (those of `db approve`; default_thresholds() unless a file is given).
std::string device_report_html(db::Store& store, const std::string& serial,
                               const db::Thresholds& thresholds = db::default_thresholds());
std::string fleet_report_html(db::Store& store);
// The fleet page without the page around it (the console's fleet dashboard): distributions with
// outliers, per-station drift flags, units per hour.
std::string fleet_report_body(db::Store& store);
// The device report's sections without the page around them (the web console shows them inline,
// bench/console/), and the report's style sheet.
std::string device_report_body(db::Store& store, const std::string& serial, const db::Thresholds& thresholds);
const char* report_css();

}  // namespace calbench::report
