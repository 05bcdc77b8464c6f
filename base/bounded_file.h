#pragma once

// The one way the tools read a user-supplied file (issue #23): before anything is read, a path
// that is not a regular file (a device such as /dev/zero, a pipe, a socket, /dev/stdin from a
// pipe or a terminal, a directory) or that is larger than its kind's limit is refused with an
// InputError naming the file and the limit, so the tools exit 2 at once instead of reading
// until memory runs out. The limits are tabled in docs/reliability.md ("Input files").

#include <cstdint>
#include <filesystem>
#include <functional>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace cwloc {

// A kind of input file: its name in messages, with its article ("a feature file"), and the
// largest size read, in bytes.
struct InputKind {
  const char* what;
  uint64_t max_bytes;
};

inline constexpr uint64_t kNoSizeLimit = std::numeric_limits<uint64_t>::max();

// Photos (--image, --image-list, --georef-images): a 100-megapixel photo, the default
// --max-image-pixels, is 20 to 60 MB as JPEG and ~400 MB as a 16-bit RGB PNG.
inline constexpr InputKind kPhotoFile{"an image", 512'000'000};
// COLMAP text feature files (--features): 100k features are ~50 MB of text, 1 GB about 2M.
inline constexpr InputKind kFeatureFile{"a feature file", 1'000'000'000};
// Query and image lists (--query-list, --image-list, cwloc-index extract --images and update
// --remove-images): a million queries with their cameras at 256 bytes a line.
inline constexpr InputKind kQueryListFile{"a query or image list", 256'000'000};
// Priors files (--priors): a position and a gravity line for a million queries.
inline constexpr InputKind kPriorsFile{"a priors file", 256'000'000};
// Motion files (--motion): a million frames at 256 bytes a line.
inline constexpr InputKind kMotionFile{"a motion file", 256'000'000};
// Rig configs (cwloc-localize --rig): a few cameras each; 16 MB are thousands of rigs.
inline constexpr InputKind kRigConfigFile{"a rig config", 16'000'000};
// Frames files (cwloc-localize --frames): a million images at 256 bytes a line.
inline constexpr InputKind kFramesFile{"a frames file", 256'000'000};
// Georef files (cwloc-index --georef): a million images at 256 bytes a line.
inline constexpr InputKind kGeorefFile{"a georef file", 256'000'000};
// Clustering files (cwloc-index --cluster-file): a million images at 256 bytes a line.
inline constexpr InputKind kClusterFile{"a clustering file", 256'000'000};
// Each file of a COLMAP sparse model, text or binary: images.txt holds every 2D point of every
// image, about 40 bytes each, so a 100k-image city of 8k-keypoint photos has a 32 GB images.txt
// (19 GB as .bin). The readers stream; memory grows with the model, not the file.
inline constexpr InputKind kColmapModelFile{"a COLMAP model file", 256'000'000'000};
// A COLMAP database.db: SQLite reads only the pages it needs, whatever the file's size, so only
// its being a regular file is checked.
inline constexpr InputKind kColmapDatabaseFile{"a COLMAP database", kNoSizeLimit};
// cwloc-eval's inputs (results, ground truth, poses, query points): the JSON lines of a
// 1M-query batch are about 1.5 GB.
inline constexpr InputKind kEvalInputFile{"an evaluation input", 4'000'000'000};

// Refuses `path` before it is opened: "<path>: is a directory, not <what>", "<path>: not a
// regular file (a character device); <what> must be a regular file, not a device, a pipe, a
// socket or /dev/stdin", or "<path>: 3.2 GB, more than the 1 GB limit for <what>". Symbolic
// links are followed. A path that does not exist or cannot be examined passes (nullopt): the
// reader's own open reports it in its words. Otherwise returns the file's size. For readers
// that stream a file (std::ifstream line by line) or hand its path to a library (SQLite);
// the file is checked by its name, so one replaced between the check and the open escapes it.
std::optional<uint64_t> CheckInputFile(const std::filesystem::path& path, const InputKind& kind);

// A whole file's bytes, refused as CheckInputFile refuses it before anything is read and
// checked again once open; "<path>: cannot open the file" or "<path>: cannot read the file"
// otherwise. Never more than kind.max_bytes: a file that grows past it while being read (or a
// /proc file, whose size is 0) is refused as well.
std::vector<uint8_t> ReadFileBounded(const std::filesystem::path& path, const InputKind& kind);

// The same file read in chunks of at most 4 MiB, each given to `consume` in order: for readers
// that need the bytes once (hashing a model of gigabytes), never the whole file in memory.
void ReadFileInChunks(const std::filesystem::path& path, const InputKind& kind,
                      const std::function<void(std::span<const uint8_t>)>& consume);

// "3.2 GB", "512 MB", "100 B": decimal units, the digits `bytes` needs to show it exceeds
// `below` (so 1,000,000,001 bytes against 1 GB reads "1.000000001 GB").
std::string FormatFileSize(uint64_t bytes, uint64_t below = 0);

}  // namespace cwloc
