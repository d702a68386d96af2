#include "bench/console/live_page.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>
#include <vector>

#include "bench/report/html_parts.hpp"
#include "db/station_live.hpp"

namespace calbench::console {
namespace {
using report::html_escape;
using report::num;

std::string age_text(double s) {
  if (!std::isfinite(s)) return "?";
  if (s < 0) s = 0;
  char b[48];
  if (s < 120) std::snprintf(b, sizeof b, "%.0f s", s);
  else if (s < 7200) std::snprintf(b, sizeof b, "%.0f min", s / 60);
  else std::snprintf(b, sizeof b, "%.1f h", s / 3600);
  return b;
}

// The step's progress as a bar: an SVG rectangle (no script, prints as it shows).
std::string bar(double f) {
  const double w = 120 * std::clamp(std::isfinite(f) ? f : 0.0, 0.0, 1.0);
  char b[256];
  std::snprintf(b, sizeof b,
                "<svg width=\"122\" height=\"12\" role=\"img\" aria-label=\"%.0f %%\"><rect x=\"0.5\" y=\"0.5\" width=\"121\" "
                "height=\"11\" fill=\"none\" stroke=\"#888\"/><rect class=\"done\" x=\"1\" y=\"1\" width=\"%.1f\" height=\"10\" "
                "fill=\"#4477aa\"/></svg> %.0f %%",
                100 * f, w, 100 * std::clamp(std::isfinite(f) ? f : 0.0, 0.0, 1.0));
  return b;
}
}  // namespace

std::string live_fragment(db::Store& store, const std::string& csrf, bool may_answer) {
  const double now = db::epoch_now_s();
  const auto rows = db::progress_rows(store, "", db::iso_utc_at(now - 86400));
  const auto prompts = db::waiting_prompts(store);
  // Runs by their newest heartbeat (rows come newest first).
  std::vector<std::string> order;
  std::map<std::string, std::vector<const db::SlotProgress*>> runs;
  for (const auto& r : rows) {
    if (!runs.count(r.run_id)) {
      if (order.size() >= kLiveRuns) continue;
      order.push_back(r.run_id);
    }
    runs[r.run_id].push_back(&r);
  }
  std::ostringstream b;
  b << "<p class=\"note\" id=\"live-summary\">" << order.size()
    << " station run(s) with a heartbeat in the last 24 h, newest first (at most " << kLiveRuns
    << "). Each slot: its plan step, the share of the step's dwell recorded, and the step's data check against its "
       "limit. Updated as the stations write (server-sent events); a running slot without a heartbeat for "
    << kStaleHeartbeatS << " s is marked stale.</p>\n";
  if (order.empty()) b << "<p id=\"no-runs\">No station run is reporting. A run reports here when it is started with "
                          "<code>calbench station run --db</code> on this store.</p>\n";
  for (const auto& run_id : order) {
    auto& slots = runs[run_id];
    std::sort(slots.begin(), slots.end(), [](const auto* a, const auto* c) { return a->slot < c->slot; });
    const db::SlotProgress& f = *slots.front();
    b << "<section class=\"run\" data-run=\"" << html_escape(run_id) << "\"><h2>Run " << html_escape(run_id.substr(0, 8))
      << " on " << html_escape(f.station) << "</h2><p class=\"muted\">started " << html_escape(f.started_at)
      << (f.login.empty() ? "" : " by login " + html_escape(f.login)) << "</p>\n";
    for (const auto& p : prompts) {
      if (p.run_id != run_id) continue;
      const double left = p.timeout_s - db::age_s(p.created_at, now);
      b << "<div class=\"prompt msg\" data-prompt=\"" << p.id << "\"><b>Operator prompt" << (p.slot.empty() ? "" : " (slot " + html_escape(p.slot) + ")")
        << ":</b> <span class=\"text\">" << html_escape(p.text) << "</span> <span class=\"muted\">(asked " << html_escape(p.created_at)
        << ", " << age_text(left) << " left before the run aborts)</span><br>";
      if (may_answer) {
        const std::string hidden = "<input type=\"hidden\" name=\"csrf\" value=\"" + csrf + "\">";
        b << "<form class=\"act\" method=\"post\" action=\"/prompt/" << p.id << "/confirm\">" << hidden
          << "<button class=\"confirm\" type=\"submit\">confirm: done</button></form> <form class=\"act\" method=\"post\" action=\"/prompt/"
          << p.id << "/reject\">" << hidden
          << "<label>reason <input class=\"reason\" name=\"reason\" maxlength=\"4096\" size=\"30\" required></label> "
             "<button class=\"reject\" type=\"submit\">reject: abort the run</button></form>";
      } else {
        b << "<span class=\"muted\">(a station or QC login answers it)</span>";
      }
      b << "</div>\n";
    }
    b << "<table class=\"q live\"><tr><th>slot</th><th>unit</th><th>step</th><th>progress</th><th>step check</th>"
         "<th>state</th><th>why</th><th>heartbeat</th></tr>\n";
    for (const auto* s : slots) {
      const double age = db::age_s(s->heartbeat_at, now);
      const bool stale = (s->state == "running" || s->state == "waiting") && !(age < kStaleHeartbeatS);
      const bool check_ok = !s->check_value || !s->check_limit || *s->check_value <= *s->check_limit;
      const int shown = std::min(s->step_index + 1, s->step_count);
      b << "<tr data-slot=\"" << html_escape(s->slot) << "\" data-state=\"" << html_escape(s->state) << "\" data-step=\""
        << s->step_index << "\"><td>" << html_escape(s->slot) << "</td><td>" << html_escape(s->serial.empty() ? "–" : s->serial)
        << "</td><td class=\"step\">" << (s->step_kind == "done" || s->step_kind == "fit" ? s->step_count : shown) << "/" << s->step_count << " "
        << html_escape(s->step_name) << " <span class=\"muted\">(" << html_escape(s->step_kind) << ")</span></td><td>" << bar(s->step_fraction)
        << "</td><td class=\"check " << (check_ok ? "pass" : "fail") << "\" title=\"" << html_escape(s->check_name) << "\">";
      if (s->check_value && s->check_limit)
        b << num(*s->check_value) << " " << (check_ok ? "≤" : "&gt;") << " " << num(*s->check_limit) << " " << html_escape(s->check_unit);
      else
        b << "–";
      b << "</td><td class=\"state " << (s->state == "passed" ? "pass" : s->state == "failed" || s->state == "aborted" ? "fail" : s->state == "waiting" ? "warn" : "")
        << "\">" << html_escape(s->state) << "</td><td class=\"why\">" << html_escape(s->reason) << "</td><td class=\""
        << (stale ? "fail stale\">no heartbeat for " + age_text(age) + ": station stopped?" : "muted\">" + age_text(age) + " ago")
        << "</td></tr>\n";
    }
    b << "</table></section>\n";
  }
  return b.str();
}

const char* live_js() {
  return R"JS(// calbench console: the live view follows the store (server-sent events from /live/events).
(function () {
  var el = document.getElementById('live'), st = document.getElementById('live-status');
  if (!el || !window.EventSource) return;
  function say(t) { if (st) st.textContent = t; }
  function connect() {
    var es = new EventSource('/live/events');
    es.addEventListener('live', function (e) {
      // Keep what the person is typing into a reject reason.
      var typing = document.activeElement && document.activeElement.classList.contains('reason');
      if (!typing) el.innerHTML = e.data;
      say('live: updated ' + new Date().toLocaleTimeString());
    });
    es.addEventListener('end', function () { es.close(); say('session ended: reload the page'); });
    es.addEventListener('replaced', function () {
      es.close();
      say('live updates paused: a newer page of this session follows the stations; reload to follow here');
    });
    es.onerror = function () {
      if (es.readyState === EventSource.CLOSED) {  // refused (the server's limit of live streams): later
        say('live: the console is busy; trying again shortly');
        setTimeout(connect, 10000 + Math.random() * 10000);
      } else {
        say('live: reconnecting…');
      }
    };
  }
  connect();
})();
)JS";
}

}  // namespace calbench::console
