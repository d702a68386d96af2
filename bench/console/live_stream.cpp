// The live page's server-sent events (/live/events, issue 38; bounded in issue 54 item 10): at most
// kStreamsPerSession streams per session (a newer one ends the oldest with event "replaced") and
// --live-streams in all (beyond: 503 with Retry-After and an SSE retry, and the page's script tries
// again later). Each stream re-checks its session and the account as every request does.
#include <chrono>
#include <thread>

#include "bench/console/console_app.hpp"
#include "bench/console/live_page.hpp"
#include "bench/report/html_parts.hpp"

// Last: httplib.h brings <resolv.h>, whose macro _res breaks Eigen's headers if they come after it.
#include <httplib.h>

namespace calbench::console {
namespace {
using report::html_escape;
constexpr double kStreamS = 300;  // a live page's event stream is renewed (EventSource reconnects) after this
constexpr int kRetryMs = 15000;   // a refused stream's page tries again after about this long

std::string event(const std::string& name, const std::string& data) {
  std::string ev = "event: " + name + "\n";
  std::size_t a = 0;
  while (a <= data.size()) {  // one data: line per line of the data
    const std::size_t e = data.find('\n', a);
    ev += "data: " + data.substr(a, e == std::string::npos ? std::string::npos : e - a) + "\n";
    if (e == std::string::npos) break;
    a = e + 1;
  }
  return ev + "\n";
}
}  // namespace

// The fragment again whenever it changes (checked every 0.5 s), a comment every 15 s to keep proxies
// from closing the stream, "end" when the session has ended, "replaced" when a newer stream of the
// session took this one's place. The stream does not keep the session alive; renewed after kStreamS.
Page Console::live_events(Ctx& c) {
  auto ticket = std::make_shared<StreamTicket>();
  {
    const std::lock_guard<std::mutex> l(streams_m_);
    auto& mine = c.s->streams;
    std::erase_if(mine, [](const std::weak_ptr<StreamTicket>& w) { return w.expired(); });
    const bool replacing = static_cast<int>(mine.size()) >= kStreamsPerSession;
    if (!replacing && streams_open_.load() >= o_.live_streams) {
      c.res.set_header("Retry-After", std::to_string(kRetryMs / 1000));
      return {503, "retry: " + std::to_string(kRetryMs) + "\n" + event("busy", "the console's live streams are all in use") + "",
              "text/event-stream"};
    }
    if (replacing) {
      if (auto old = mine.front().lock()) old->stop = true;
      mine.erase(mine.begin());
    }
    ++streams_open_;
    ticket->open = &streams_open_;
    mine.push_back(ticket);
  }
  auto sess = c.s;
  const std::string token = c.token, address = c.req.remote_addr;
  auto last = std::make_shared<std::string>();
  const auto start = Clock::now();
  auto said = std::make_shared<Clock::time_point>(start);
  c.res.set_header("X-Accel-Buffering", "no");
  c.res.set_chunked_content_provider("text/event-stream", [=, this](std::size_t, httplib::DataSink& sink) {
    const auto send = [&](const std::string& text) { return sink.write(text.data(), text.size()); };
    if (ticket->stop) {
      send(event("replaced", "a newer live page of this session follows the stations"));
      sink.done();
      return true;
    }
    if (!sessions_.find(token, false)) {
      send(event("end", "session ended"));
      sink.done();
      return true;
    }
    std::string frag;
    try {
      const std::lock_guard<std::mutex> l(sess->m);
      db::Store* st = nullptr;
      PgPool::Lease lease;
      if (const std::string why = open_checked(*sess, st, lease); !why.empty()) {
        end_sessions(sess->login, why, address, st);
        send(event("end", "session ended: " + why));
        sink.done();
        return true;
      }
      frag = live_fragment(*st, sess->csrf, may_answer(*sess));
    } catch (const std::exception& e) {
      frag = "<div class=\"msg err\">the store could not be read: " + html_escape(e.what()) + "</div>";
    }
    const auto now = Clock::now();
    if (frag != *last) {
      *last = frag;
      if (!send(event("live", frag))) return false;
      *said = now;
    } else if (now - *said > std::chrono::seconds(15)) {
      if (!send(": keep-alive\n\n")) return false;
      *said = now;
    }
    if (now - start > std::chrono::duration<double>(kStreamS)) {
      sink.done();
      return true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    return sink.is_writable();
  });
  Page p;
  p.streamed = true;
  return p;
}

}  // namespace calbench::console
