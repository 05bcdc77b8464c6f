#pragma once

// cwloc-serve: localization over HTTP/1.1 (docs/serve.md). One thread reads and writes every
// connection (http_server.h); queries run on a WorkQueue of --threads workers.

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "app/option_table.h"
#include "serve/http_server.h"
#include "serve/index_registry.h"

namespace cwloc {

// Queries that may wait per worker when --queue is 0: a burst or a second of the machine's
// slowdown at 80 % load (fast queries, ~10 ms) waits instead of being refused; --budget-ms
// bounds the wait where answers must be quick.
constexpr size_t kQueuedQueriesPerWorker = 16;

struct ServeOptions {
  std::vector<IndexSpec> indexes;  // the first is the default
  std::string host = "127.0.0.1";
  int port = 8080;             // 0: a free port (Bind returns it)
  int threads = 0;             // query workers; 0: the cores
  size_t queue = 0;            // queries waiting for a worker; 0: kQueuedQueriesPerWorker each
  HttpLimits http;             // connections, body and header sizes, deadlines
  double session_ttl_s = 300;  // a session unused for this long ends
  size_t max_sessions = 1024;
  std::string token;         // when set, requests need "Authorization: Bearer TOKEN"
  std::string allow_origin;  // CORS: the origin allowed, "*" for any; empty: none
  std::string viewer_dir;    // serve the viewer's files from here, not the built-in ones
  bool verify = false;       // verify every index file when it is opened
  bool quiet = false;        // no line per request on stderr
  // Every query's options before its own. Its localizer.budget_ms (--budget-ms) is each
  // request's deadline here, counted from when the request was read: one that no worker
  // started within it gets 503, one started gets the rest as the localizer's budget.
  QueryOptions defaults;
};

class Server {
 public:
  // Opens the indexes; throws InputError naming a file that fails.
  explicit Server(ServeOptions options);
  ~Server();
  Server(const Server&) = delete;
  Server& operator=(const Server&) = delete;

  // Binds the address; returns the port. Throws InputError when it cannot.
  int Bind();
  // Answers requests until Stop(), then lets those in flight finish.
  void Serve();
  // Stops accepting; safe from any thread.
  void Stop();
  // Opens the index files again and swaps them in; false (and why on stderr) when one fails,
  // and then the old ones stay.
  bool Reload();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The token in a --token-file: its first line, without surrounding whitespace; throws
// InputError for a file that cannot be read or holds no token.
std::string ReadTokenFile(const std::string& path);

}  // namespace cwloc
