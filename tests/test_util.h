#pragma once

#include <sys/types.h>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <iterator>
#include <optional>
#include <random>
#include <span>
#include <string>
#include <vector>

#include "base/error.h"

namespace cwloc::test {

// True in a build with AddressSanitizer or ThreadSanitizer (CWLOC_SANITIZE), whose tests'
// own code is compiled without them (CWLOC_SANITIZED, cmake/CwlocHelpers.cmake).
#if defined(CWLOC_SANITIZED) || defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
inline constexpr bool kSanitized = true;
#elif defined(__has_feature)
inline constexpr bool kSanitized =
    __has_feature(address_sanitizer) || __has_feature(thread_sanitizer);
#else
inline constexpr bool kSanitized = false;
#endif

// The items a real-data test repeats one code path over (photos, queries): all of them, or the
// first under a sanitizer, which runs 10-20x slower and checks the path, not the accuracy over
// every item (the Release suite checks that). A plain iterator pair: clang 14 cannot compile
// libstdc++ 12's views.
template <typename Iterator>
struct Items {
  Iterator first, last;
  Iterator begin() const { return first; }
  Iterator end() const { return last; }
  size_t size() const { return static_cast<size_t>(std::distance(first, last)); }
};
template <typename Container>
auto SanitizerSample(const Container& items) {
  const auto first = std::begin(items), last = std::end(items);
  return Items<decltype(first)>{first, kSanitized && first != last ? std::next(first) : last};
}

// The PRNG every test draws from; test_main reseeds it before each test so a failure
// reproduces with --gtest_filter alone. The seed is printed when it differs from the default.
std::mt19937_64& Rng();

// The source tree ($CWLOC_SOURCE_DIR or the configured one): schemas, tools.
std::filesystem::path SourceDir();

// tests/data/golden: the committed index files of every format version (tests/data/README.md).
std::filesystem::path GoldenDir();

// ../shared/data/<name> next to the source tree (or $CWLOC_SHARED_DATA/<name>), if present.
std::optional<std::filesystem::path> SharedDataDir(const std::string& name);

// A fresh empty directory under the build tree's temp area, removed at the end of the test.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

// A fixture shared by the test processes of one build tree (ctest runs each test in a process
// of its own, so a suite's SetUpTestSuite runs once per test): the folder `make` fills, made
// once under a lock in the build tree and kept while this test binary and our tools stay as
// they are (a rebuild of either makes it anew). `make` writes into the folder it is given, or
// fails the test or throws, and then nothing is kept. Call it from SetUpTestSuite; read the
// folder, never write into it.
std::filesystem::path SharedFixture(const std::string& name,
                                    const std::function<void(const std::filesystem::path&)>& make);

// A whole file's bytes (empty when it cannot be read), and a file replaced by `bytes` (throws
// std::runtime_error when it cannot be written).
std::vector<uint8_t> ReadBytes(const std::filesystem::path& path);
void WriteBytes(const std::filesystem::path& path, std::span<const uint8_t> bytes);
// A file of `size` zero bytes that takes no disk space (a hole), for size limits; returns `path`.
std::filesystem::path WriteSparseFile(const std::filesystem::path& path, uint64_t size);

// The InputError message `body` throws, "" when it returns.
template <typename Body>
std::string InputErrorOf(Body&& body) {
  try {
    body();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// Path of an executable of ours in build/bin ($CWLOC_BIN_DIR or the configured one).
std::filesystem::path ToolPath(const std::string& name);

// A path in single quotes for a shell command line.
std::string Quote(const std::filesystem::path& path);

// Runs a shell command, captures stdout+stderr, returns the exit code.
int RunCommand(const std::string& command, std::string* output);

// tools/validate_json.py's exit code for `file` against schemas/`schema` (JSON lines when
// `lines`); its report in *output.
int ValidateJson(const std::string& schema, const std::filesystem::path& file, bool lines,
                 std::string* output);

// `command` for RunCommand under `ulimit -v kib` (the address space a small device leaves a
// tool). Sanitizer builds reserve terabytes of address space, so there it runs without one.
std::string UnderMemoryLimit(uint64_t kib, const std::string& command);

// A file's bytes as text ("" when it cannot be read) and a folder's entries.
std::string ReadFile(const std::filesystem::path& path);
std::vector<std::filesystem::path> ListDir(const std::filesystem::path& dir);

// RFC 4648 base64 with padding, as clients encode images in JSON.
std::string Base64(const std::string& bytes);

// Tools killed at random moments (docs/reliability.md, "Interrupted writers"): a child process
// running `args` (args[0] the executable; no shell), its stdout and stderr into `output` when
// one is given, waited for or killed.
pid_t Spawn(const std::vector<std::string>& args, const std::filesystem::path& output = {});
// Its exit code, or -1 when a signal ended it.
int Wait(pid_t pid);
// Sleeps for `delay`, kills it with SIGKILL and reaps it; true when it had exited before.
bool KillAfter(pid_t pid, std::chrono::steady_clock::duration delay);
// Waits until the process catches `signal_number` (its handler installed, as
// /proc/PID/status's SigCgt says), for at most `limit`; whether it does.
bool WaitUntilCatching(pid_t pid, int signal_number, std::chrono::steady_clock::duration limit);
// True when `name` is a temporary `<destination>.tmp-<pid>-...` of one of the `killed` writers.
// A writer killed before its own clean-up ran keeps every earlier killed writer's temporaries.
bool IsKilledWritersTemporary(const std::string& name, const std::string& destination,
                              const std::vector<pid_t>& killed);

// While alive, writes that grow a file past `bytes` fail with EFBIG ("File too large"), the
// way a full disk fails them; unlike /dev/full this reaches files of any name, even as root.
class FileSizeLimit {
 public:
  explicit FileSizeLimit(uint64_t bytes);
  ~FileSizeLimit();
  FileSizeLimit(const FileSizeLimit&) = delete;
  FileSizeLimit& operator=(const FileSizeLimit&) = delete;

 private:
  uint64_t old_soft_limit_;
  void (*old_handler_)(int);
};

}  // namespace cwloc::test

// Skips the current test with a message CTest shows, when shared data is absent.
#define CWLOC_REQUIRE_SHARED_DATA(var, name)                 \
  const auto var##_opt = ::cwloc::test::SharedDataDir(name); \
  if (!var##_opt)                                            \
    GTEST_SKIP() << "shared data '" << name                  \
                 << "' not found next to the source "        \
                    "tree (../shared/data); skipping";       \
  const std::filesystem::path var = *var##_opt
