// The station live view (console page /live, issue 38 item 3): every slot of the recent station
// runs from the store's progress rows (db/station_live.hpp) — its step, the progress within it, the
// step's data check against its limit, its state and, for a failed slot, why — and each waiting
// operator prompt with a confirm and a reject form. The page's #live element is this fragment; the
// server sends it again (server-sent events, /live/events) whenever it changes.
#pragma once
#include <string>

#include "db/store.hpp"

namespace calbench::console {

// A running slot whose heartbeat is older than this is shown as stale (the station stopped, crashed or
// lost its store).
inline constexpr double kStaleHeartbeatS = 30;
// Runs shown: those with a heartbeat in the last day, at most this many, newest first.
inline constexpr std::size_t kLiveRuns = 20;

// `csrf`: the session's token for the prompt forms; `may_answer`: the login may answer prompts
// (station or QC; the store refuses others in any case).
std::string live_fragment(db::Store& store, const std::string& csrf, bool may_answer);

// The page's script (asset /assets/live.js): subscribes to /live/events and replaces #live.
const char* live_js();

}  // namespace calbench::console
