// cwloc-localize given a device, a pipe or an oversized file for any of its input files (issue
// #23): each is refused by name before anything is read, with exit code 2, under a 1 GB
// address-space limit that reading /dev/zero would exhaust in about a second.
#include <gmock/gmock.h>
#include <sys/stat.h>

#include <cstring>
#include <string>

#include "tests/test_util.h"

namespace cwloc {
namespace {

using test::Quote;
using testing::HasSubstr;

constexpr uint64_t kMemoryLimitKib = 1'048'576;  // 1 GB

std::string NotRegular(const std::string& path, const std::string& kind, const std::string& what) {
  return path + ": not a regular file (" + kind + "); " + what +
         " must be a regular file, not a device, a pipe, a socket or /dev/stdin";
}

class LocalizeInputLimitsTest : public testing::Test {
 protected:
  // cwloc-localize on the golden index with `args`, under the memory limit.
  int Run(const std::string& args, std::string* output) const {
    return test::RunCommand(
        test::UnderMemoryLimit(kMemoryLimitKib,
                               test::ToolPath("cwloc-localize").string() + " --index " +
                                   Quote(test::GoldenDir() / "index-1.1.cwl") + " " + args),
        output);
  }

  test::TempDir dir_;
};

TEST_F(LocalizeInputLimitsTest, DevZeroAsAQueryIsRefusedInItsErrorRecord) {
  std::string output;
  EXPECT_EQ(Run("--image /dev/zero", &output), 2) << output;
  const std::string photo_error = NotRegular("/dev/zero", "a character device", "an image");
  EXPECT_THAT(output, HasSubstr("\"error\":\"" + photo_error + "\""));
  EXPECT_THAT(output, HasSubstr("cwloc-localize: error: " + photo_error + "\n"));

  EXPECT_EQ(Run("--features /dev/zero --image-size '640 480'", &output), 2) << output;
  EXPECT_THAT(output,
              HasSubstr("cwloc-localize: error: " +
                        NotRegular("/dev/zero", "a character device", "a feature file") + "\n"));
}

TEST_F(LocalizeInputLimitsTest, DevZeroAsAListOrPriorsFileEndsTheRun) {
  std::string output;
  const std::string list_error =
      "cwloc-localize: error: " +
      NotRegular("/dev/zero", "a character device", "a query or image list") + "\n";
  EXPECT_EQ(Run("--query-list /dev/zero", &output), 2) << output;
  EXPECT_THAT(output, HasSubstr(list_error));
  EXPECT_EQ(Run("--image-list /dev/zero", &output), 2) << output;
  EXPECT_THAT(output, HasSubstr(list_error));

  const auto photo = test::SourceDir() / "tests/data/photos/rgb.jpg";
  EXPECT_EQ(Run("--image " + Quote(photo) + " --priors /dev/zero", &output), 2) << output;
  EXPECT_THAT(output,
              HasSubstr("cwloc-localize: error: " +
                        NotRegular("/dev/zero", "a character device", "a priors file") + "\n"));
}

// A named pipe nobody writes would block an open() forever; a directory reads as nothing.
TEST_F(LocalizeInputLimitsTest, PipesAndDirectoriesAreRefusedWithoutWaiting) {
  const auto fifo = dir_ / "queries.fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0) << std::strerror(errno);
  std::string output;
  EXPECT_EQ(Run("--image-list " + Quote(fifo), &output), 2) << output;
  EXPECT_THAT(output, HasSubstr("cwloc-localize: error: " +
                                NotRegular(fifo.string(), "a pipe", "a query or image list")));
  EXPECT_EQ(Run("--features " + Quote(fifo) + " --image-size '640 480'", &output), 2) << output;
  EXPECT_THAT(output, HasSubstr("cwloc-localize: error: " +
                                NotRegular(fifo.string(), "a pipe", "a feature file")));
  EXPECT_EQ(Run("--image " + Quote(dir_.path()), &output), 2) << output;
  EXPECT_THAT(output, HasSubstr("cwloc-localize: error: " + dir_.path().string() +
                                ": is a directory, not an image"));
}

TEST_F(LocalizeInputLimitsTest, FilesOverTheirLimitAreRefusedBeforeTheyAreRead) {
  std::string output;
  const auto features = test::WriteSparseFile(dir_ / "big.txt", 3'200'000'000);
  EXPECT_EQ(Run("--features " + Quote(features) + " --image-size '640 480'", &output), 2) << output;
  EXPECT_THAT(output, HasSubstr("cwloc-localize: error: " + features.string() +
                                ": 3.2 GB, more than the 1 GB limit for a feature file\n"));

  const auto list = test::WriteSparseFile(dir_ / "list.txt", 256'000'001);
  EXPECT_EQ(Run("--image-list " + Quote(list), &output), 2) << output;
  EXPECT_THAT(output,
              HasSubstr("cwloc-localize: error: " + list.string() +
                        ": 256.000001 MB, more than the 256 MB limit for a query or image list\n"));

  const auto photo = test::WriteSparseFile(dir_ / "huge.jpg", 600'000'000);
  EXPECT_EQ(Run("--image " + Quote(photo), &output), 2) << output;
  EXPECT_THAT(output, HasSubstr("cwloc-localize: error: " + photo.string() +
                                ": 600 MB, more than the 512 MB limit for an image\n"));

  const auto priors = test::WriteSparseFile(dir_ / "priors.txt", 1'000'000'000);
  EXPECT_EQ(Run("--features " + Quote(features) + " --priors " + Quote(priors), &output), 2)
      << output;
  EXPECT_THAT(output, HasSubstr("cwloc-localize: error: " + priors.string() +
                                ": 1 GB, more than the 256 MB limit for a priors file\n"));
}

}  // namespace
}  // namespace cwloc
