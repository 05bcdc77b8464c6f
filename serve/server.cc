#include "serve/server.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <new>
#include <nlohmann/json.hpp>
#include <thread>

#include "base/error.h"
#include "serve/server_impl.h"
#include "serve/viewer_assets.h"

namespace cwloc {
namespace {

using Clock = WorkQueue::Clock;

// The endpoint a path counts under in /metrics: a session's id is left out.
std::string EndpointOf(const std::string& path) {
  static const char* const kEndpoints[] = {"/v1/localize", "/v1/geopose", "/v1/coverage",
                                           "/v1/info",     "/v1/map",     "/v1/admin/reload",
                                           "/healthz",     "/metrics",    "/"};
  for (const char* endpoint : kEndpoints) {
    if (path == endpoint) return endpoint;
  }
  if (path == "/v1/sessions") return path;
  if (path.rfind("/v1/sessions/", 0) == 0)
    return path.size() > 7 && path.substr(path.size() - 7) == "/frames" ? "/v1/sessions/{id}/frames"
                                                                        : "/v1/sessions/{id}";
  if (path.rfind("/viewer/", 0) == 0) return "/viewer";
  return "other";
}

// Takes as long whichever byte differs, so a token cannot be guessed byte by byte.
bool ConstantTimeEqual(const std::string& a, const std::string& b) {
  if (a.size() != b.size()) return false;
  unsigned char difference = 0;
  for (size_t i = 0; i < a.size(); ++i) difference |= static_cast<unsigned char>(a[i] ^ b[i]);
  return difference == 0;
}

}  // namespace

std::string BusyMessage(size_t capacity) {
  return "busy: " + std::to_string(capacity) + " queries wait already (--queue); retry later";
}

void SetError(HttpResponse& res, const HttpError& error) {
  res.status = error.status;
  nlohmann::ordered_json body;
  body["error"] = error.message;
  body["status"] = error.status;
  res.SetContent(body.dump(), "application/json");
  if (error.status == 503) res.SetHeader("Retry-After", "1");
}

Server::Impl::Impl(ServeOptions options_in)
    : options(std::move(options_in)),
      registry(options.indexes, options.verify),
      work(options.threads, options.queue),
      sessions(std::chrono::milliseconds(static_cast<int64_t>(options.session_ttl_s * 1000)),
               options.max_sessions) {
  limits.max_image_pixels = options.defaults.photo.max_image_pixels;
}

namespace {

// The options with their defaults filled in; throws InputError for one out of its range.
ServeOptions Checked(ServeOptions options) {
  if (options.threads == 0) options.threads = std::max(1u, std::thread::hardware_concurrency());
  if (options.threads < 1 || options.threads > 1024)
    throw InputError("--threads must be between 1 and 1024");
  if (options.queue == 0)
    options.queue = kQueuedQueriesPerWorker * static_cast<size_t>(options.threads);
  const HttpLimits& http = options.http;
  if (http.max_connections < 1 || http.max_connections > 10000)
    throw InputError("--max-connections must be between 1 and 10000");
  if (!(http.request_timeout_s > 0) || !(http.write_timeout_s > 0))
    throw InputError("--request-timeout and --write-timeout must be more than 0 seconds");
  if (!(http.min_body_rate > 0)) throw InputError("--min-body-rate must be more than 0");
  if (!(options.session_ttl_s > 0)) throw InputError("--session-ttl must be more than 0 seconds");
  // One query per worker: a photo's SIFT runs on the worker's thread alone.
  options.defaults.photo.sift.num_threads = 1;
  return options;
}

}  // namespace

Server::Server(ServeOptions options) {
  impl_ = std::make_unique<Impl>(Checked(std::move(options)));
  impl_->http = std::make_unique<HttpServer>(impl_->options.http, impl_->Callbacks(*this));
}

HttpCallbacks Server::Impl::Callbacks(Server& server) {
  HttpCallbacks callbacks;
  callbacks.screen = [this](const HttpRequest& req) { return Screen(req); };
  callbacks.handle = [this, &server](HttpRequest& req, HttpResponse& res) {
    Route(server, req, res);
  };
  callbacks.defer = [this](DeferredWork deferred, std::shared_ptr<HttpResponse> res,
                           std::function<void()> done) {
    RunDeferred(std::move(deferred), std::move(res), std::move(done));
  };
  callbacks.error = [this](int status, const std::string& message, const std::string& kind) {
    if (!kind.empty()) metrics.CountError(kind);
    HttpResponse res;
    AllowOrigin(res);
    SetError(res, {status, message, kind});
    return res;
  };
  callbacks.log = [this](const HttpRequest& req, const HttpResponse& res, double seconds) {
    Log(req, res, seconds);
  };
  return callbacks;
}

// Every answer, errors too: a browser hides an answer without it from the page.
void Server::Impl::AllowOrigin(HttpResponse& res) const {
  if (!options.allow_origin.empty())
    res.SetHeader("Access-Control-Allow-Origin", options.allow_origin);
}

std::optional<HttpResponse> Server::Impl::Screen(const HttpRequest& req) {
  HttpResponse res;
  AllowOrigin(res);
  if (!options.allow_origin.empty()) {
    if (req.method == "OPTIONS") {
      res.SetHeader("Access-Control-Allow-Methods", "GET, POST, DELETE, OPTIONS");
      res.SetHeader("Access-Control-Allow-Headers", "Authorization, Content-Type");
      res.SetHeader("Access-Control-Max-Age", "600");
      res.status = 204;
      return res;
    }
  }
  // The viewer's files hold no map data; the page asks for the token itself.
  const bool static_file =
      req.method == "GET" && (req.path == "/" || req.path.rfind("/viewer/", 0) == 0);
  if (!options.token.empty() && !static_file) {
    const std::string header = req.Header("authorization");
    const std::string prefix = "Bearer ";
    if (header.rfind(prefix, 0) != 0 ||
        !ConstantTimeEqual(header.substr(prefix.size()), options.token)) {
      metrics.CountError("unauthorized");
      SetError(res, {401, "this server needs 'Authorization: Bearer TOKEN'", "unauthorized"});
      res.SetHeader("WWW-Authenticate", "Bearer");
      return res;
    }
  }
  // A query that would find the queue full is turned away before its body is read: under
  // overload, reading and parsing the bodies of requests that get 503 anyway took the cores
  // the queries needed (half the throughput at twice the sustainable rate, measured).
  if (req.method == "POST" && (req.path == "/v1/localize" || req.path == "/v1/geopose" ||
                               (req.path.rfind("/v1/sessions/", 0) == 0))) {
    if (work.queued() >= work.capacity()) {
      metrics.CountError("overloaded");
      SetError(res, {503, BusyMessage(work.capacity()), "overloaded"});
      return res;
    }
  }
  return std::nullopt;
}

void Server::Impl::Log(const HttpRequest& req, const HttpResponse& res, double seconds) {
  metrics.CountRequest(EndpointOf(req.path), res.status, seconds);
  if (!options.quiet) {
    std::fprintf(stderr, "cwloc-serve: %s %s %d %.1f ms\n", req.method.c_str(), req.path.c_str(),
                 res.status, seconds * 1e3);
  }
}

void Server::Impl::MetricsPage(HttpResponse& res) {
  const std::vector<Metrics::Gauge> gauges = {
      {"cwloc_queue_depth", "Queries waiting for a worker.", static_cast<double>(work.queued())},
      {"cwloc_queue_capacity", "Queries that may wait (--queue).",
       static_cast<double>(work.capacity())},
      {"cwloc_workers_busy", "Workers running a query.", static_cast<double>(work.busy())},
      {"cwloc_workers", "Query workers (--threads).", static_cast<double>(work.threads())},
      {"cwloc_connections", "Connections open (--max-connections).",
       static_cast<double>(http->connections())},
      {"cwloc_sessions", "Open sessions.", static_cast<double>(sessions.size())},
      {"cwloc_index_generation", "Reloads of the index files so far.",
       static_cast<double>(registry.generation())}};
  res.SetContent(metrics.Text(gauges), "text/plain; version=0.0.4");
}

void Server::Impl::ViewerFile(const ViewerAsset& asset, HttpResponse& res) {
  // From --viewer-dir at every request, so that an edited viewer shows on reload; the built-in
  // copy of a file the folder lacks (three.js).
  std::ifstream in;
  if (!options.viewer_dir.empty())
    in.open(std::filesystem::path(options.viewer_dir) / asset.file, std::ios::binary);
  if (in.is_open()) {
    res.SetContent(std::string(std::istreambuf_iterator<char>(in), {}), asset.content_type);
  } else {
    res.SetContent(std::string(asset.bytes.begin(), asset.bytes.end()), asset.content_type);
  }
}

void Server::Impl::AdminReload(Server& server, HttpResponse& res) {
  if (options.token.empty()) {
    throw HttpError{403, "reloading over HTTP needs --token-file (SIGHUP reloads too)",
                    "forbidden"};
  }
  if (!server.Reload()) {
    throw HttpError{500, "reload failed; the old indexes stay (the reason is on stderr)",
                    "reload_failed"};
  }
  res.SetContent(nlohmann::json{{"generation", registry.generation()}}.dump(), "application/json");
}

namespace {

// A session's id in /v1/sessions/ID[/frames]: hex digits, '.' and base64url (sessions.h);
// empty when the path is no such.
std::string SessionId(const std::string& path, bool frames) {
  const std::string prefix = "/v1/sessions/", suffix = frames ? "/frames" : "";
  if (path.rfind(prefix, 0) != 0 || path.size() <= prefix.size() + suffix.size() ||
      path.compare(path.size() - suffix.size(), suffix.size(), suffix) != 0)
    return "";
  const std::string id = path.substr(prefix.size(), path.size() - prefix.size() - suffix.size());
  constexpr const char* kIdCharacters =
      "0123456789abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ._-";
  return id.find_first_not_of(kIdCharacters) == std::string::npos ? id : "";
}

}  // namespace

void Server::Impl::Route(Server& server, HttpRequest& req, HttpResponse& res) {
  using Handler = void (Impl::*)(const HttpRequest&, HttpResponse&);
  static const std::map<std::pair<std::string, std::string>, Handler> kRoutes = {
      {{"POST", "/v1/localize"}, &Impl::Localize},
      {{"POST", "/v1/geopose"}, &Impl::GeoPose},
      {{"POST", "/v1/sessions"}, &Impl::StartSession},
      {{"GET", "/v1/coverage"}, &Impl::Coverage},
      {{"GET", "/v1/info"}, &Impl::Info},
      {{"GET", "/v1/map"}, &Impl::Map}};
  AllowOrigin(res);
  try {
    if (const auto found = kRoutes.find({req.method, req.path}); found != kRoutes.end())
      return (this->*found->second)(req, res);
    if (req.method == "POST" && !SessionId(req.path, true).empty()) {
      req.matches = {req.path, SessionId(req.path, true)};
      return SessionFrame(req, res);
    }
    if (req.method == "DELETE" && !SessionId(req.path, false).empty()) {
      req.matches = {req.path, SessionId(req.path, false)};
      return EndSession(req, res);
    }
    if (req.method == "POST" && req.path == "/v1/admin/reload") return AdminReload(server, res);
    if (req.method == "GET" && req.path == "/healthz") return res.SetContent("ok\n", "text/plain");
    if (req.method == "GET" && req.path == "/metrics") return MetricsPage(res);
    for (const ViewerAsset& asset : ViewerAssets())
      if (req.method == "GET" && req.path == asset.path) return ViewerFile(asset, res);
    throw HttpError{404, "no such endpoint: " + req.method + " " + req.path, "not_found"};
  } catch (const HttpError& e) {
    if (!e.kind.empty()) metrics.CountError(e.kind);
    SetError(res, e);
  } catch (const InputError& e) {
    metrics.CountError("bad_request");
    SetError(res, {400, e.what(), "bad_request"});
  } catch (const std::bad_alloc&) {
    metrics.CountError("out_of_memory");
    SetError(res, {503, "out of memory", "out_of_memory"});
  }
}

Server::~Server() = default;

int Server::Bind() {
  Impl& s = *impl_;
  if (s.options.port < 0 || s.options.port > 65535)
    throw InputError("--listen: port " + std::to_string(s.options.port) + " is not in 0..65535");
  const std::optional<int> port = s.http->Bind(s.options.host, s.options.port);
  if (!port) {
    throw InputError("--listen " + s.options.host + ":" + std::to_string(s.options.port) +
                     ": cannot bind (in use, or not an address of this machine)");
  }
  return *port;
}

void Server::Serve() { impl_->http->Serve(); }

void Server::Stop() { impl_->http->Stop(); }

bool Server::Reload() {
  try {
    impl_->registry.Reload();
    std::fprintf(stderr, "cwloc-serve: reloaded the index files (generation %llu)\n",
                 static_cast<unsigned long long>(impl_->registry.generation()));
    return true;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cwloc-serve: reload failed, the old indexes stay: %s\n", e.what());
    return false;
  }
}

std::string ReadTokenFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot read the token file");
  std::string line;
  std::getline(in, line);
  const size_t begin = line.find_first_not_of(" \t\r");
  const size_t end = line.find_last_not_of(" \t\r");
  if (begin == std::string::npos) throw InputError(path + ": the token file's first line is empty");
  return line.substr(begin, end - begin + 1);
}

}  // namespace cwloc
