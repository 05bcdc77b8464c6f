#pragma once
// A cwloc-serve process for one test: started on a free localhost port, stopped with SIGTERM.
#include <httplib.h>
#include <signal.h>
#include <sys/types.h>

#include <chrono>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <regex>
#include <string>
#include <thread>
#include <vector>

#include "localizer/query.h"
#include "tests/test_util.h"

namespace cwloc::test {

// A query's features in cwloc-serve's binary layout (app/feature_file.h: "CWLF", version 1, N,
// N x (x, y) float32, N x 128 descriptors; little-endian).
inline std::string BinaryFeatureBody(const Query& query) {
  std::string binary = "CWLF";
  const auto put_u32 = [&](uint32_t value) {
    for (int b = 0; b < 4; ++b) binary.push_back(static_cast<char>(value >> (8 * b) & 0xff));
  };
  put_u32(1);
  put_u32(query.NumFeatures());
  for (const float value : query.keypoints) {
    uint32_t bits;
    std::memcpy(&bits, &value, 4);
    put_u32(bits);
  }
  binary.append(reinterpret_cast<const char*>(query.descriptors.data()), query.descriptors.size());
  return binary;
}

class ServeProcess {
 public:
  // cwloc-serve --listen 127.0.0.1:0 -q with `args`; waits until it listens.
  explicit ServeProcess(std::vector<std::string> args) : log_(dir_ / "serve.log") {
    args.insert(args.begin(), {ToolPath("cwloc-serve").string(), "--listen", "127.0.0.1:0", "-q"});
    pid_ = Spawn(args, log_);
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    const std::regex listening("listening on http://127\\.0\\.0\\.1:([0-9]+)/");
    while (std::chrono::steady_clock::now() < give_up) {
      std::smatch match;
      const std::string text = Log();
      if (std::regex_search(text, match, listening)) {
        port_ = std::stoi(match[1]);
        return;
      }
      if (::waitpid(pid_, nullptr, WNOHANG) == pid_) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    ADD_FAILURE() << "cwloc-serve did not start: " << Log();
  }
  ~ServeProcess() {
    if (pid_ > 0 && !stopped_) {
      ::kill(pid_, SIGTERM);
      Wait(pid_);
    }
  }
  ServeProcess(const ServeProcess&) = delete;
  ServeProcess& operator=(const ServeProcess&) = delete;

  int port() const { return port_; }
  pid_t pid() const { return pid_; }
  std::string Log() const { return ReadFile(log_); }
  httplib::Client Client() const {
    httplib::Client client("127.0.0.1", port_);
    client.set_read_timeout(std::chrono::seconds(120));
    return client;
  }
  // SIGTERM, then its exit code.
  int Stop() {
    ::kill(pid_, SIGTERM);
    stopped_ = true;
    return Wait(pid_);
  }

 private:
  TempDir dir_;
  std::filesystem::path log_;
  pid_t pid_ = -1;
  int port_ = 0;
  bool stopped_ = false;
};

}  // namespace cwloc::test
