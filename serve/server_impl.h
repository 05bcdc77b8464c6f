#pragma once

// What Server's two files share: its state, and the request handlers (handlers.cc) that
// server.cc routes to.

#include <httplib.h>

#include <chrono>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "serve/index_registry.h"
#include "serve/metrics.h"
#include "serve/request_inputs.h"
#include "serve/server.h"
#include "serve/sessions.h"
#include "serve/work_queue.h"

namespace cwloc {

// A refusal: its HTTP status, the message and the kind /metrics counts it under.
struct HttpError {
  int status;
  std::string message;
  std::string kind;
};

// The 503 of a full queue of `capacity` queries.
std::string BusyMessage(size_t capacity);

// Sets a JSON error body {"error": message, "status": status}.
void SetError(httplib::Response& res, const HttpError& error);

// Recent queries' seconds on a worker, for photos and for features (a photo's SIFT takes 20-50
// times a query's matching): how long before its deadline a waiting request must start to
// finish within --budget-ms, so that a worker does not spend a photo's SIFT on an answer that
// the budget then cuts short.
class ServiceTimes {
 public:
  double Expected(bool photo) const;
  void Add(bool photo, double seconds);

 private:
  mutable std::mutex mutex_;
  double seconds_[2] = {0, 0};  // exponential moving averages: features, photos
};

struct Server::Impl {
  explicit Impl(ServeOptions options_in);

  // Server::Server's stages (server.cc): httplib's limits and timeouts; the hooks every request
  // passes (before routing, httplib's refusals, exceptions, the log line); the routes, whose
  // /v1/admin/reload calls `server`'s Reload.
  void ConfigureHttp();
  void SetHooks();
  void SetRoutes(Server& server);
  // Before routing: CORS, the token, and a query turned away while the queue is full.
  httplib::Server::HandlerResponse PreRoute(const httplib::Request& req, httplib::Response& res);

  // /v1/localize, /v1/geopose, /v1/sessions..., /v1/coverage, /v1/info, /v1/map.
  void Localize(const httplib::Request& req, httplib::Response& res);
  void GeoPose(const httplib::Request& req, httplib::Response& res);
  void StartSession(const httplib::Request& req, httplib::Response& res);
  void SessionFrame(const httplib::Request& req, httplib::Response& res);
  void EndSession(const httplib::Request& req, httplib::Response& res);
  void Coverage(const httplib::Request& req, httplib::Response& res);
  void Info(const httplib::Request& req, httplib::Response& res);
  void Map(const httplib::Request& req, httplib::Response& res);

  // The request's ?index=, or the default; throws HttpError 404.
  std::shared_ptr<const ServedIndex> IndexOf(const httplib::Request& req) const;
  // The server's defaults, and the request's options part or body when it has one.
  RequestInputs InputsOf(const std::string& options_json) const;
  // Runs `work` (a photo's query, or features') on a worker within the request's deadline;
  // throws HttpError 503 when the queue is full or no worker is free early enough to finish
  // by the deadline. `work` may throw HttpError or InputError.
  void RunOnWorker(const std::function<void()>& work, bool photo,
                   WorkQueue::Clock::time_point deadline);
  // The request's deadline under --budget-ms (far away without one).
  WorkQueue::Clock::time_point DeadlineFrom(WorkQueue::Clock::time_point start) const;
  // The localizer's budget for a query whose features are known now: the request's rest.
  void BoundByDeadline(WorkQueue::Clock::time_point deadline, QueryOptions* options) const;

  ServeOptions options;
  RequestLimits limits;
  IndexRegistry registry;
  WorkQueue work;
  SessionTable sessions;
  ServiceTimes service_times;
  Metrics metrics;
  httplib::Server http;
};

}  // namespace cwloc
