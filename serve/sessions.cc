#include "serve/sessions.h"

#include <random>

namespace cwloc {

std::string SessionTable::Add(std::shared_ptr<Session> session, std::string_view opened_by) {
  std::random_device random;  // the system's source: ids must not be guessable
  const Clock::time_point now = Clock::now();
  std::lock_guard<std::mutex> lock(mutex_);
  DropExpired(now);
  if (sessions_.size() >= capacity_) return {};
  std::string id;
  do {
    id.clear();
    for (int i = 0; i < 4; ++i) {
      char hex[9];
      std::snprintf(hex, sizeof(hex), "%08x", static_cast<unsigned>(random()));
      id += hex;
    }
    id += '.';
    id += opened_by;
  } while (sessions_.count(id) != 0 || ended_.count(id) != 0);
  sessions_[id] = {std::move(session), now + time_to_live_};
  return id;
}

bool SessionTable::Reopen(const std::string& id, std::shared_ptr<Session> session) {
  const Clock::time_point now = Clock::now();
  std::lock_guard<std::mutex> lock(mutex_);
  DropExpired(now);
  if (sessions_.size() >= capacity_ || ended_.count(id) != 0) return false;
  // Two frames racing to reopen it: the first one's session stays.
  sessions_.emplace(id, Entry{std::move(session), now + time_to_live_});
  return true;
}

std::shared_ptr<Session> SessionTable::Find(const std::string& id, bool* ended) {
  const Clock::time_point now = Clock::now();
  std::lock_guard<std::mutex> lock(mutex_);
  DropExpired(now);
  const auto found = sessions_.find(id);
  *ended = found == sessions_.end() && ended_.count(id) != 0;
  if (found == sessions_.end()) return nullptr;
  found->second.expires = now + time_to_live_;
  return found->second.session;
}

void SessionTable::Touch(const std::string& id) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (const auto found = sessions_.find(id); found != sessions_.end())
    found->second.expires = Clock::now() + time_to_live_;
}

bool SessionTable::Remove(const std::string& id) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (sessions_.erase(id) == 0) return false;
  Ended(id);
  return true;
}

size_t SessionTable::size() {
  std::lock_guard<std::mutex> lock(mutex_);
  DropExpired(Clock::now());
  return sessions_.size();
}

void SessionTable::DropExpired(Clock::time_point now) {
  for (auto it = sessions_.begin(); it != sessions_.end();) {
    // A session whose frame is running is in use however long the frame takes.
    if (it->second.expires > now || it->second.session->busy) {
      ++it;
      continue;
    }
    Ended(it->first);
    it = sessions_.erase(it);
  }
}

void SessionTable::Ended(const std::string& id) {
  if (!ended_.insert(id).second) return;
  ended_order_.push_back(id);
  if (ended_order_.size() > capacity_) {
    ended_.erase(ended_order_.front());
    ended_order_.pop_front();
  }
}

}  // namespace cwloc
