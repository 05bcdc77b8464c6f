// cwloc-load-bench: an open-loop HTTP load for cwloc-serve (bench/serve_benchmark.py). Request i
// is due at start + i / rate whatever the answers' latency (a closed loop would wait for slow
// answers and hide them), and its latency counts from that due time. Compiled so that the
// client's own pauses (a Python client's GIL, its 1.5 MB bodies) do not show as the server's.
// One line per answer on stdout: status (0: no answer), latency (s), 1 when "success":true,
// and when it came (s after the first due time).
//
//   cwloc-load-bench --port 8080 --rate 80 --seconds 20 --body q.body:application/json ...
#include <CLI/CLI.hpp>
#include <atomic>
#include <boost/asio/connect.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <string>
#include <thread>
#include <vector>

namespace cwloc {
namespace {

namespace beast = boost::beast;
namespace http = beast::http;
using tcp = boost::asio::ip::tcp;
using Clock = std::chrono::steady_clock;

struct Body {
  std::string content_type;
  std::string bytes;
};

struct Answer {
  int status = 0;
  double latency_s = 0.0;
  bool localized = false;
  double done_s = 0.0;
};

// "path:content/type" -> the file's bytes and its type.
Body ReadBody(const std::string& spec) {
  const size_t colon = spec.find(':');
  if (colon == std::string::npos) throw std::runtime_error(spec + ": expected FILE:CONTENT_TYPE");
  std::ifstream in(spec.substr(0, colon), std::ios::binary);
  if (!in) throw std::runtime_error(spec.substr(0, colon) + ": cannot read");
  return {spec.substr(colon + 1), std::string(std::istreambuf_iterator<char>(in), {})};
}

class Connection {
 public:
  explicit Connection(const tcp::resolver::results_type& endpoints) : endpoints_(endpoints) {}

  // Status and body of one POST; a keep-alive connection the server closed is opened again once.
  std::pair<int, std::string> Post(const std::string& target, const Body& body) {
    http::request<http::span_body<const char>> request{http::verb::post, target, 11};
    request.set(http::field::host, "cwloc-load-bench");
    request.set(http::field::content_type, body.content_type);
    request.body() = {body.bytes.data(), body.bytes.size()};
    request.prepare_payload();
    for (int attempt = 0; attempt < 2; ++attempt) {
      try {
        if (!open_) {
          stream_.connect(endpoints_);
          open_ = true;
        }
        http::write(stream_, request);
        http::response_parser<http::string_body> parser;
        parser.body_limit(64 << 20);
        http::read(stream_, buffer_, parser);
        if (!parser.get().keep_alive()) Close();
        return {parser.get().result_int(), std::move(parser.get().body())};
      } catch (const beast::system_error&) {
        Close();
      }
    }
    return {0, ""};
  }

 private:
  void Close() {
    beast::error_code ignored;
    stream_.socket().close(ignored);
    buffer_.clear();
    open_ = false;
  }

  boost::asio::io_context context_;
  beast::tcp_stream stream_{context_};
  beast::flat_buffer buffer_;
  tcp::resolver::results_type endpoints_;
  bool open_ = false;
};

int Run(const std::string& host, int port, const std::string& target, double rate, double seconds,
        int connections, const std::vector<std::string>& body_specs) {
  std::vector<Body> bodies;
  for (const std::string& spec : body_specs) bodies.push_back(ReadBody(spec));
  boost::asio::io_context context;
  const auto endpoints = tcp::resolver(context).resolve(host, std::to_string(port));
  const size_t total = static_cast<size_t>(rate * seconds);
  const Clock::time_point start = Clock::now() + std::chrono::milliseconds(200);
  std::atomic<size_t> next{0};
  std::vector<std::vector<Answer>> answers(connections);
  std::vector<std::thread> threads;
  for (int c = 0; c < connections; ++c) {
    threads.emplace_back([&, c] {
      Connection connection(endpoints);
      for (size_t i = next++; i < total; i = next++) {
        const Clock::time_point due = start + std::chrono::duration_cast<Clock::duration>(
                                                  std::chrono::duration<double>(i / rate));
        std::this_thread::sleep_until(due);
        const auto [status, text] = connection.Post(target, bodies[i % bodies.size()]);
        const Clock::time_point now = Clock::now();
        answers[c].push_back({status, std::chrono::duration<double>(now - due).count(),
                              status == 200 && text.find("\"success\":true") != std::string::npos,
                              std::chrono::duration<double>(now - start).count()});
      }
    });
  }
  for (std::thread& thread : threads) thread.join();
  for (const std::vector<Answer>& of_connection : answers)
    for (const Answer& a : of_connection)
      std::printf("%d %.6f %d %.6f\n", a.status, a.latency_s, a.localized ? 1 : 0, a.done_s);
  return 0;
}

}  // namespace
}  // namespace cwloc

int main(int argc, char** argv) {
  CLI::App app{"An open-loop HTTP load: requests at fixed times, latency from each one's due time"};
  std::string host = "127.0.0.1", target = "/v1/localize";
  int port = 0, connections = 64;
  double rate = 0.0, seconds = 0.0;
  std::vector<std::string> bodies;
  app.add_option("--host", host, "the server's address");
  app.add_option("--port", port, "the server's port")->required()->check(CLI::Range(1, 65535));
  app.add_option("--target", target, "the path posted to");
  app.add_option("--rate", rate, "requests per second")->required()->check(CLI::Range(0.01, 1e5));
  app.add_option("--seconds", seconds, "how long")->required()->check(CLI::Range(0.1, 86400.0));
  app.add_option("--connections", connections, "keep-alive connections, one thread each")
      ->check(CLI::Range(1, 1000));
  app.add_option("--body", bodies, "FILE:CONTENT_TYPE, sent in turn")->required();
  CLI11_PARSE(app, argc, argv);
  try {
    return cwloc::Run(host, port, target, rate, seconds, connections, bodies);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cwloc-load-bench: %s\n", e.what());
    return 2;
  }
}
