#pragma once

// A stream's frames tracked with the previous pose (POST /v1/sessions): one Tracker per
// session, on the index the session began with. A session not used for its time to live is
// dropped; there are at most a fixed number at once.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>

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

  // A new session's id (32 hex digits from the system's random source); empty when the table
  // is full of sessions that have not expired.
  std::string Add(std::shared_ptr<Session> session);
  // The session, its time to live renewed; null when there is none or it expired.
  std::shared_ptr<Session> Find(const std::string& id);
  bool Remove(const std::string& id);
  size_t size();
  std::chrono::milliseconds time_to_live() const { return time_to_live_; }

 private:
  struct Entry {
    std::shared_ptr<Session> session;
    Clock::time_point expires;
  };
  void DropExpired(Clock::time_point now);

  const std::chrono::milliseconds time_to_live_;
  const size_t capacity_;
  std::mutex mutex_;
  std::map<std::string, Entry> sessions_;
};

}  // namespace cwloc
