#include "base/checkpointed_file.h"

#include <gtest/gtest.h>

#include <chrono>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "base/error.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

namespace fs = std::filesystem;
using std::chrono::hours;
using std::chrono::milliseconds;
using test::ListDir;
using test::ReadFile;

TEST(CheckpointedFileTest, RecordsAppearOnlyAtCheckpointsAfterThePreviousFile) {
  test::TempDir dir;
  const fs::path path = dir / "out.jsonl";
  std::ofstream(path) << "previous\n";
  CheckpointedFile file(path, hours(1));
  file.Append("a\n");
  file.Append("b\n");
  EXPECT_EQ(ReadFile(path), "previous\n");  // until the first checkpoint
  EXPECT_EQ(ListDir(dir.path()), std::vector<fs::path>{path});
  file.Checkpoint();
  EXPECT_EQ(ReadFile(path), "a\nb\n");
  file.Append("c\n");
  EXPECT_EQ(ReadFile(path), "a\nb\n");
  file.Checkpoint();
  file.Checkpoint();  // nothing pending: nothing to do
  EXPECT_EQ(file.checkpoints(), 2);
  EXPECT_EQ(ReadFile(path), "a\nb\nc\n");
  file.Append("d\n");
  file.Close();
  EXPECT_EQ(ReadFile(path), "a\nb\nc\nd\n");
  EXPECT_EQ(ListDir(dir.path()), std::vector<fs::path>{path});
}

TEST(CheckpointedFileTest, CloseLeavesEveryRecordInOrder) {
  test::TempDir dir;
  const fs::path path = dir / "out.txt";
  std::string expected;
  CheckpointedFile file(path, hours(1));
  auto& rng = test::Rng();
  for (int i = 0; i < 20000; ++i) {
    const std::string record = std::to_string(i) + std::string(rng() % 300, 'x') + "\n";
    file.Append(record);
    expected += record;
    if (i % 3000 == 0) file.Checkpoint();  // each copies what was committed on
  }
  file.Close();
  EXPECT_EQ(file.checkpoints(), 8);
  EXPECT_TRUE(ReadFile(path) == expected);
}

TEST(CheckpointedFileTest, CheckpointsComeByThemselvesOnceTheIntervalPassed) {
  test::TempDir dir;
  const fs::path path = dir / "out.txt";
  CheckpointedFile file(path, milliseconds(20));
  file.Append("a\n");
  EXPECT_FALSE(fs::exists(path));
  std::this_thread::sleep_for(milliseconds(30));
  file.Append("b\n");  // due: this one goes in with it
  EXPECT_EQ(file.checkpoints(), 1);
  EXPECT_EQ(ReadFile(path), "a\nb\n");
}

// A run without records that completes leaves an empty file, as a truncating writer did; one
// that fails before its first record leaves the previous file.
TEST(CheckpointedFileTest, AnEmptyRunLeavesAnEmptyFileOnlyWhenClosed) {
  test::TempDir dir;
  const fs::path path = dir / "out.txt";
  std::ofstream(path) << "previous\n";
  { CheckpointedFile file(path); }
  EXPECT_EQ(ReadFile(path), "previous\n");
  CheckpointedFile(path).Close();
  EXPECT_TRUE(fs::exists(path));
  EXPECT_EQ(ReadFile(path), "");
}

// An exception unwinding past it keeps the records that were appended.
TEST(CheckpointedFileTest, DestroyedWithoutCloseItKeepsThePendingRecords) {
  test::TempDir dir;
  const fs::path path = dir / "out.txt";
  std::ofstream(path) << "previous\n";
  {
    CheckpointedFile file(path, hours(1));
    file.Append("a\n");
    file.Checkpoint();
    file.Append("b\n");
  }
  EXPECT_EQ(ReadFile(path), "a\nb\n");
  EXPECT_EQ(ListDir(dir.path()), std::vector<fs::path>{path});
}

TEST(CheckpointedFileTest, AnUnwritableFolderFailsAtOnce) {
  test::TempDir dir;
  const fs::path path = dir / "missing" / "out.txt";
  try {
    CheckpointedFile file(path);
    FAIL() << "expected an error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), path.string() +
                                         ": cannot create a temporary file next to it: No such "
                                         "file or directory");
  }
}

// A failed write may leave a part of its record in the new file: that file is never committed,
// the last checkpoint stays, and every later call fails.
TEST(CheckpointedFileTest, AFailedWriteKeepsTheLastCheckpoint) {
  test::TempDir dir;
  const fs::path path = dir / "out.txt";
  {
    CheckpointedFile file(path, hours(1));
    file.Append("a\n");
    file.Checkpoint();
    const test::FileSizeLimit limit(6);
    file.Append("b\n");
    EXPECT_THROW(file.Append("a record too long for the limit\n"), InputError);
    EXPECT_THROW(file.Append("c\n"), InputError);
    EXPECT_THROW(file.Close(), InputError);
  }
  EXPECT_EQ(ReadFile(path), "a\n");
  EXPECT_EQ(ListDir(dir.path()), std::vector<fs::path>{path});
}

// A symbolic link (as /dev/stdout is), a pipe or a device is written in place, record by
// record, and stays what it is.
TEST(CheckpointedFileTest, ADestinationThatIsNotARegularFileIsWrittenInPlace) {
  test::TempDir dir;
  const fs::path target = dir / "target.txt", link = dir / "link.txt";
  std::ofstream(target) << "previous\n";
  fs::create_symlink(target, link);
  CheckpointedFile file(link, hours(1));
  file.Append("a\n");
  EXPECT_EQ(ReadFile(target), "a\n");
  file.Close();
  EXPECT_TRUE(fs::is_symlink(link));
  EXPECT_EQ(ReadFile(target), "a\n");

  CheckpointedFile null("/dev/null");
  null.Append("a\n");
  null.Close();
  EXPECT_TRUE(fs::is_character_file("/dev/null"));
}

}  // namespace
}  // namespace cwloc
