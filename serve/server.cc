#include "serve/server.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <new>
#include <nlohmann/json.hpp>
#include <thread>

#include "base/error.h"
#include "serve/server_impl.h"
#include "serve/viewer_assets.h"

namespace cwloc {
namespace {

using Clock = WorkQueue::Clock;

// When this thread's request began, for its latency (httplib calls the pre-routing handler,
// the handler and the logger on one thread).
thread_local Clock::time_point request_start;

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

std::string StatusWord(int status) {
  switch (status) {
    case 400:
      return "a malformed request";
    case 404:
      return "no such endpoint";
    case 405:
      return "method not allowed";
    case 408:
      return "the request was not read in time";
    case 413:
      return "the body is too large";
    case 414:
      return "the URI is too long";
    case 416:
      return "range not satisfiable";
    default:
      return "HTTP error";
  }
}

}  // namespace

std::string BusyMessage(size_t capacity) {
  return "busy: " + std::to_string(capacity) + " queries wait already (--queue); retry later";
}

void SetError(httplib::Response& res, const HttpError& error) {
  res.status = error.status;
  nlohmann::ordered_json body;
  body["error"] = error.message;
  body["status"] = error.status;
  res.set_content(body.dump(), "application/json");
  if (error.status == 503) res.set_header("Retry-After", "1");
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
  if (options.queue == 0) options.queue = 4 * static_cast<size_t>(options.threads);
  if (options.max_connections < 1 || options.max_connections > 10000)
    throw InputError("--max-connections must be between 1 and 10000");
  if (!(options.read_timeout_s > 0) || !(options.write_timeout_s > 0))
    throw InputError("--read-timeout and --write-timeout must be more than 0 seconds");
  if (!(options.session_ttl_s > 0)) throw InputError("--session-ttl must be more than 0 seconds");
  // One query per worker: a photo's SIFT runs on the worker's thread alone.
  options.defaults.photo.sift.num_threads = 1;
  return options;
}

}  // namespace

Server::Server(ServeOptions options) {
  impl_ = std::make_unique<Impl>(Checked(std::move(options)));
  impl_->ConfigureHttp();
  impl_->SetHooks();
  impl_->SetRoutes(*this);
}

void Server::Impl::ConfigureHttp() {
  const size_t connections = options.max_connections;
  http.new_task_queue = [connections] { return new httplib::ThreadPool(connections); };
  http.set_payload_max_length(options.max_body_bytes);
  const auto micros = [](double seconds) {
    return std::chrono::microseconds(static_cast<int64_t>(seconds * 1e6));
  };
  http.set_read_timeout(micros(options.read_timeout_s));
  http.set_write_timeout(micros(options.write_timeout_s));
  http.set_tcp_nodelay(true);  // else Nagle holds a response's body back ~40 ms (measured)
  http.set_keep_alive_timeout(5);
  http.set_keep_alive_max_count(1000);
}

httplib::Server::HandlerResponse Server::Impl::PreRoute(const httplib::Request& req,
                                                        httplib::Response& res) {
  request_start = Clock::now();
  // curl --data-binary sends any body as a form unless told otherwise, and httplib caps forms
  // at 8 KB: our API takes no forms, so such a body is read as the bytes it is. (The request
  // is httplib's own, not const; its body is read after this handler.)
  if (req.get_header_value("Content-Type") == "application/x-www-form-urlencoded") {
    auto& headers = const_cast<httplib::Request&>(req).headers;
    headers.erase("Content-Type");
    headers.emplace("Content-Type", "application/octet-stream");
  }
  // No compression: Debian's cpp-httplib compresses with Brotli at its highest quality, 1.6 s
  // of a connection thread for three.js's 850 KB (measured), outside --threads. A proxy in
  // front compresses if the network needs it (docs/serve.md).
  const_cast<httplib::Request&>(req).headers.erase("Accept-Encoding");
  if (!options.allow_origin.empty()) {
    res.set_header("Access-Control-Allow-Origin", options.allow_origin);
    if (req.method == "OPTIONS") {
      res.set_header("Access-Control-Allow-Methods", "GET, POST, DELETE, OPTIONS");
      res.set_header("Access-Control-Allow-Headers", "Authorization, Content-Type");
      res.set_header("Access-Control-Max-Age", "600");
      res.status = 204;
      return httplib::Server::HandlerResponse::Handled;
    }
  }
  // The viewer's files hold no map data; the page asks for the token itself.
  const bool static_file =
      req.method == "GET" && (req.path == "/" || req.path.rfind("/viewer/", 0) == 0);
  if (!options.token.empty() && !static_file) {
    const std::string header = req.get_header_value("Authorization");
    const std::string prefix = "Bearer ";
    if (header.rfind(prefix, 0) != 0 ||
        !ConstantTimeEqual(header.substr(prefix.size()), options.token)) {
      metrics.CountError("unauthorized");
      SetError(res, {401, "this server needs 'Authorization: Bearer TOKEN'", "unauthorized"});
      res.set_header("WWW-Authenticate", "Bearer");
      return httplib::Server::HandlerResponse::Handled;
    }
  }
  // A query that would find the queue full is turned away before its body is read: under
  // overload, reading and parsing the bodies of requests that get 503 anyway took the cores
  // the queries needed (half the throughput at twice the sustainable rate, measured). The
  // unread body ends the connection.
  if (req.method == "POST" && (req.path == "/v1/localize" || req.path == "/v1/geopose" ||
                               (req.path.rfind("/v1/sessions/", 0) == 0))) {
    if (work.queued() >= work.capacity()) {
      metrics.CountError("overloaded");
      SetError(res, {503, BusyMessage(work.capacity()), "overloaded"});
      res.set_header("Connection", "close");
      return httplib::Server::HandlerResponse::Handled;
    }
  }
  return httplib::Server::HandlerResponse::Unhandled;
}

void Server::Impl::SetHooks() {
  http.set_pre_routing_handler(
      [this](const httplib::Request& req, httplib::Response& res) { return PreRoute(req, res); });
  // httplib's own refusals (404, 413, 400, ...) get a JSON body too.
  http.set_error_handler(httplib::Server::HandlerWithResponse(
      [this](const httplib::Request& req, httplib::Response& res) {
        if (!res.body.empty()) return httplib::Server::HandlerResponse::Unhandled;
        std::string message = StatusWord(res.status);
        if (res.status == 404) message += ": " + req.method + " " + req.path;
        if (res.status == 413)
          message += ": over --max-body-mb (" + std::to_string(options.max_body_bytes) + " bytes)";
        metrics.CountError(res.status == 404   ? "not_found"
                           : res.status == 413 ? "too_large"
                                               : "bad_request");
        SetError(res, {res.status, message, ""});
        return httplib::Server::HandlerResponse::Handled;
      }));
  http.set_exception_handler(
      [this](const httplib::Request&, httplib::Response& res, std::exception_ptr error) {
        std::string what = "unknown exception";
        try {
          std::rethrow_exception(error);
        } catch (const std::exception& e) {
          what = e.what();
        } catch (...) {
        }
        metrics.CountError("internal");
        SetError(res, {500, "internal error: " + what, "internal"});
      });
  http.set_logger([this](const httplib::Request& req, const httplib::Response& res) {
    const double seconds = std::chrono::duration<double>(Clock::now() - request_start).count();
    metrics.CountRequest(EndpointOf(req.path), res.status, seconds);
    if (!options.quiet) {
      std::fprintf(stderr, "cwloc-serve: %s %s %d %.1f ms\n", req.method.c_str(), req.path.c_str(),
                   res.status, seconds * 1e3);
    }
  });
}

void Server::Impl::SetRoutes(Server& server) {
  // Each handler's refusals become their status and a JSON error.
  const auto handled = [this](void (Impl::*handler)(const httplib::Request&, httplib::Response&)) {
    return [this, handler](const httplib::Request& req, httplib::Response& res) {
      try {
        (this->*handler)(req, res);
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
    };
  };
  http.Post("/v1/localize", handled(&Impl::Localize));
  http.Post("/v1/geopose", handled(&Impl::GeoPose));
  http.Post("/v1/sessions", handled(&Impl::StartSession));
  http.Post(R"(/v1/sessions/([0-9a-f]+)/frames)", handled(&Impl::SessionFrame));
  http.Delete(R"(/v1/sessions/([0-9a-f]+))", handled(&Impl::EndSession));
  http.Get("/v1/coverage", handled(&Impl::Coverage));
  http.Get("/v1/info", handled(&Impl::Info));
  http.Get("/v1/map", handled(&Impl::Map));
  http.Post("/v1/admin/reload", [this, &server](const httplib::Request&, httplib::Response& res) {
    if (options.token.empty()) {
      SetError(res,
               {403, "reloading over HTTP needs --token-file (SIGHUP reloads too)", "forbidden"});
      return;
    }
    if (!server.Reload()) {
      SetError(res, {500, "reload failed; the old indexes stay (the reason is on stderr)",
                     "reload_failed"});
      return;
    }
    res.set_content(nlohmann::json{{"generation", registry.generation()}}.dump(),
                    "application/json");
  });
  http.Get("/healthz", [](const httplib::Request&, httplib::Response& res) {
    res.set_content("ok\n", "text/plain");
  });
  http.Get("/metrics", [this](const httplib::Request&, httplib::Response& res) {
    const std::vector<Metrics::Gauge> gauges = {
        {"cwloc_queue_depth", "Queries waiting for a worker.", static_cast<double>(work.queued())},
        {"cwloc_queue_capacity", "Queries that may wait (--queue).",
         static_cast<double>(work.capacity())},
        {"cwloc_workers_busy", "Workers running a query.", static_cast<double>(work.busy())},
        {"cwloc_workers", "Query workers (--threads).", static_cast<double>(work.threads())},
        {"cwloc_sessions", "Open sessions.", static_cast<double>(sessions.size())},
        {"cwloc_index_generation", "Reloads of the index files so far.",
         static_cast<double>(registry.generation())}};
    res.set_content(metrics.Text(gauges), "text/plain; version=0.0.4");
  });
  for (const ViewerAsset& asset : ViewerAssets()) {
    http.Get(asset.path, [&asset, this](const httplib::Request&, httplib::Response& res) {
      // From --viewer-dir at every request, so that an edited viewer shows on reload; the
      // built-in copy of a file the folder lacks (three.js).
      std::ifstream in;
      if (!options.viewer_dir.empty())
        in.open(std::filesystem::path(options.viewer_dir) / asset.file, std::ios::binary);
      if (in.is_open()) {
        res.set_content(std::string(std::istreambuf_iterator<char>(in), {}), asset.content_type);
      } else {
        res.set_content(asset.bytes.data(), asset.bytes.size(), asset.content_type);
      }
    });
  }
}

Server::~Server() = default;

int Server::Bind() {
  Impl& s = *impl_;
  if (s.options.port < 0 || s.options.port > 65535)
    throw InputError("--listen: port " + std::to_string(s.options.port) + " is not in 0..65535");
  int port = s.options.port;
  if (port == 0) {
    port = s.http.bind_to_any_port(s.options.host);
  } else if (!s.http.bind_to_port(s.options.host, port)) {
    port = -1;
  }
  if (port < 0) {
    throw InputError("--listen " + s.options.host + ":" + std::to_string(s.options.port) +
                     ": cannot bind (in use, or not an address of this machine)");
  }
  return port;
}

void Server::Serve() { impl_->http.listen_after_bind(); }

void Server::Stop() { impl_->http.stop(); }

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
