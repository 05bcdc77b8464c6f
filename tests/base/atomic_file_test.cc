#include "base/atomic_file.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fstream>
#include <string>
#include <vector>

#include "base/error.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

namespace fs = std::filesystem;

using test::ListDir;
using test::ReadFile;

TEST(AtomicFileTest, CommitReplacesTheFileAndLeavesNoTemporaryFile) {
  test::TempDir dir;
  const fs::path path = dir / "a.bin";
  std::ofstream(path) << "old content";
  AtomicFile file(path);
  EXPECT_TRUE(file.temp_path().empty());  // unnamed: a kill now would leave nothing
  file.Write("new", 3);
  EXPECT_EQ(ReadFile(path), "old content");  // untouched until Commit()
  EXPECT_EQ(ListDir(dir.path()), std::vector<fs::path>{path});
  file.Commit();
  EXPECT_EQ(ReadFile(path), "new");
  EXPECT_EQ(ListDir(dir.path()), std::vector<fs::path>{path});
  EXPECT_EQ(fs::status(path).permissions() & fs::perms::owner_read, fs::perms::owner_read);
}

TEST(AtomicFileTest, ANewDestinationGetsTheUnnamedFileDirectly) {
  test::TempDir dir;
  AtomicFile file(dir / "new.bin");
  file.Write("x", 1);
  EXPECT_TRUE(ListDir(dir.path()).empty());
  file.Commit();
  EXPECT_EQ(ReadFile(dir / "new.bin"), "x");
  EXPECT_EQ(ListDir(dir.path()), std::vector<fs::path>{dir / "new.bin"});
}

// What a writer killed between its link and its rename, or a killed named writer, leaves.
TEST(AtomicFileTest, TemporaryFilesOfDeadWritersAreRemovedOthersKept) {
  test::TempDir dir;
  // A pid that no longer runs: a child that has exited and been reaped.
  const pid_t dead = fork();
  if (dead == 0) _exit(0);
  ASSERT_GT(dead, 0);
  ASSERT_EQ(waitpid(dead, nullptr, 0), dead);
  const fs::path stale = dir / ("a.bin.tmp-" + std::to_string(dead) + "-3");
  const fs::path live = dir / "a.bin.tmp-1-0";  // init runs: not provably dead
  const fs::path other = dir / ("b.bin.tmp-" + std::to_string(dead) + "-0");  // another file's
  for (const fs::path& p : {stale, live, other}) std::ofstream(p) << "left";
  AtomicFile file(dir / "a.bin");
  EXPECT_FALSE(fs::exists(stale));
  EXPECT_TRUE(fs::exists(live));
  EXPECT_TRUE(fs::exists(other));
}

TEST(AtomicFileTest, TemporaryNamesAreUnique) {
  test::TempDir dir;
  AtomicFile a(dir / "a.bin", AtomicFile::Temporary::kNamed),
      b(dir / "a.bin", AtomicFile::Temporary::kNamed);
  EXPECT_TRUE(fs::exists(a.temp_path()));
  EXPECT_NE(a.temp_path(), b.temp_path());
  b.Write("b", 1);
  b.Commit();
  a.Write("a", 1);
  a.Commit();  // the last commit wins
  EXPECT_EQ(ReadFile(dir / "a.bin"), "a");
  EXPECT_EQ(ListDir(dir.path()).size(), 1u);
}

TEST(AtomicFileTest, WithoutCommitNothingIsLeft) {
  test::TempDir dir;
  {
    AtomicFileWriter writer(dir / "a.bin");
    writer.Append("abandoned");
  }
  EXPECT_TRUE(ListDir(dir.path()).empty());
}

TEST(AtomicFileTest, MissingDirectoryIsAnErrorNamingTheFile) {
  test::TempDir dir;
  try {
    AtomicFile file(dir / "missing" / "a.bin");
    FAIL() << "expected an error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), (dir / "missing" / "a.bin").string() +
                                         ": cannot create a temporary file next to it: No such "
                                         "file or directory");
  }
}

TEST(AtomicFileTest, FailedWriteKeepsTheOldFileAndRemovesTheTemporaryOne) {
  for (const bool bypass_page_cache : {false, true}) {
    SCOPED_TRACE(bypass_page_cache ? "past the page cache" : "through the page cache");
    test::TempDir dir;
    const fs::path path = dir / "a.bin";
    std::ofstream(path) << "old content";
    try {
      const test::FileSizeLimit limit(4);
      AtomicFile file(path);
      if (bypass_page_cache) file.BypassPageCache();
      file.Write("too long for the limit", 22);
      file.Commit();
      FAIL() << "expected an error";
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()), path.string() + ": cannot write: File too large");
    }
    EXPECT_EQ(ReadFile(path), "old content");
    EXPECT_EQ(ListDir(dir.path()), std::vector<fs::path>{path});
  }
}

// Past the page cache, pieces of any size land as written: across the aligned buffer's end,
// and a last block cut to the content's size. On a file system without O_DIRECT (tmpfs before
// Linux 6.6) the same bytes go through the page cache.
TEST(AtomicFileTest, BypassingThePageCacheWritesTheSameBytes) {
  test::TempDir dir;
  std::vector<fs::path> dirs{dir.path()};
  if (fs::is_directory("/dev/shm")) dirs.push_back("/dev/shm");
  for (const fs::path& folder : dirs) {
    for (size_t total : {size_t{3}, size_t{4096}, (size_t{17} << 20) + 4099}) {
      SCOPED_TRACE(folder.string() + ", " + std::to_string(total) + " bytes");
      std::string expected(total, '\0');
      for (size_t i = 0; i < total; ++i) expected[i] = static_cast<char>('a' + i * 7 % 26);
      const fs::path path = folder / ("direct_" + std::to_string(::getpid()) + ".bin");
      AtomicFile file(path);
      file.BypassPageCache();
      for (size_t done = 0, piece = 1; done < total; piece = piece * 5 + 3) {
        const size_t n = std::min(piece, total - done);
        file.Write(expected.data() + done, n);
        done += n;
      }
      file.Commit();
      const bool same = ReadFile(path) == expected;
      fs::remove(path);
      EXPECT_TRUE(same);
    }
  }
}

// A header written last: bytes still in the buffer and bytes on the disk are replaced, in both
// modes; past the page cache, a part of a block already on the disk is refused.
TEST(AtomicFileTest, OverwriteReplacesBytesWrittenBefore) {
  test::TempDir dir;
  for (const bool bypass_page_cache : {false, true}) {
    for (const size_t total : {size_t{5000}, (size_t{17} << 20) + 10}) {
      SCOPED_TRACE(std::to_string(total) + (bypass_page_cache ? " bytes past the page cache"
                                                              : " bytes through the page cache"));
      std::string expected(total, 'x');
      const fs::path path = dir / "a.bin";
      AtomicFile file(path);
      if (bypass_page_cache) file.BypassPageCache();
      file.Write(expected.data(), total);
      const std::string first_block(4096, 'h');
      file.Overwrite(0, first_block.data(), first_block.size());
      expected.replace(0, 4096, first_block);
      file.Overwrite(total - 3, "end", 3);  // in the buffer, whichever mode
      expected.replace(total - 3, 3, "end");
      EXPECT_THROW(file.Overwrite(total - 2, "end", 3), std::logic_error);
      file.Commit();
      EXPECT_TRUE(ReadFile(path) == expected);
    }
  }
  const int probe = ::open((dir / "probe").c_str(), O_WRONLY | O_CREAT | O_DIRECT, 0644);
  if (probe < 0) GTEST_SKIP() << "no O_DIRECT in " << dir.path();
  ::close(probe);
  AtomicFile file(dir / "b.bin");
  file.BypassPageCache();
  const std::string content((size_t{17} << 20) + 10, 'y');
  file.Write(content.data(), content.size());
  EXPECT_THROW(file.Overwrite(100, "part", 4), std::logic_error);
}

TEST(AtomicFileTest, WriterBuffersSmallPiecesAndPassesLargeOnes) {
  test::TempDir dir;
  std::string expected;
  AtomicFileWriter writer(dir / "a.bin");
  for (int i = 0; i < 1000; ++i) {
    const std::string piece = std::to_string(i) + ",";
    writer.Append(piece);
    expected += piece;
  }
  char* cursor = writer.Ensure(2);
  *cursor++ = '|';
  writer.Advance(cursor);
  expected += '|';
  const std::string large(AtomicFileWriter::kBufferSize + 17, 'x');
  writer.Append(large);
  expected += large;
  writer.Append("end");
  expected += "end";
  writer.Commit();
  EXPECT_TRUE(ReadFile(dir / "a.bin") == expected);
}

// Between file systems copy_file_range fails (EXDEV); the copy goes through a buffer then.
TEST(AtomicFileTest, CopyFromAnotherFileSystemGoesThroughABuffer) {
  test::TempDir dir;
  if (!fs::is_directory("/dev/shm")) GTEST_SKIP() << "no /dev/shm";
  const fs::path source = "/dev/shm/cwloc_copy_test_" + std::to_string(::getpid());
  std::string content;
  for (int i = 0; i < 300000; ++i) content += static_cast<char>('a' + i % 26);
  std::ofstream(source, std::ios::binary) << content;
  const int fd = ::open(source.c_str(), O_RDONLY | O_CLOEXEC);
  ASSERT_GE(fd, 0);
  AtomicFile file(dir / "copy.bin");
  file.Write("<", 1);
  file.CopyFrom(fd, content.size() - 1);
  ::close(fd);
  fs::remove(source);
  file.Commit();
  std::string expected = "<";  // appended: "<" + string trips GCC 12's -Wrestrict
  expected.append(content, 0, content.size() - 1);
  EXPECT_TRUE(ReadFile(dir / "copy.bin") == expected);
}

}  // namespace
}  // namespace cwloc
