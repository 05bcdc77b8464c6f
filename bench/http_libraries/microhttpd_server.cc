// Minimal libmicrohttpd server for bench/http_library_bench.sh.
// Usage: microhttpd_server PORT
// Threading: MHD_USE_INTERNAL_POLLING_THREAD + MHD_OPTION_THREAD_POOL_SIZE 2
// (epoll event loops; handlers run on those 2 threads), not
// thread-per-connection, so the thread count stays at 2 whatever the
// number of clients.
#include <arpa/inet.h>
#include <microhttpd.h>
#include <netinet/in.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

namespace {

constexpr size_t kMaxBody = 16 * 1024 * 1024;

struct RequestState {
  size_t body_size = 0;
  bool too_large = false;
};

void busy_work_1ms() {
  const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(1);
  volatile unsigned long sink = 0;
  while (std::chrono::steady_clock::now() < end) ++sink;
}

MHD_Result reply(MHD_Connection* conn, unsigned status, const std::string& body) {
  MHD_Response* res = MHD_create_response_from_buffer(body.size(), const_cast<char*>(body.data()),
                                                      MHD_RESPMEM_MUST_COPY);
  MHD_add_response_header(res, MHD_HTTP_HEADER_CONTENT_TYPE, "text/plain");
  MHD_Result ret = MHD_queue_response(conn, status, res);
  MHD_destroy_response(res);
  return ret;
}

MHD_Result handler(void*, MHD_Connection* conn, const char* url, const char* method, const char*,
                   const char* /*upload_data*/, size_t* upload_size, void** con_cls) {
  auto* st = static_cast<RequestState*>(*con_cls);
  if (st == nullptr) {            // first call: headers only. Replying now would make MHD
    *con_cls = new RequestState;  // close the connection (request not fully read).
    return MHD_YES;
  }
  if (*upload_size != 0) {  // body chunk
    st->body_size += *upload_size;
    if (st->body_size > kMaxBody) st->too_large = true;
    *upload_size = 0;
    return MHD_YES;
  }
  // request complete
  if (std::strcmp(method, MHD_HTTP_METHOD_GET) == 0 && std::strcmp(url, "/healthz") == 0)
    return reply(conn, MHD_HTTP_OK, "ok");
  const bool work = std::strcmp(url, "/echo-size-work") == 0;
  if (std::strcmp(method, MHD_HTTP_METHOD_POST) != 0 ||
      (!work && std::strcmp(url, "/echo-size") != 0))
    return reply(conn, MHD_HTTP_NOT_FOUND, "not found");
  if (st->too_large) return reply(conn, MHD_HTTP_CONTENT_TOO_LARGE, "too large");
  if (work) busy_work_1ms();
  return reply(conn, MHD_HTTP_OK, std::to_string(st->body_size));
}

void completed(void*, MHD_Connection*, void** con_cls, MHD_RequestTerminationCode) {
  delete static_cast<RequestState*>(*con_cls);
  *con_cls = nullptr;
}

volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) return 2;
  const auto port = static_cast<uint16_t>(std::atoi(argv[1]));
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(port);
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  MHD_Daemon* d =
      MHD_start_daemon(MHD_USE_INTERNAL_POLLING_THREAD | MHD_USE_EPOLL, port, nullptr, nullptr,
                       &handler, nullptr, MHD_OPTION_SOCK_ADDR, &addr, MHD_OPTION_THREAD_POOL_SIZE,
                       2u, MHD_OPTION_CONNECTION_TIMEOUT, 10u,  // idle/slow client, seconds
                       MHD_OPTION_CONNECTION_MEMORY_LIMIT, size_t{64 * 1024},  // bounds headers
                       MHD_OPTION_CONNECTION_LIMIT, 256u, MHD_OPTION_NOTIFY_COMPLETED, &completed,
                       nullptr, MHD_OPTION_END);
  if (d == nullptr) {
    std::fprintf(stderr, "microhttpd: cannot start on port %u\n", unsigned{port});
    return 1;
  }
  std::signal(SIGTERM, on_signal);
  std::signal(SIGINT, on_signal);
  while (!g_stop) pause();
  MHD_stop_daemon(d);
  return 0;
}
