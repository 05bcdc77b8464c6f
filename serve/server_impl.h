#pragma once

// What Server's two files share: its state, and the request handlers (handlers.cc) that
// server.cc routes to.

#include <chrono>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "serve/http_server.h"
#include "serve/index_registry.h"
#include "serve/metrics.h"
#include "serve/request_inputs.h"
#include "serve/server.h"
#include "serve/sessions.h"
#include "serve/viewer_assets.h"
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
void SetError(HttpResponse& res, const HttpError& error);

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

  // The HTTP layer's callbacks (server.cc): a request screened before its body is read (CORS,
  // the token, a query turned away while the queue is full), routed, its deferred work run on
  // a worker, a refusal made, an answer logged.
  HttpCallbacks Callbacks(Server& server);
  std::optional<HttpResponse> Screen(const HttpRequest& req);
  void AllowOrigin(HttpResponse& res) const;
  void Route(Server& server, HttpRequest& req, HttpResponse& res);
  void RunDeferred(DeferredWork work, std::shared_ptr<HttpResponse> res,
                   std::function<void()> done);
  void Log(const HttpRequest& req, const HttpResponse& res, double seconds);
  // GET /metrics, the viewer's files, POST /v1/admin/reload.
  void MetricsPage(HttpResponse& res);
  void ViewerFile(const ViewerAsset& asset, HttpResponse& res);
  void AdminReload(Server& server, HttpResponse& res);

  // /v1/localize, /v1/geopose, /v1/sessions..., /v1/coverage, /v1/info, /v1/map (handlers.cc).
  void Localize(const HttpRequest& req, HttpResponse& res);
  void GeoPose(const HttpRequest& req, HttpResponse& res);
  void StartSession(const HttpRequest& req, HttpResponse& res);
  void SessionFrame(const HttpRequest& req, HttpResponse& res);
  void EndSession(const HttpRequest& req, HttpResponse& res);
  // The session of a frame, opened again from its id when this server never held it; throws
  // HttpError 404 when there is none (or it ended here), 503 when the table is full.
  std::shared_ptr<Session> SessionOf(const std::string& id, HttpResponse& res);
  void Coverage(const HttpRequest& req, HttpResponse& res);
  void Info(const HttpRequest& req, HttpResponse& res);
  void Map(const HttpRequest& req, HttpResponse& res);

  // The request's ?index=, or the default; throws HttpError 404.
  std::shared_ptr<const ServedIndex> IndexOf(const HttpRequest& req) const;
  // The server's defaults, and the request's options part or body when it has one.
  RequestInputs InputsOf(const std::string& options_json) const;
  // Answers with `work` (a photo's query, or features') run on a worker within the request's
  // deadline; 503 when the queue is full or no worker is free early enough to finish by the
  // deadline. `work` fills the response, or throws HttpError or InputError.
  static void Defer(HttpResponse& res, std::function<void(HttpResponse&)> work, bool photo,
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
  std::unique_ptr<HttpServer> http;  // made by Server::Server with Callbacks
};

}  // namespace cwloc
