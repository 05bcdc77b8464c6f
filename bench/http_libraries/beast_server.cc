// Minimal Boost.Beast (async, Boost.Asio) server for bench/http_library_bench.sh.
// Usage: beast_server PORT
// One io_context run by 2 threads; each connection on its own strand.
#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <chrono>
#include <cstdlib>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace beast = boost::beast;
namespace http = beast::http;
namespace net = boost::asio;
using tcp = net::ip::tcp;

namespace {

constexpr std::uint64_t kMaxBody = 16 * 1024 * 1024;
constexpr std::uint32_t kMaxHeader = 16 * 1024;
constexpr std::chrono::seconds kTimeout{10};

void busy_work_1ms() {
  const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(1);
  volatile unsigned long sink = 0;
  while (std::chrono::steady_clock::now() < end) ++sink;
}

class Session : public std::enable_shared_from_this<Session> {
 public:
  explicit Session(tcp::socket&& socket) : stream_(std::move(socket)) {
    // Beast reads at most max(512, free capacity) bytes per recv; without this
    // a 200 KB upload takes ~400 recv calls (and ~20 ms here).
    buffer_.reserve(64 * 1024);
  }
  void start() {
    net::dispatch(stream_.get_executor(), [self = shared_from_this()] { self->read(); });
  }

 private:
  void read() {
    parser_.emplace();
    parser_->body_limit(kMaxBody);
    parser_->header_limit(kMaxHeader);
    stream_.expires_after(kTimeout);  // bounds slow / idle clients
    http::async_read(
        stream_, buffer_, *parser_,
        [self = shared_from_this()](beast::error_code ec, std::size_t) { self->on_read(ec); });
  }

  void on_read(beast::error_code ec) {
    if (ec == http::error::body_limit)
      return respond(http::status::payload_too_large, "too large", false);
    if (ec) return close();
    const auto& req = parser_->get();
    const auto target = req.target();
    if (req.method() == http::verb::get && target == "/healthz") {
      respond(http::status::ok, "ok", req.keep_alive());
    } else if (req.method() == http::verb::post &&
               (target == "/echo-size" || target == "/echo-size-work")) {
      if (target == "/echo-size-work") busy_work_1ms();
      respond(http::status::ok, std::to_string(req.body().size()), req.keep_alive());
    } else {
      respond(http::status::not_found, "not found", req.keep_alive());
    }
  }

  void respond(http::status status, std::string body, bool keep_alive) {
    res_ = {};
    res_.version(11);
    res_.result(status);
    res_.set(http::field::content_type, "text/plain");
    res_.keep_alive(keep_alive);
    res_.body() = std::move(body);
    res_.prepare_payload();
    http::async_write(stream_, res_,
                      [self = shared_from_this()](beast::error_code ec, std::size_t) {
                        if (ec || !self->res_.keep_alive()) return self->close();
                        self->read();
                      });
  }

  void close() {
    beast::error_code ec;
    stream_.socket().shutdown(tcp::socket::shutdown_send, ec);
  }

  beast::tcp_stream stream_;
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::string_body>> parser_;
  http::response<http::string_body> res_;
};

class Listener : public std::enable_shared_from_this<Listener> {
 public:
  Listener(net::io_context& ioc, tcp::endpoint ep) : ioc_(ioc), acceptor_(ioc, ep) {}
  void accept() {
    acceptor_.async_accept(net::make_strand(ioc_),
                           [self = shared_from_this()](beast::error_code ec, tcp::socket s) {
                             if (!ec) std::make_shared<Session>(std::move(s))->start();
                             self->accept();
                           });
  }

 private:
  net::io_context& ioc_;
  tcp::acceptor acceptor_;
};

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) return 2;
  const auto port = static_cast<unsigned short>(std::atoi(argv[1]));
  constexpr int kThreads = 2;
  net::io_context ioc(kThreads);
  std::make_shared<Listener>(ioc, tcp::endpoint(net::ip::make_address("127.0.0.1"), port))
      ->accept();
  net::signal_set signals(ioc, SIGINT, SIGTERM);
  signals.async_wait([&](beast::error_code, int) { ioc.stop(); });
  std::vector<std::thread> threads;
  for (int i = 1; i < kThreads; ++i) threads.emplace_back([&] { ioc.run(); });
  ioc.run();
  for (auto& t : threads) t.join();
  return 0;
}
