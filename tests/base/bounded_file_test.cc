#include "base/bounded_file.h"

#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <string>
#include <vector>

#include "tests/test_util.h"

namespace cwloc {
namespace {

namespace fs = std::filesystem;

using test::InputErrorOf;

constexpr InputKind kSmallFile{"a test file", 100};

TEST(FormatFileSizeTest, DecimalUnitsWithTheDigitsThatShowTheExcess) {
  EXPECT_EQ(FormatFileSize(0), "0 B");
  EXPECT_EQ(FormatFileSize(999), "999 B");
  EXPECT_EQ(FormatFileSize(1000), "1 KB");
  EXPECT_EQ(FormatFileSize(512'000'000), "512 MB");
  EXPECT_EQ(FormatFileSize(1'000'000'000), "1 GB");
  EXPECT_EQ(FormatFileSize(3'249'999'999), "3.2 GB");  // truncated, not rounded
  EXPECT_EQ(FormatFileSize(16'800'000'000, 512'000'000), "16.8 GB");
  EXPECT_EQ(FormatFileSize(256'000'000'000), "256 GB");
  EXPECT_EQ(FormatFileSize(1'050'000'000, 1'000'000'000), "1.05 GB");
  EXPECT_EQ(FormatFileSize(1'000'000'001, 1'000'000'000), "1.000000001 GB");
  EXPECT_EQ(FormatFileSize(101, 100), "101 B");
  EXPECT_EQ(FormatFileSize(kNoSizeLimit), "18.4 EB");
}

TEST(ReadFileBoundedTest, ReadsAWholeFileUpToItsLimit) {
  test::TempDir dir;
  const std::vector<uint8_t> bytes(100, 0xAB);
  test::WriteBytes(dir / "a.bin", bytes);
  EXPECT_EQ(ReadFileBounded(dir / "a.bin", kSmallFile), bytes);
  EXPECT_EQ(CheckInputFile(dir / "a.bin", kSmallFile), 100u);
  test::WriteBytes(dir / "empty.bin", {});
  EXPECT_TRUE(ReadFileBounded(dir / "empty.bin", kSmallFile).empty());
  // Through a symbolic link: what counts is the file it names.
  fs::create_symlink(dir / "a.bin", dir / "link.bin");
  EXPECT_EQ(ReadFileBounded(dir / "link.bin", kSmallFile), bytes);
}

TEST(ReadFileBoundedTest, AFileOverTheLimitIsRefusedWithItsSizeAndTheLimit) {
  test::TempDir dir;
  test::WriteBytes(dir / "big.bin", std::vector<uint8_t>(101, 1));
  const std::string expected =
      (dir / "big.bin").string() + ": 101 B, more than the 100 B limit for a test file";
  EXPECT_EQ(InputErrorOf([&] { ReadFileBounded(dir / "big.bin", kSmallFile); }), expected);
  EXPECT_EQ(InputErrorOf([&] { CheckInputFile(dir / "big.bin", kSmallFile); }), expected);
}

TEST(ReadFileBoundedTest, AHugeSparseFileIsRefusedBeforeAnythingIsRead) {
  test::TempDir dir;
  const fs::path big = test::WriteSparseFile(dir / "big.txt", 3'200'000'000);
  EXPECT_EQ(InputErrorOf([&] { CheckInputFile(big, kFeatureFile); }),
            big.string() + ": 3.2 GB, more than the 1 GB limit for a feature file");
  EXPECT_EQ(InputErrorOf([&] { ReadFileBounded(big, kPhotoFile); }),
            big.string() + ": 3.2 GB, more than the 512 MB limit for an image");
  const fs::path just_over = test::WriteSparseFile(dir / "just_over.txt", 1'000'000'001);
  EXPECT_EQ(InputErrorOf([&] { CheckInputFile(just_over, kFeatureFile); }),
            just_over.string() + ": 1.000000001 GB, more than the 1 GB limit for a feature file");
  const fs::path at_limit = test::WriteSparseFile(dir / "at_limit.txt", 1'000'000'000);
  EXPECT_EQ(CheckInputFile(at_limit, kFeatureFile), 1'000'000'000u);
  // A city-sized COLMAP model file passes; the database has no limit.
  const fs::path model = test::WriteSparseFile(dir / "images.bin", 100'000'000'000);
  EXPECT_EQ(CheckInputFile(model, kColmapModelFile), 100'000'000'000u);
  EXPECT_EQ(CheckInputFile(model, kColmapDatabaseFile), 100'000'000'000u);
}

TEST(ReadFileBoundedTest, DevicesAreRefusedBeforeTheyAreRead) {
  const auto start = std::chrono::steady_clock::now();
  const std::string expected =
      "/dev/zero: not a regular file (a character device); a feature file must be a regular "
      "file, not a device, a pipe, a socket or /dev/stdin";
  EXPECT_EQ(InputErrorOf([] { ReadFileBounded("/dev/zero", kFeatureFile); }), expected);
  EXPECT_EQ(InputErrorOf([] { CheckInputFile("/dev/zero", kFeatureFile); }), expected);
  EXPECT_EQ(InputErrorOf([] { ReadFileBounded("/dev/urandom", kPhotoFile); }),
            "/dev/urandom: not a regular file (a character device); an image must be a regular "
            "file, not a device, a pipe, a socket or /dev/stdin");
  EXPECT_EQ(InputErrorOf([] { CheckInputFile("/dev/null", kColmapDatabaseFile); }),
            "/dev/null: not a regular file (a character device); a COLMAP database must be a "
            "regular file, not a device, a pipe, a socket or /dev/stdin");
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(10));
}

TEST(ReadFileBoundedTest, PipesSocketsAndDirectoriesAreRefusedWithoutBlocking) {
  test::TempDir dir;
  // A named pipe nobody writes: opening it would wait for a writer forever.
  const fs::path fifo = dir / "fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0) << std::strerror(errno);
  EXPECT_EQ(InputErrorOf([&] { ReadFileBounded(fifo, kSmallFile); }),
            fifo.string() +
                ": not a regular file (a pipe); a test file must be a regular file, not a "
                "device, a pipe, a socket or /dev/stdin");
  // An anonymous pipe, as a shell's <(...) or a piped /dev/stdin give it: /dev/fd/N.
  int fds[2];
  ASSERT_EQ(::pipe(fds), 0);
  const fs::path pipe_path = "/dev/fd/" + std::to_string(fds[0]);
  EXPECT_EQ(InputErrorOf([&] { CheckInputFile(pipe_path, kQueryListFile); }),
            pipe_path.string() +
                ": not a regular file (a pipe); a query or image list must be a regular file, "
                "not a device, a pipe, a socket or /dev/stdin");
  ::close(fds[0]);
  ::close(fds[1]);

  const fs::path socket_path = dir / "socket";
  const int socket_fd = ::socket(AF_UNIX, SOCK_STREAM, 0);
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  ASSERT_LT(socket_path.string().size(), sizeof(address.sun_path));
  std::strcpy(address.sun_path, socket_path.c_str());
  ASSERT_EQ(::bind(socket_fd, reinterpret_cast<sockaddr*>(&address), sizeof(address)), 0);
  EXPECT_EQ(InputErrorOf([&] { CheckInputFile(socket_path, kPriorsFile); }),
            socket_path.string() +
                ": not a regular file (a socket); a priors file must be a regular file, not a "
                "device, a pipe, a socket or /dev/stdin");
  ::close(socket_fd);

  EXPECT_EQ(InputErrorOf([&] { ReadFileBounded(dir.path(), kPhotoFile); }),
            dir.path().string() + ": is a directory, not an image");
  EXPECT_EQ(InputErrorOf([&] { CheckInputFile(dir.path(), kGeorefFile); }),
            dir.path().string() + ": is a directory, not a georef file");
}

TEST(ReadFileBoundedTest, AMissingFileIsLeftToTheReadersOwnMessage) {
  test::TempDir dir;
  EXPECT_EQ(CheckInputFile(dir / "missing.txt", kFeatureFile), std::nullopt);
  EXPECT_EQ(InputErrorOf([&] { ReadFileBounded(dir / "missing.jpg", kPhotoFile); }),
            (dir / "missing.jpg").string() + ": cannot open the file");
}

// A /proc file says it has 0 bytes and has more: the read stops at the limit all the same.
TEST(ReadFileBoundedTest, AFileLongerThanItsSizeSaysStopsAtTheLimit) {
  if (!fs::exists("/proc/self/status")) GTEST_SKIP() << "no /proc";
  EXPECT_FALSE(ReadFileBounded("/proc/self/status", kPriorsFile).empty());
  EXPECT_EQ(InputErrorOf([] {
              ReadFileBounded("/proc/self/status", InputKind{"a test file", 10});
            }),
            "/proc/self/status: more than the 10 B limit for a test file (it grew while being "
            "read)");
}

}  // namespace
}  // namespace cwloc
