// cwloc-serve: answers localization requests over HTTP from memory-mapped cwloc indexes
// (docs/serve.md).
#include <signal.h>
#include <sys/resource.h>
#ifdef __GLIBC__
#include <malloc.h>
#endif

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include "base/error.h"
#include "cwloc/version.h"
#include "exe/localize/table_flags.h"
#include "exe/tool_main.h"
#include "serve/server.h"

namespace cwloc {
namespace {

struct ServeCli {
  std::vector<std::string> indexes;
  std::string listen = "127.0.0.1:8080";
  std::string token_file;
  double max_body_mb = static_cast<double>(HttpLimits().max_body_bytes) / (1 << 20);
};

// "HOST:PORT", "[V6]:PORT" or ":PORT" (localhost).
void ParseListen(const std::string& text, ServeOptions* options) {
  const size_t colon = text.rfind(':');
  if (colon == std::string::npos) throw InputError("--listen '" + text + "': expected HOST:PORT");
  std::string host = text.substr(0, colon);
  if (host.size() >= 2 && host.front() == '[' && host.back() == ']')
    host = host.substr(1, host.size() - 2);
  options->host = host.empty() ? "127.0.0.1" : host;
  const std::string port = text.substr(colon + 1);
  if (port.empty() || port.size() > 5 ||
      port.find_first_not_of("0123456789") != std::string::npos || std::stoi(port) > 65535) {
    throw InputError("--listen '" + text + "': the port must be a number in 0..65535");
  }
  options->port = std::stoi(port);
}

// SIGTERM and SIGINT stop the server (the requests in flight finish), SIGHUP reloads the
// index files. Blocked in every thread before any starts, they are taken by sigwait here.
void HandleSignals(Server* server, const sigset_t& signals) {
  while (true) {
    int signal_number = 0;
    if (sigwait(&signals, &signal_number) != 0) continue;
    if (signal_number == SIGHUP) {
      server->Reload();
      continue;
    }
    std::fprintf(stderr, "cwloc-serve: %s: finishing the requests in flight\n",
                 signal_number == SIGINT ? "SIGINT" : "SIGTERM");
    server->Stop();
    return;
  }
}

// Each connection is a descriptor; the index files, the workers and the 503 answers' sockets
// need some more. The soft limit rises to what that needs, up to the hard one.
void RaiseOpenFileLimit(size_t max_connections) {
  const rlim_t needed = static_cast<rlim_t>(max_connections) + 256;
  rlimit limit{};
  if (getrlimit(RLIMIT_NOFILE, &limit) != 0 || limit.rlim_cur >= needed) return;
  limit.rlim_cur = limit.rlim_max == RLIM_INFINITY ? needed : std::min(needed, limit.rlim_max);
  setrlimit(RLIMIT_NOFILE, &limit);
  if (limit.rlim_cur < needed) {
    throw InputError("--max-connections " + std::to_string(max_connections) + " needs " +
                     std::to_string(needed) + " open files; the limit is " +
                     std::to_string(limit.rlim_cur) + " (ulimit -n)");
  }
}

int Run(const ServeCli& cli, ServeOptions options) {
  for (const std::string& index : cli.indexes) options.indexes.push_back(ParseIndexSpec(index));
  ParseListen(cli.listen, &options);
  if (!(cli.max_body_mb > 0) || cli.max_body_mb > 4096)
    throw InputError("--max-body-mb must be more than 0 and at most 4096");
  options.http.max_body_bytes = static_cast<size_t>(cli.max_body_mb * (1 << 20));
  if (!cli.token_file.empty()) options.token = ReadTokenFile(cli.token_file);
  RaiseOpenFileLimit(options.http.max_connections);

#ifdef __GLIBC__
  // A request's body and features are megabytes, freed when it ends. glibc's threshold for
  // giving such blocks back to the system rises with each one freed, after which they stay in
  // its per-thread arenas, which the server's connection threads multiply.
  mallopt(M_MMAP_THRESHOLD, 1 << 20);
#endif
  sigset_t signals;
  sigemptyset(&signals);
  for (const int signal_number : {SIGTERM, SIGINT, SIGHUP}) sigaddset(&signals, signal_number);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  signal(SIGPIPE, SIG_IGN);  // a client that hangs up is its connection's error, not ours

  const std::string host = options.host;
  const size_t num_indexes = options.indexes.size();
  Server server(std::move(options));
  const int port = server.Bind();
  std::fprintf(stderr, "cwloc-serve: listening on http://%s:%d/ (%zu index%s)\n",
               host.find(':') != std::string::npos ? ("[" + host + "]").c_str() : host.c_str(),
               port, num_indexes, num_indexes == 1 ? "" : "es");
  std::thread signal_thread(HandleSignals, &server, signals);
  server.Serve();
  signal_thread.join();
  std::fprintf(stderr, "cwloc-serve: stopped\n");
  return kExitOk;
}

}  // namespace
}  // namespace cwloc

int main(int argc, char** argv) {
  CLI::App app{"cwloc-serve: camera localization over HTTP from cwloc indexes (docs/serve.md)"};
  app.set_version_flag("--version", std::string("cwloc-serve ") + cwloc::kToolVersion);
  cwloc::ServeCli cli;
  cwloc::ServeOptions options;
  app.add_option("--index", cli.indexes,
                 "An index to serve: FILE (named by its file name without extension) or "
                 "NAME=FILE; repeat for several, the first is the default")
      ->required();
  app.add_option("--listen", cli.listen,
                 "HOST:PORT to listen on (port 0: a free one, printed on stderr); 0.0.0.0 "
                 "to accept other machines")
      ->capture_default_str();
  app.add_option("--threads", options.threads,
                 "Query workers (0: one per core); each runs one query at a time")
      ->capture_default_str();
  app.add_option("--queue", options.queue,
                 "Queries that may wait for a worker (0: " +
                     std::to_string(cwloc::kQueuedQueriesPerWorker) +
                     " per worker); more get 503 at once")
      ->capture_default_str();
  app.add_option("--max-connections", options.http.max_connections,
                 "Connections served at once; one more is answered 503 at once")
      ->capture_default_str();
  app.add_option("--max-body-mb", cli.max_body_mb, "Largest request body (MiB); larger get 413")
      ->capture_default_str();
  app.add_option("--request-timeout", options.http.request_timeout_s,
                 "Seconds a request's headers may take (from the connection's last answer), "
                 "its body this plus its size over --min-body-rate; later: 408")
      ->capture_default_str();
  app.add_option("--min-body-rate", options.http.min_body_rate,
                 "Bytes per second a request's body must at least arrive at")
      ->capture_default_str();
  app.add_option("--write-timeout", options.http.write_timeout_s,
                 "Seconds an answer may take to be sent before its connection is dropped")
      ->capture_default_str();
  app.add_option("--session-ttl", options.session_ttl_s,
                 "Seconds a tracking session may go without a frame before it ends")
      ->capture_default_str();
  app.add_option("--max-sessions", options.max_sessions, "Tracking sessions open at once")
      ->capture_default_str();
  app.add_option("--token-file", cli.token_file,
                 "A file whose first line is a token: every request then needs "
                 "'Authorization: Bearer TOKEN' (the viewer's files excepted), and POST "
                 "/v1/admin/reload is allowed");
  app.add_option("--allow-origin", options.allow_origin,
                 "CORS: let pages from this origin ('*' for any) call the API");
  app.add_option("--viewer-dir", options.viewer_dir,
                 "Serve the viewer's files from this folder (serve/viewer/) instead of the "
                 "built-in ones, read at every request: to work on the viewer");
  app.add_flag("--verify", options.verify,
               "Verify each index's checksums and stored indices when it is opened");
  app.add_flag("-q,--quiet", options.quiet, "No line per request on stderr");
  cwloc::TableFlags table_flags;
  table_flags.AddTo(&app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? cwloc::kExitOk : cwloc::kExitBadInput;
  }
  return cwloc::RunTool("cwloc-serve", [&] {
    table_flags.Apply(&options.defaults);
    return cwloc::Run(cli, std::move(options));
  });
}
