#pragma once

// A stream's frames tracked with the previous pose (POST /v1/sessions): one Tracker per
// session, on the index the session began with. A session not used for its time to live is
// dropped; there are at most a fixed number at once.
//
// A session's id is 32 random hex digits, '.', and the base64url of what opened it (the index's
// name and the options): a replica that never held the session (it restarted, or the
// session's replica is gone, docs/serve.md "Behind a reverse proxy") opens it again from its
// id, and its next frame is localized from scratch. A session that ended or expired here stays
// ended.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <string_view>

#include "localizer/tracker.h"
#include "serve/index_registry.h"
#include "serve/request_inputs.h"

namespace cwloc {

struct Session {
  Session(std::shared_ptr<const ServedIndex> index_in, RequestInputs inputs_in)
      : index(std::move(index_in)),
        inputs(std::move(inputs_in)),
        tracker(index->localizer, inputs.options.localizer, inputs.options.tracker) {}

  std::shared_ptr<const ServedIndex> index;  // kept while the session lives, across reloads
  RequestInputs inputs;                      // every frame's defaults
  std::atomic<bool> busy{false};             // a frame is in flight: one at a time
  Tracker tracker;
};

class SessionTable {
 public:
  using Clock = std::chrono::steady_clock;

  SessionTable(std::chrono::milliseconds time_to_live, size_t capacity)
      : time_to_live_(time_to_live), capacity_(capacity) {}

  // A new session's id (32 hex digits from the system's random source, '.', `opened_by`);
  // empty when the table is full of sessions that have not expired.
  std::string Add(std::shared_ptr<Session> session, std::string_view opened_by);
  // A session opened again under its id; false when the table is full.
  bool Reopen(const std::string& id, std::shared_ptr<Session> session);
  // The session, its time to live renewed; null when there is none or it expired, and then
  // `ended` says whether it was here and ended (deleted or expired).
  std::shared_ptr<Session> Find(const std::string& id, bool* ended);
  bool Remove(const std::string& id);
  // Its time to live counted again from now: a frame's answer is made.
  void Touch(const std::string& id);
  size_t size();
  std::chrono::milliseconds time_to_live() const { return time_to_live_; }

 private:
  struct Entry {
    std::shared_ptr<Session> session;
    Clock::time_point expires;
  };
  void DropExpired(Clock::time_point now);
  // Remembers an ended id (the last `capacity_` of them), so that it is not opened again.
  void Ended(const std::string& id);

  const std::chrono::milliseconds time_to_live_;
  const size_t capacity_;
  std::mutex mutex_;
  std::map<std::string, Entry> sessions_;
  std::set<std::string> ended_;
  std::deque<std::string> ended_order_;
};

}  // namespace cwloc
