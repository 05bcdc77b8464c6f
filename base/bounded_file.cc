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

std::vector<uint8_t> ReadFileBounded(const std::filesystem::path& path, const InputKind& kind) {
  CheckInputFile(path, kind);
  // O_NONBLOCK: a path replaced by a pipe since the check must not block the open.
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NOCTTY | O_NONBLOCK);
  if (fd < 0) throw InputError(path.string() + ": cannot open the file");
  std::vector<uint8_t> bytes;
  try {
    struct stat st {};
    if (::fstat(fd, &st) != 0) throw InputError(path.string() + ": cannot read the file");
    CheckStatus(path, st, kind);
    // Room for one byte more than the size, to see the end without growing.
    const uint64_t cap = kind.max_bytes == kNoSizeLimit ? kNoSizeLimit : kind.max_bytes + 1;
    bytes.resize(static_cast<size_t>(std::min<uint64_t>(st.st_size, cap - 1)) + 1);
    size_t used = 0;
    for (;;) {
      if (used == bytes.size()) {
        if (used > kind.max_bytes) {
          throw InputError(path.string() + ": more than the " + FormatFileSize(kind.max_bytes) +
                           " limit for " + kind.what + " (it grew while being read)");
        }
        bytes.resize(
            static_cast<size_t>(std::min<uint64_t>(cap, std::max<size_t>(used * 2, 4096))));
      }
      const ssize_t got = ::read(fd, bytes.data() + used, bytes.size() - used);
      if (got < 0 && errno == EINTR) continue;
      if (got < 0) throw InputError(path.string() + ": cannot read the file");
      if (got == 0) break;
      used += static_cast<size_t>(got);
    }
    bytes.resize(used);
  } catch (...) {
    ::close(fd);
    throw;
  }
  ::close(fd);
  return bytes;
}

}  // namespace cwloc
