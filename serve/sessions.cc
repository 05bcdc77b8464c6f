#include "serve/sessions.h"

#include <random>

namespace cwloc {

std::string SessionTable::Add(std::shared_ptr<Session> session) {
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
  } while (sessions_.count(id) != 0);
  sessions_[id] = {std::move(session), now + time_to_live_};
  return id;
}

std::shared_ptr<Session> SessionTable::Find(const std::string& id) {
  const Clock::time_point now = Clock::now();
  std::lock_guard<std::mutex> lock(mutex_);
  DropExpired(now);
  const auto found = sessions_.find(id);
  if (found == sessions_.end()) return nullptr;
  found->second.expires = now + time_to_live_;
  return found->second.session;
}

bool SessionTable::Remove(const std::string& id) {
  std::lock_guard<std::mutex> lock(mutex_);
  return sessions_.erase(id) > 0;
}

size_t SessionTable::size() {
  std::lock_guard<std::mutex> lock(mutex_);
  DropExpired(Clock::now());
  return sessions_.size();
}

void SessionTable::DropExpired(Clock::time_point now) {
  for (auto it = sessions_.begin(); it != sessions_.end();) {
    it = it->second.expires <= now ? sessions_.erase(it) : std::next(it);
  }
}

}  // namespace cwloc
