#include "tests/test_util.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/file.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <thread>
#include <vector>

namespace cwloc::test {

std::mt19937_64& Rng() {
  static std::mt19937_64 rng;
  return rng;
}

std::filesystem::path SourceDir() {
  const char* env = std::getenv("CWLOC_SOURCE_DIR");
  return env ? env : CWLOC_TEST_SOURCE_DIR;
}

std::filesystem::path GoldenDir() { return SourceDir() / "tests" / "data" / "golden"; }

std::optional<std::filesystem::path> SharedDataDir(const std::string& name) {
  std::vector<std::filesystem::path> roots;
  if (const char* env = std::getenv("CWLOC_SHARED_DATA")) roots.emplace_back(env);
  roots.push_back(SourceDir() / ".." / "shared" / "data");
  for (const auto& root : roots) {
    std::error_code ec;
    if (std::filesystem::is_directory(root / name, ec))
      return std::filesystem::canonical(root / name);
  }
  return std::nullopt;
}

TempDir::TempDir() {
  static std::atomic<int> counter{0};
  path_ = std::filesystem::temp_directory_path() /
          ("cwloc_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
  std::filesystem::remove_all(path_);
  std::filesystem::create_directories(path_);
}

TempDir::~TempDir() {
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
}

namespace {

// Changes when this test binary or one of our tools is rebuilt.
std::string BuildFingerprint() {
  std::string stamps;
  std::error_code ec;
  for (const auto& file :
       {std::filesystem::read_symlink("/proc/self/exe", ec), ToolPath("cwloc-synth"),
        ToolPath("cwloc-index"), ToolPath("cwloc-localize")}) {
    const auto time = std::filesystem::last_write_time(file, ec);
    const auto size =
        std::filesystem::is_regular_file(file, ec) ? std::filesystem::file_size(file) : 0;
    stamps += file.string() + ":" + std::to_string(time.time_since_epoch().count()) + ":" +
              std::to_string(size) + ";";
  }
  char hex[17];
  std::snprintf(hex, sizeof(hex), "%016zx", std::hash<std::string>()(stamps));
  return hex;
}

}  // namespace

std::filesystem::path SharedFixture(const std::string& name,
                                    const std::function<void(const std::filesystem::path&)>& make) {
  // One folder per test binary: another binary's build never replaces what this one reads.
  std::error_code ec;
  const auto root = ToolPath("").parent_path().parent_path() / "test-fixtures" /
                    std::filesystem::read_symlink("/proc/self/exe", ec).filename();
  std::filesystem::create_directories(root);
  const auto folder = root / (name + "-" + BuildFingerprint());
  const int lock = ::open((root / (name + ".lock")).c_str(), O_CREAT | O_RDWR | O_CLOEXEC, 0644);
  if (lock < 0 || ::flock(lock, LOCK_EX) != 0)
    throw std::runtime_error(root.string() + ": cannot lock " + name + ": " + std::strerror(errno));
  struct Unlock {
    int fd;
    ~Unlock() { ::close(fd); }
  } unlock{lock};
  if (std::filesystem::is_directory(folder)) return folder;
  // Older builds' copies of this fixture, and a half-made one of a process that died.
  for (const auto& entry : std::filesystem::directory_iterator(root)) {
    const std::string entry_name = entry.path().filename().string();
    if (entry_name.size() == name.size() + 17 && entry_name.rfind(name + "-", 0) == 0 &&
        entry.is_directory())
      std::filesystem::remove_all(entry.path());
  }
  const auto partial = root / (name + ".partial");
  std::filesystem::remove_all(partial);
  std::filesystem::create_directories(partial);
  make(partial);
  if (testing::Test::HasFailure())
    throw std::runtime_error("shared fixture " + name + " could not be made");
  std::filesystem::rename(partial, folder);
  return folder;
}

std::vector<uint8_t> ReadBytes(const std::filesystem::path& path) {
  // In one read: a byte-wise iterator is slow in the tests' unoptimised code.
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) return {};
  std::vector<uint8_t> bytes(static_cast<size_t>(in.tellg()));
  in.seekg(0);
  in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  bytes.resize(static_cast<size_t>(in.gcount()));
  return bytes;
}

void WriteBytes(const std::filesystem::path& path, std::span<const uint8_t> bytes) {
  // A new file rather than the old one truncated: ext4 flushes a file truncated and rewritten
  // (auto_da_alloc), which makes loops that rewrite one file many times slow.
  std::filesystem::remove(path);
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
  if (!out.flush()) throw std::runtime_error(path.string() + ": cannot write");
}

std::filesystem::path WriteSparseFile(const std::filesystem::path& path, uint64_t size) {
  std::ofstream(path, std::ios::binary | std::ios::trunc).close();
  if (::truncate(path.c_str(), static_cast<off_t>(size)) != 0)
    throw std::runtime_error(path.string() +
                             ": cannot make a sparse file: " + std::strerror(errno));
  return path;
}

std::filesystem::path ToolPath(const std::string& name) {
  const char* dir = std::getenv("CWLOC_BIN_DIR");
  return std::filesystem::path(dir ? dir : CWLOC_TEST_BIN_DIR) / name;
}

std::string Quote(const std::filesystem::path& path) {
  // Appended, not "'" + string: that trips a GCC 12 -Wrestrict false positive.
  std::string quoted = "'";
  quoted += path.string();
  quoted += '\'';
  return quoted;
}

int RunCommand(const std::string& command, std::string* output) {
  output->clear();
  FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
  if (!pipe) return -1;
  std::array<char, 4096> buffer;
  size_t n;
  while ((n = std::fread(buffer.data(), 1, buffer.size(), pipe)) > 0)
    output->append(buffer.data(), n);
  const int status = ::pclose(pipe);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

int ValidateJson(const std::string& schema, const std::filesystem::path& file, bool lines,
                 std::string* output) {
  return RunCommand("/usr/bin/python3 " + Quote(SourceDir() / "tools" / "validate_json.py") + " " +
                        Quote(SourceDir() / "schemas" / schema) + " " + Quote(file) +
                        (lines ? " --lines" : ""),
                    output);
}

std::string UnderMemoryLimit(uint64_t kib, const std::string& command) {
  if (kSanitized) return command;
  return "ulimit -v " + std::to_string(kib) + " && " + command;
}

std::string Base64(const std::string& bytes) {
  static const char kDigits[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string text;
  for (size_t i = 0; i < bytes.size(); i += 3) {
    uint32_t bits = static_cast<uint8_t>(bytes[i]) << 16;
    if (i + 1 < bytes.size()) bits |= static_cast<uint8_t>(bytes[i + 1]) << 8;
    if (i + 2 < bytes.size()) bits |= static_cast<uint8_t>(bytes[i + 2]);
    const size_t chunk = std::min<size_t>(3, bytes.size() - i);
    for (size_t d = 0; d < 4; ++d) text += d <= chunk ? kDigits[bits >> (18 - 6 * d) & 63] : '=';
  }
  return text;
}

std::string ReadFile(const std::filesystem::path& path) {
  const std::vector<uint8_t> bytes = ReadBytes(path);
  return {bytes.begin(), bytes.end()};
}

std::vector<std::filesystem::path> ListDir(const std::filesystem::path& dir) {
  return {std::filesystem::directory_iterator(dir), std::filesystem::directory_iterator()};
}

pid_t Spawn(const std::vector<std::string>& args, const std::filesystem::path& output) {
  std::vector<char*> argv;
  for (const std::string& arg : args) argv.push_back(const_cast<char*>(arg.c_str()));
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  if (!output.empty()) {
    posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, output.c_str(),
                                     O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  }
  pid_t pid = 0;
  EXPECT_EQ(posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ), 0) << args[0];
  posix_spawn_file_actions_destroy(&actions);
  return pid;
}

int Wait(pid_t pid) {
  int status = 0;
  if (::waitpid(pid, &status, 0) != pid) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

bool KillAfter(pid_t pid, std::chrono::steady_clock::duration delay) {
  std::this_thread::sleep_for(delay);
  ::kill(pid, SIGKILL);
  return Wait(pid) >= 0;
}

bool WaitUntilCatching(pid_t pid, int signal_number, std::chrono::steady_clock::duration limit) {
  const auto give_up = std::chrono::steady_clock::now() + limit;
  const std::string status_path = "/proc/" + std::to_string(pid) + "/status";
  do {
    std::ifstream status(status_path);
    std::string line;
    while (std::getline(status, line)) {
      if (line.rfind("SigCgt:", 0) != 0) continue;
      const uint64_t caught = std::stoull(line.substr(7), nullptr, 16);
      if ((caught >> (signal_number - 1)) & 1) return true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  } while (std::chrono::steady_clock::now() < give_up);
  return false;
}

bool IsKilledWritersTemporary(const std::string& name, const std::string& destination,
                              const std::vector<pid_t>& killed) {
  return std::any_of(killed.begin(), killed.end(), [&](pid_t pid) {
    return name.rfind(destination + ".tmp-" + std::to_string(pid) + "-", 0) == 0;
  });
}

FileSizeLimit::FileSizeLimit(uint64_t bytes) {
  // Without this, exceeding the limit kills the process (SIGXFSZ) instead of failing write().
  old_handler_ = std::signal(SIGXFSZ, SIG_IGN);
  rlimit limit{};
  ::getrlimit(RLIMIT_FSIZE, &limit);
  old_soft_limit_ = limit.rlim_cur;
  limit.rlim_cur = bytes;
  ::setrlimit(RLIMIT_FSIZE, &limit);
}

FileSizeLimit::~FileSizeLimit() {
  rlimit limit{};
  ::getrlimit(RLIMIT_FSIZE, &limit);
  limit.rlim_cur = old_soft_limit_;
  ::setrlimit(RLIMIT_FSIZE, &limit);
  std::signal(SIGXFSZ, old_handler_);
}

}  // namespace cwloc::test
