#pragma once

// cwloc-serve's HTTP/1.1 on an open port (Boost.Beast over Asio; docs/serve.md, "Limits"): one
// thread reads and writes every connection, so a slow client holds a socket, never a thread;
// the handlers' queries run on the query workers (work_queue.h) while the connection waits.
// Each request has a deadline for its headers and, by its size and a minimum rate, its body;
// a body over the limit is refused on its Content-Length before it is read, a connection
// beyond the limit is answered 503 at once, and a refused request's unread body is drained for
// a moment (lingering close) so that the client reads the answer before the socket closes.

#include <cstddef>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "serve/http_message.h"

namespace cwloc {

struct HttpLimits {
  // A connection costs a socket and a few KiB (no thread): room for many slow clients.
  size_t max_connections = 1000;       // served at once; one more is answered 503 and closed
  size_t max_body_bytes = 32 << 20;    // larger: 413 (on Content-Length, or as chunks arrive)
  size_t max_header_bytes = 16 << 10;  // request line and headers: 431 beyond
  // A request's headers arrive within this of its connection's last answer (or of its
  // opening); its body within this plus its size over min_body_rate. Else 408 and the
  // connection ends.
  double request_timeout_s = 10;
  double min_body_rate = 64 << 10;  // bytes per second
  double write_timeout_s = 10;      // an answer is sent within this
};

// What the server does with requests; called on its I/O thread, so each must be quick.
struct HttpCallbacks {
  // A request whose headers are read (its body not yet): a response refuses it before the body
  // is read (a token missing, a full queue); nullopt reads the body.
  std::function<std::optional<HttpResponse>(const HttpRequest& head)> screen;
  // The whole request: fills the response, or its `deferred` work to run on a worker.
  std::function<void(HttpRequest& request, HttpResponse& response)> handle;
  // Runs deferred work on a worker and calls `done` there when the response is filled (an
  // error response when the work did not run).
  std::function<void(DeferredWork work, std::shared_ptr<HttpResponse> response,
                     std::function<void()> done)>
      defer;
  // The server's own refusals (status, message, the kind /metrics counts them under), as the
  // handlers' errors are made.
  std::function<HttpResponse(int status, const std::string& message, const std::string& kind)>
      error;
  // Every answered request and its time from its first byte read to its answer written.
  std::function<void(const HttpRequest& request, const HttpResponse& response, double seconds)> log;
};

// Reads one whole request from its bytes as a connection does (the header and body limits, the
// query string, a multipart body), at once rather than from a socket: the fuzzer's entry.
// Throws InputError naming what a connection would refuse; nullopt when the bytes end early.
std::optional<HttpRequest> ParseRequestBytes(std::string_view bytes, const HttpLimits& limits);

struct HttpServerState;

class HttpServer {
 public:
  HttpServer(HttpLimits limits, HttpCallbacks callbacks);
  ~HttpServer();
  HttpServer(const HttpServer&) = delete;
  HttpServer& operator=(const HttpServer&) = delete;

  // Binds host:port (0: any free port) and returns the port; nullopt when it cannot.
  std::optional<int> Bind(const std::string& host, int port);
  // Serves until Stop(), then lets the requests in flight finish.
  void Serve();
  // Stops accepting and ends idle connections; safe from any thread, a signal handler's too.
  void Stop();
  size_t connections() const;  // open, served or lingering

 private:
  std::shared_ptr<HttpServerState> impl_;
};

}  // namespace cwloc
