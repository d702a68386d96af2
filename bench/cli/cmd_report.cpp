// calbench report SERIAL --html OUT.html [--thresholds FILE] | calbench report fleet --html OUT.html
#include <iostream>
#include <memory>

#include "bench/approval_thresholds.hpp"
#include "bench/cli/number_options.hpp"
#include "bench/cli/registry.hpp"
#include "bench/io/json_util.hpp"
#include "bench/report/db_report.hpp"
#include "db/store.hpp"

namespace calbench::cli {
namespace {

struct ReportArgs {
  std::string target, html, db, thresholds;
};

const bool registered = add_command(90, [](CLI::App& app) {
  auto a = std::make_shared<ReportArgs>();
  auto* sub = app.add_subcommand("report", "printable HTML report of a device (or of the fleet) from the database");
  sub->add_option("SERIAL", a->target, "device serial number, or `fleet` for the fleet report")->required();
  sub->add_option("--html", a->html, "output HTML file (self-contained, plots embedded)")->required()
      ->check(non_empty());
  sub->add_option("--db", a->db, "database: a SQLite file or a postgresql:// URI (default: $CALBENCH_DB, else ./calbench.db)");
  sub->add_option("--thresholds", a->thresholds,
                  "approval thresholds (JSON, as for `db approve`) for the verdict; default: the built-in limits of the device's class");
  sub->callback([a] {
    db::OpenOptions o;
    o.read_only = true;
    db::Store s(a->db.empty() ? db::Store::default_path() : a->db, o);
    // Without a file, the defaults of the device's class (as db approve judges its sets).
    std::string model;
    if (a->thresholds.empty() && a->target != "fleet")
      if (const auto d = s.find_device(a->target)) model = d->model;
    const db::Thresholds t = approval_thresholds(a->thresholds, model);
    const std::string html = a->target == "fleet" ? report::fleet_report_html(s) : report::device_report_html(s, a->target, t);
    write_text_atomic(a->html, html);
    std::cout << "report written to " << a->html << "\n";
  });
});

}  // namespace
}  // namespace calbench::cli
