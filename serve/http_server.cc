#include "serve/http_server.h"

#include <algorithm>
#include <atomic>
#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <cctype>
#include <chrono>
#include <limits>
#include <mutex>
#include <set>

#include "base/error.h"

namespace cwloc {

namespace net = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
using tcp = net::ip::tcp;
using Clock = std::chrono::steady_clock;

namespace {

// How long, and how much, a refused request's unread body is drained before its socket closes:
// long enough for the client to read the answer, too little for a client to hold on.
constexpr std::chrono::milliseconds kLingerTime{1000};
constexpr size_t kLingerBytes = 4 << 20;
// Connections answered 503 (beyond max_connections) that may linger at once; more are closed.
constexpr size_t kMaxRefusedPerServed = 4;

std::chrono::steady_clock::duration Seconds(double seconds) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
}

std::string_view Std(beast::string_view text) { return {text.data(), text.size()}; }

std::string Lower(std::string_view text) {
  std::string out(text);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

// The request line and headers as the handlers see them; false for a malformed query string.
bool ReadHead(const http::request<http::string_body>& message, HttpRequest* request) {
  request->method = std::string(Std(message.method_string()));
  const std::string_view target = Std(message.target());
  const size_t question = target.find('?');
  const std::optional<std::string> path = DecodeUrlComponent(target.substr(0, question));
  if (!path) return false;
  request->path = *path;
  std::string_view query = question == std::string_view::npos ? "" : target.substr(question + 1);
  while (!query.empty()) {
    const size_t amp = query.find('&');
    const std::string_view pair = query.substr(0, amp);
    query.remove_prefix(amp == std::string_view::npos ? query.size() : amp + 1);
    const size_t equals = pair.find('=');
    const auto name = DecodeUrlComponent(pair.substr(0, equals));
    const auto value =
        DecodeUrlComponent(equals == std::string_view::npos ? "" : pair.substr(equals + 1));
    if (!name || !value) return false;
    request->params.emplace(*name, *value);
  }
  for (const auto& field : message)
    request->headers.emplace_back(Lower(Std(field.name_string())), std::string(Std(field.value())));
  return true;
}

http::response<http::string_body> ToMessage(const HttpResponse& response, unsigned version,
                                            bool keep_alive) {
  http::response<http::string_body> message{static_cast<http::status>(response.status), version};
  message.set(http::field::content_type, response.content_type);
  for (const auto& [name, value] : response.headers) message.set(name, value);
  message.body() = response.body;
  message.keep_alive(keep_alive);
  message.prepare_payload();
  return message;
}

}  // namespace

struct HttpServerState : std::enable_shared_from_this<HttpServerState> {
  HttpServerState(HttpLimits limits_in, HttpCallbacks callbacks_in)
      : acceptor(io), limits(limits_in), callbacks(std::move(callbacks_in)) {}

  void Accept();
  void OnAccept(tcp::socket socket);

  net::io_context io{1};
  tcp::acceptor acceptor;
  const HttpLimits limits;
  const HttpCallbacks callbacks;
  std::atomic<size_t> served{0};   // connections read and answered
  std::atomic<size_t> refused{0};  // connections answered 503 and lingering
  std::atomic<bool> stopping{false};
  // Connections waiting for a request, which Stop ends (on the I/O thread only).
  std::set<std::shared_ptr<class Connection>> idle;
};

// One client's connection: its requests one after the other, each read whole (headers, then
// body) under its deadline, handled, answered; then the next, or a close.
class Connection : public std::enable_shared_from_this<Connection> {
 public:
  Connection(std::shared_ptr<HttpServerState> server, tcp::socket socket)
      : server_(std::move(server)), socket_(std::move(socket)), timer_(socket_.get_executor()) {}
  ~Connection() { --server_->served; }

  void ReadHeader();
  // Ends a connection waiting for its next request (the server stops).
  void EndIfIdle() { Close(); }

 private:
  // The socket's operations after `time` are cancelled and timed_out_ says so (a
  // beast::tcp_stream would close the socket, and the 408 could not be sent).
  void ExpireAfter(Clock::duration time);
  void OnHeader(beast::error_code error);
  void ReadBody();
  void OnBody(beast::error_code error);
  void Handle();
  void Refuse(int status, const std::string& message, const std::string& kind);
  void Write();
  void OnWrite(beast::error_code error);
  void Linger();
  void Close();
  // Whether the request's body is read (or it has none): only then may the connection go on.
  bool FullyRead() const { return body_read_ || parser_->is_done(); }

  std::shared_ptr<HttpServerState> server_;
  tcp::socket socket_;
  net::steady_timer timer_;
  bool timed_out_ = false;
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::string_body>> parser_;
  HttpRequest request_;
  std::shared_ptr<HttpResponse> response_;
  Clock::time_point start_;
  bool body_read_ = false;
  std::array<char, 16 << 10> discard_;  // a lingering connection's drained bytes
  size_t drained_ = 0;
};

void Connection::ReadHeader() {
  if (server_->stopping) return Close();
  parser_.emplace();
  parser_->header_limit(static_cast<uint32_t>(server_->limits.max_header_bytes));
  // No limit while the headers are read (Beast would end the read on a too-large
  // Content-Length without a word); OnHeader answers 413, ReadBody sets the limit. Not
  // boost::none: Boost 1.74 compares a length against it as if it were less than any.
  parser_->body_limit(std::numeric_limits<std::uint64_t>::max());
  request_ = HttpRequest();
  response_.reset();
  body_read_ = false;
  ExpireAfter(Seconds(server_->limits.request_timeout_s));
  server_->idle.insert(shared_from_this());
  http::async_read_header(socket_, buffer_, *parser_,
                          [self = shared_from_this()](beast::error_code error, size_t) {
                            self->server_->idle.erase(self);
                            self->OnHeader(error);
                          });
}

void Connection::OnHeader(beast::error_code error) {
  start_ = Clock::now();
  if (error == http::error::header_limit) {
    return Refuse(431,
                  "the request line and headers are over " +
                      std::to_string(server_->limits.max_header_bytes) + " bytes",
                  "bad_request");
  }
  if (timed_out_ && buffer_.size() > 0)
    return Refuse(408, "the request's headers were not read in time", "timeout");
  if (error) return Close();  // the client left, or sent nothing in time
  if (!ReadHead(parser_->get(), &request_))
    return Refuse(400, "a malformed URL escape in the request's target", "bad_request");
  const auto length = parser_->content_length();
  if (length && *length > server_->limits.max_body_bytes) {
    return Refuse(413,
                  "the body is too large: " + std::to_string(*length) +
                      " bytes, over --max-body-mb (" +
                      std::to_string(server_->limits.max_body_bytes) + " bytes)",
                  "too_large");
  }
  if (std::optional<HttpResponse> refusal = server_->callbacks.screen(request_)) {
    response_ = std::make_shared<HttpResponse>(std::move(*refusal));
    return Write();
  }
  ReadBody();
}

void Connection::ReadBody() {
  if (parser_->is_done()) return OnBody({});  // no body
  parser_->body_limit(server_->limits.max_body_bytes);
  const auto length = parser_->content_length();
  const double bytes = static_cast<double>(
      length ? *length : (parser_->chunked() ? server_->limits.max_body_bytes : 0));
  ExpireAfter(Seconds(server_->limits.request_timeout_s + bytes / server_->limits.min_body_rate));
  // Beast reads as much as the buffer has room for, at least 512 bytes: without room a 1.5 MB
  // body took ~3,000 reads, a third of a core at 100 requests a second. Up to 64 KiB a read.
  const size_t room = static_cast<size_t>(std::min(bytes, 65536.0));
  if (buffer_.capacity() < room) buffer_.reserve(room);
  const auto read = [self = shared_from_this()] {
    http::async_read(self->socket_, self->buffer_, *self->parser_,
                     [self](beast::error_code error, size_t) { self->OnBody(error); });
  };
  if (Lower(Std(parser_->get()[http::field::expect])) != "100-continue" || parser_->is_done())
    return read();
  // The client waits for this before it sends the body (curl does for more than 1 KB).
  auto go_on = std::make_shared<http::response<http::empty_body>>(http::status::continue_,
                                                                  parser_->get().version());
  http::async_write(socket_, *go_on,
                    [self = shared_from_this(), go_on, read](beast::error_code error, size_t) {
                      if (error) return self->Close();
                      read();
                    });
}

void Connection::OnBody(beast::error_code error) {
  if (error == http::error::body_limit) {
    return Refuse(413,
                  "the body is too large: over --max-body-mb (" +
                      std::to_string(server_->limits.max_body_bytes) + " bytes)",
                  "too_large");
  }
  if (timed_out_)
    return Refuse(408,
                  "the request's body was not read in time (--request-timeout, "
                  "--min-body-rate)",
                  "timeout");
  if (error) return Close();
  body_read_ = true;
  request_.body = std::move(parser_->get().body());
  Handle();
}

void Connection::Handle() {
  response_ = std::make_shared<HttpResponse>();
  try {
    if (request_.IsMultipart())
      request_.parts = ParseMultipart(request_.Header("content-type"), request_.body);
    server_->callbacks.handle(request_, *response_);
  } catch (const InputError& e) {
    return Refuse(400, e.what(), "bad_request");
  } catch (const std::exception& e) {
    return Refuse(500, std::string("internal error: ") + e.what(), "internal");
  }
  if (!response_->deferred) return Write();
  DeferredWork work = std::move(*response_->deferred);
  response_->deferred.reset();
  // The worker fills the response; the answer is written back here, on the I/O thread.
  // The guard keeps the I/O thread running while no socket operation is pending.
  auto guard = std::make_shared<net::executor_work_guard<net::io_context::executor_type>>(
      server_->io.get_executor());
  server_->callbacks.defer(std::move(work), response_, [self = shared_from_this(), guard] {
    net::post(self->server_->io, [self, guard] { self->Write(); });
  });
}

void Connection::Refuse(int status, const std::string& message, const std::string& kind) {
  response_ = std::make_shared<HttpResponse>(server_->callbacks.error(status, message, kind));
  response_->close = true;
  Write();
}

void Connection::Write() {
  const http::request<http::string_body>& message = parser_->get();
  // An unread body ends the connection: what follows on the socket is no request.
  const bool keep_alive =
      message.keep_alive() && !response_->close && FullyRead() && !server_->stopping;
  auto reply = std::make_shared<http::response<http::string_body>>(
      ToMessage(*response_, message.version() ? message.version() : 11, keep_alive));
  ExpireAfter(Seconds(server_->limits.write_timeout_s));
  http::async_write(socket_, *reply,
                    [self = shared_from_this(), reply](beast::error_code error, size_t) {
                      self->OnWrite(error);
                    });
}

void Connection::OnWrite(beast::error_code error) {
  const double seconds = std::chrono::duration<double>(Clock::now() - start_).count();
  if (!request_.method.empty()) server_->callbacks.log(request_, *response_, seconds);
  if (error) return Close();
  const bool keep_alive =
      parser_->get().keep_alive() && !response_->close && FullyRead() && !server_->stopping;
  if (keep_alive) return ReadHeader();
  if (!FullyRead()) return Linger();
  Close();
}

// The answer is out; the client may still be sending the body: stop sending, drain what comes
// for a moment, then close (closing with unread bytes would reset the connection, and the
// client might lose the answer).
void Connection::Linger() {
  beast::error_code ignored;
  socket_.shutdown(tcp::socket::shutdown_send, ignored);
  ExpireAfter(kLingerTime);
  socket_.async_read_some(net::buffer(discard_),
                          [self = shared_from_this()](beast::error_code error, size_t bytes) {
                            self->drained_ += bytes;
                            if (error || self->drained_ > kLingerBytes) return self->Close();
                            self->Linger();
                          });
}

void Connection::Close() {
  beast::error_code ignored;
  timer_.cancel();
  socket_.shutdown(tcp::socket::shutdown_both, ignored);
  socket_.close(ignored);
}

void Connection::ExpireAfter(Clock::duration time) {
  timed_out_ = false;
  timer_.expires_after(time);
  timer_.async_wait([self = shared_from_this()](beast::error_code error) {
    // A wait re-armed after it fired but before this ran is no expiry.
    if (error || self->timer_.expiry() > Clock::now()) return;
    self->timed_out_ = true;
    beast::error_code ignored;
    self->socket_.cancel(ignored);
  });
}

// A connection beyond max_connections: the 503 at once, then a linger, then the close.
class Refusal : public std::enable_shared_from_this<Refusal> {
 public:
  Refusal(std::shared_ptr<HttpServerState> server, tcp::socket socket)
      : server_(std::move(server)), stream_(std::move(socket)) {}
  ~Refusal() { --server_->refused; }

  void Start() {
    const HttpResponse busy = server_->callbacks.error(
        503,
        "busy: " + std::to_string(server_->limits.max_connections) +
            " connections are served already (--max-connections); retry later",
        "connections_full");
    reply_ = ToMessage(busy, 11, false);
    stream_.expires_after(Seconds(server_->limits.write_timeout_s));
    http::async_write(stream_, reply_,
                      [self = shared_from_this()](beast::error_code error, size_t) {
                        if (error) return;
                        beast::error_code ignored;
                        self->stream_.socket().shutdown(tcp::socket::shutdown_send, ignored);
                        self->Drain();
                      });
  }

 private:
  void Drain() {
    stream_.expires_after(kLingerTime);
    stream_.async_read_some(net::buffer(discard_),
                            [self = shared_from_this()](beast::error_code error, size_t bytes) {
                              self->drained_ += bytes;
                              if (!error && self->drained_ <= kLingerBytes) self->Drain();
                            });
  }

  std::shared_ptr<HttpServerState> server_;
  beast::tcp_stream stream_;
  http::response<http::string_body> reply_;
  std::array<char, 4096> discard_;
  size_t drained_ = 0;
};

void HttpServerState::Accept() {
  acceptor.async_accept([self = shared_from_this()](beast::error_code error, tcp::socket socket) {
    if (error) {
      if (!self->acceptor.is_open()) return;  // stopped
    } else {
      self->OnAccept(std::move(socket));
    }
    self->Accept();
  });
}

void HttpServerState::OnAccept(tcp::socket socket) {
  beast::error_code ignored;
  socket.set_option(tcp::no_delay(true), ignored);  // else Nagle holds an answer's body ~40 ms
  if (served < limits.max_connections) {
    ++served;
    std::make_shared<Connection>(shared_from_this(), std::move(socket))->ReadHeader();
    return;
  }
  if (refused < kMaxRefusedPerServed * limits.max_connections) {
    ++refused;
    std::make_shared<Refusal>(shared_from_this(), std::move(socket))->Start();
  }  // else the socket closes here
}

std::optional<HttpRequest> ParseRequestBytes(std::string_view bytes, const HttpLimits& limits) {
  http::request_parser<http::string_body> parser;
  parser.header_limit(static_cast<uint32_t>(limits.max_header_bytes));
  parser.body_limit(limits.max_body_bytes);
  parser.eager(true);
  beast::error_code error;
  while (!bytes.empty() && !parser.is_done()) {
    const size_t used = parser.put(net::buffer(bytes.data(), bytes.size()), error);
    if (error == http::error::need_more) return std::nullopt;
    if (error) throw InputError("HTTP request: " + error.message());
    bytes.remove_prefix(used);
  }
  if (!parser.is_done()) return std::nullopt;
  HttpRequest request;
  if (!ReadHead(parser.get(), &request))
    throw InputError("HTTP request: a malformed URL escape in the request's target");
  request.body = std::move(parser.get().body());
  if (request.IsMultipart())
    request.parts = ParseMultipart(request.Header("content-type"), request.body);
  return request;
}

HttpServer::HttpServer(HttpLimits limits, HttpCallbacks callbacks)
    : impl_(std::make_shared<HttpServerState>(limits, std::move(callbacks))) {}

HttpServer::~HttpServer() = default;

std::optional<int> HttpServer::Bind(const std::string& host, int port) {
  beast::error_code error;
  const net::ip::address address = net::ip::make_address(host, error);
  if (error) return std::nullopt;
  const tcp::endpoint endpoint(address, static_cast<unsigned short>(port));
  tcp::acceptor& acceptor = impl_->acceptor;
  acceptor.open(endpoint.protocol(), error);
  if (!error) acceptor.set_option(net::socket_base::reuse_address(true), error);
  if (!error) acceptor.bind(endpoint, error);
  if (!error) acceptor.listen(net::socket_base::max_listen_connections, error);
  if (error) return std::nullopt;
  return acceptor.local_endpoint().port();
}

void HttpServer::Serve() {
  impl_->Accept();
  impl_->io.run();
}

void HttpServer::Stop() {
  net::post(impl_->io, [impl = impl_] {
    impl->stopping = true;
    beast::error_code ignored;
    impl->acceptor.close(ignored);
    for (const auto& connection : std::set(impl->idle)) connection->EndIfIdle();
  });
}

size_t HttpServer::connections() const { return impl_->served + impl_->refused; }

}  // namespace cwloc
