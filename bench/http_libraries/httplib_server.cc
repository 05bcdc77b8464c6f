// Minimal cpp-httplib server for bench/http_library_bench.sh.
// Usage: httplib_server PORT
#include <httplib.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>

static void busy_work_1ms() {
  const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(1);
  volatile unsigned long sink = 0;
  while (std::chrono::steady_clock::now() < end) ++sink;
}

int main(int argc, char** argv) {
  if (argc != 2) return 2;
  const int port = std::atoi(argv[1]);
  httplib::Server svr;
  // 2 workers. Each worker serves one connection for its whole keep-alive
  // life, so the pool bounds the connections served at once; the default
  // keep-alive limits (5 requests, 5 s idle) are kept so that connections
  // rotate between workers. A much larger max count starves other clients.
  svr.new_task_queue = [] { return new httplib::ThreadPool(2); };
  svr.set_keep_alive_max_count(5);
  svr.set_keep_alive_timeout(5);
  // Default is off: headers and body go out in two send()s and Nagle +
  // delayed ACK then cost ~40 ms per request.
  svr.set_tcp_nodelay(true);
  svr.set_read_timeout(10);
  svr.set_write_timeout(10);
  svr.set_payload_max_length(16 * 1024 * 1024);  // larger bodies -> 413
  // Note: bodies sent as application/x-www-form-urlencoded are capped at 8 KB
  // (compile-time CPPHTTPLIB_FORM_URL_ENCODED_PAYLOAD_MAX_LENGTH) -> 413.

  svr.Get("/healthz", [](const httplib::Request&, httplib::Response& res) {
    res.set_content("ok", "text/plain");
  });
  svr.Post("/echo-size", [](const httplib::Request& req, httplib::Response& res) {
    res.set_content(std::to_string(req.body.size()), "text/plain");
  });
  svr.Post("/echo-size-work", [](const httplib::Request& req, httplib::Response& res) {
    busy_work_1ms();
    res.set_content(std::to_string(req.body.size()), "text/plain");
  });
  if (svr.listen("127.0.0.1", port)) return 0;
  std::fprintf(stderr, "httplib: cannot listen on port %d\n", port);
  return 1;
}
