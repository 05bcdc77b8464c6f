#include "base/bounded_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>

#include "base/error.h"

namespace cwloc {
namespace {

const char* KindOfFile(mode_t mode) {
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISFIFO(mode)) return "a pipe";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a file";
}

// The check both functions make, on the path's status and again on the open file's.
void CheckStatus(const std::filesystem::path& path, const struct stat& st, const InputKind& kind) {
  if (S_ISDIR(st.st_mode)) throw InputError(path.string() + ": is a directory, not " + kind.what);
  if (!S_ISREG(st.st_mode)) {
    throw InputError(path.string() + ": not a regular file (" + KindOfFile(st.st_mode) + "); " +
                     kind.what + " must be a regular file, not a device, a pipe, a socket or " +
                     "/dev/stdin");
  }
  const auto size = static_cast<uint64_t>(st.st_size);
  if (size > kind.max_bytes) {
    throw InputError(path.string() + ": " + FormatFileSize(size, kind.max_bytes) +
                     ", more than the " + FormatFileSize(kind.max_bytes) + " limit for " +
                     kind.what);
  }
}

}  // namespace

std::string FormatFileSize(uint64_t bytes, uint64_t below) {
  static constexpr const char* kUnits[] = {"B", "KB", "MB", "GB", "TB", "PB", "EB"};
  int unit = 0;
  uint64_t scale = 1;  // bytes per unit
  while (unit + 1 < 7 && bytes / scale >= 1000) {
    scale *= 1000;
    ++unit;
  }
  // One decimal, or as many as it takes to exceed `below`; truncated, never rounded up.
  int decimals = unit == 0 ? 0 : 1;
  uint64_t step = unit == 0 ? 1 : scale / 10;  // bytes per last shown digit
  while (step > 1 && bytes > below && bytes / step * step <= below) {
    step /= 10;
    ++decimals;
  }
  std::string text = std::to_string(bytes / scale);
  if (decimals > 0) {
    std::string fraction = std::to_string(bytes % scale / step);
    fraction.insert(fraction.begin(), static_cast<size_t>(decimals) - fraction.size(), '0');
    while (!fraction.empty() && fraction.back() == '0') fraction.pop_back();
    if (!fraction.empty()) text += "." + fraction;
  }
  return text + " " + kUnits[unit];
}

std::optional<uint64_t> CheckInputFile(const std::filesystem::path& path, const InputKind& kind) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return std::nullopt;
  CheckStatus(path, st, kind);
  return static_cast<uint64_t>(st.st_size);
}

void ReadFileInChunks(const std::filesystem::path& path, const InputKind& kind,
                      const std::function<void(std::span<const uint8_t>)>& consume) {
  CheckInputFile(path, kind);
  // O_NONBLOCK: a path replaced by a pipe since the check must not block the open.
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NOCTTY | O_NONBLOCK);
  if (fd < 0) throw InputError(path.string() + ": cannot open the file");
  try {
    struct stat st {};
    if (::fstat(fd, &st) != 0) throw InputError(path.string() + ": cannot read the file");
    CheckStatus(path, st, kind);
    constexpr uint64_t kChunkBytes = uint64_t{4} << 20;
    std::vector<uint8_t> chunk(
        size_t(std::clamp<uint64_t>(uint64_t(st.st_size) + 1, 4096, kChunkBytes)));
    uint64_t total = 0;
    for (;;) {
      const ssize_t got = ::read(fd, chunk.data(), chunk.size());
      if (got < 0 && errno == EINTR) continue;
      if (got < 0) throw InputError(path.string() + ": cannot read the file");
      if (got == 0) break;
      total += uint64_t(got);
      if (total > kind.max_bytes) {
        throw InputError(path.string() + ": more than the " + FormatFileSize(kind.max_bytes) +
                         " limit for " + kind.what + " (it grew while being read)");
      }
      consume({chunk.data(), size_t(got)});
    }
  } catch (...) {
    ::close(fd);
    throw;
  }
  ::close(fd);
}

std::vector<uint8_t> ReadFileBounded(const std::filesystem::path& path, const InputKind& kind) {
  std::vector<uint8_t> bytes;
  if (const std::optional<uint64_t> size = CheckInputFile(path, kind))
    bytes.reserve(size_t(std::min(*size, kind.max_bytes)));
  ReadFileInChunks(path, kind, [&](std::span<const uint8_t> chunk) {
    bytes.insert(bytes.end(), chunk.begin(), chunk.end());
  });
  return bytes;
}

}  // namespace cwloc
