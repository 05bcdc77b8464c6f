#include "format/index_file.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cstring>
#include <numeric>

#include "format/xxhash64.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

using testing::HasSubstr;

using test::ReadBytes;
using test::WriteBytes;

std::string OpenError(const std::filesystem::path& path) {
  return test::InputErrorOf([&] { IndexFile::Open(path); });
}

class IndexFileTest : public testing::Test {
 protected:
  void SetUp() override {
    floats_.resize(1000);
    std::iota(floats_.begin(), floats_.end(), 0.5f);
    bytes_.resize(777);
    for (auto& b : bytes_) b = static_cast<uint8_t>(test::Rng()());
    ids_ = {7, 1, 3};
    path_ = dir_ / "test.cwl";
    Write(path_);
  }

  std::vector<SectionData> Sections() const {
    return {MakeSection<float>(section::kViewNeighbor, floats_),
            MakeSection<uint8_t>(section::kDescriptors, bytes_),
            MakeSection<uint32_t>(section::kCovisOffsets, ids_)};
  }

  void Write(const std::filesystem::path& path) const { WriteIndexFile(path, Sections()); }

  test::TempDir dir_;
  std::filesystem::path path_;
  std::vector<float> floats_;
  std::vector<uint8_t> bytes_;
  std::vector<uint32_t> ids_;
};

TEST_F(IndexFileTest, RoundTripsEverySection) {
  const IndexFile file = IndexFile::Open(path_);
  EXPECT_EQ(file.header().format_major, kFormatMajor);
  ASSERT_EQ(file.sections().size(), 3u);
  const auto floats = file.Section<float>(section::kViewNeighbor);
  EXPECT_TRUE(std::equal(floats.begin(), floats.end(), floats_.begin(), floats_.end()));
  const auto bytes = file.Section<uint8_t>(section::kDescriptors);
  EXPECT_TRUE(std::equal(bytes.begin(), bytes.end(), bytes_.begin(), bytes_.end()));
  const auto ids = file.Section<uint32_t>(section::kCovisOffsets);
  EXPECT_TRUE(std::equal(ids.begin(), ids.end(), ids_.begin(), ids_.end()));
  for (const SectionEntry& entry : file.sections()) EXPECT_EQ(entry.offset % kSectionAlignment, 0u);
  EXPECT_NO_THROW(file.VerifyChecksums());
}

TEST_F(IndexFileTest, HeaderBytesAreAsSpecified) {
  const std::vector<uint8_t> bytes = ReadBytes(path_);
  ASSERT_GE(bytes.size(), 128u);
  EXPECT_EQ(std::string(bytes.begin(), bytes.begin() + 8), "CWLOCIDX");
  EXPECT_EQ(bytes[8], 0x04);  // byte-order mark 0x01020304, little-endian
  EXPECT_EQ(bytes[11], 0x01);
  EXPECT_EQ(bytes[12], kFormatMajor);
  EXPECT_EQ(bytes[14], 1);    // no section newer than format 1.1
  EXPECT_EQ(bytes[16], 128);  // header size
  EXPECT_EQ(bytes[20], 48);   // section entry size
  // First section starts right after the header; the 4000 float bytes pad to 4032.
  const uint64_t table_offset = 128 + 4032 + 832 + 64;
  uint64_t stored_table_offset = 0;
  std::memcpy(&stored_table_offset, bytes.data() + 48, 8);
  EXPECT_EQ(stored_table_offset, table_offset);
  EXPECT_EQ(bytes.size(), table_offset + 3 * 48);
  EXPECT_EQ(std::string(bytes.begin() + table_offset, bytes.begin() + table_offset + 4), "VNND");
}

TEST_F(IndexFileTest, OutputIsByteIdenticalForTheSameInput) {
  const auto second = dir_ / "second.cwl";
  Write(second);
  EXPECT_EQ(ReadBytes(path_), ReadBytes(second));
}

// The write in steps (leading sections in two batches, on a second thread or not, the rest
// after) gives the one-step write's bytes; the rest must follow the leading sections, and an
// unfinished writer leaves nothing.
TEST_F(IndexFileTest, WritingLeadingSectionsAheadGivesTheSameBytes) {
  const std::vector<SectionData> sections = Sections();
  for (const bool background : {false, true}) {
    const auto path = dir_ / (background ? "ahead_background.cwl" : "ahead.cwl");
    IndexFileWriter writer(path, {sections[0]}, background);
    writer.WriteAhead({sections[1]}, background);
    EXPECT_FALSE(std::filesystem::exists(path));
    writer.Finish(sections, kIndexContainer, 0, std::nullopt);
    EXPECT_EQ(ReadBytes(path), ReadBytes(path_));
  }
  {
    IndexFileWriter writer(dir_ / "other.cwl", {sections[1]}, true);
    EXPECT_THROW(writer.Finish(sections, kIndexContainer, 0, std::nullopt), std::logic_error);
  }
  { IndexFileWriter writer(dir_ / "unfinished.cwl", {sections[0]}, true); }
  EXPECT_FALSE(std::filesystem::exists(dir_ / "other.cwl"));
  EXPECT_FALSE(std::filesystem::exists(dir_ / "unfinished.cwl"));
}

TEST_F(IndexFileTest, WritingReplacesAtomicallyAndLeavesNoTemporaryFile) {
  Write(path_);
  size_t files = 0;
  for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator(dir_.path()))
    ++files;
  EXPECT_EQ(files, 1u);
}

TEST_F(IndexFileTest, UnwritableDirectoryIsAClearError) {
  try {
    WriteIndexFile(dir_ / "missing_dir" / "x.cwl", Sections());
    FAIL() << "expected an error";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("x.cwl: cannot create a temporary file next to it"));
  }
}

TEST_F(IndexFileTest, TruncatedFileIsReported) {
  std::vector<uint8_t> bytes = ReadBytes(path_);
  bytes.resize(bytes.size() - 10);
  WriteBytes(path_, bytes);
  EXPECT_THAT(OpenError(path_), HasSubstr("truncated or extended: the header says"));
  bytes.resize(57);
  WriteBytes(path_, bytes);
  EXPECT_THAT(OpenError(path_), HasSubstr("truncated: 57 bytes, smaller than the 128-byte header"));
}

TEST_F(IndexFileTest, WrongMagicIsReported) {
  std::vector<uint8_t> bytes = ReadBytes(path_);
  bytes[0] = 'X';
  WriteBytes(path_, bytes);
  EXPECT_EQ(OpenError(path_),
            path_.string() + ": not a cwloc index (wrong magic; expected \"CWLOCIDX\")");
}

TEST_F(IndexFileTest, NewerMajorVersionNamesBothVersions) {
  std::vector<uint8_t> bytes = ReadBytes(path_);
  bytes[12] = 2;
  const uint64_t checksum = XxHash64({bytes.data(), 120});
  std::memcpy(bytes.data() + 120, &checksum, 8);
  WriteBytes(path_, bytes);
  EXPECT_EQ(
      OpenError(path_),
      path_.string() +
          ": index format 2.1 is not readable by this cwloc, which reads format 1.x (up to 1.5); "
          "rebuild the index with this cwloc-index or upgrade cwloc");
}

TEST_F(IndexFileTest, FlippedHeaderByteIsReported) {
  std::vector<uint8_t> bytes = ReadBytes(path_);
  bytes[40] ^= 0x10;  // file_size
  WriteBytes(path_, bytes);
  EXPECT_THAT(OpenError(path_), HasSubstr("header checksum mismatch"));
}

TEST_F(IndexFileTest, FlippedByteInAnySectionIsFoundByVerify) {
  const std::vector<uint8_t> original = ReadBytes(path_);
  const IndexFile file = IndexFile::Open(path_);
  std::vector<SectionEntry> entries(file.sections().begin(), file.sections().end());
  for (const SectionEntry& entry : entries) {
    for (const uint64_t at : {uint64_t{0}, entry.size / 2, entry.size - 1}) {
      std::vector<uint8_t> bytes = original;
      bytes[entry.offset + at] ^= 0x01;
      const auto corrupt = dir_ / "corrupt.cwl";
      WriteBytes(corrupt, bytes);
      const IndexFile opened = IndexFile::Open(corrupt);  // open stays O(sections)
      try {
        opened.VerifyChecksums();
        ADD_FAILURE() << "flip in " << SectionTagName(entry.tag) << " at " << at << " not found";
      } catch (const InputError& e) {
        EXPECT_THAT(e.what(), HasSubstr("'" + SectionTagName(entry.tag) + "': checksum mismatch"));
      }
    }
  }
}

TEST_F(IndexFileTest, FlippedSectionTableByteIsReported) {
  std::vector<uint8_t> bytes = ReadBytes(path_);
  bytes[bytes.size() - 48 + 8] ^= 0x40;  // last entry's offset
  WriteBytes(path_, bytes);
  EXPECT_THAT(OpenError(path_), HasSubstr("section table checksum mismatch"));
}

TEST_F(IndexFileTest, MissingSectionOrWrongElementSizeIsReported) {
  const IndexFile file = IndexFile::Open(path_);
  EXPECT_THROW(file.Section<uint32_t>(section::kTracks), InputError);
  try {
    file.Section<double>(section::kViewNeighbor);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("section 'VNND' has 4-byte elements (expected 8)"));
  }
}

TEST_F(IndexFileTest, UnknownOptionalSectionIsSkippedUnknownRequiredIsRefused) {
  const std::vector<uint32_t> extra = {1, 2, 3};
  std::vector<SectionData> sections = Sections();
  sections.push_back(MakeSection<uint32_t>(SectionTag("ZZZZ"), extra, /*flags=*/0));
  WriteIndexFile(path_, sections);
  EXPECT_NO_THROW(IndexFile::Open(path_));
  sections.back().flags = kSectionRequired;
  WriteIndexFile(path_, sections);
  EXPECT_THAT(OpenError(path_),
              HasSubstr("section 3 'ZZZZ': a required section unknown to this cwloc"));
}

TEST_F(IndexFileTest, MissingFileIsAClearError) {
  EXPECT_THAT(OpenError(dir_ / "nope.cwl"),
              HasSubstr("nope.cwl: cannot open: No such file or directory"));
}

// A device, a folder or a named pipe with no writer (which open() would wait on) is refused.
TEST_F(IndexFileTest, WhatIsNotARegularFileIsRefusedAtOnce) {
  const std::filesystem::path fifo = dir_ / "pipe.cwl";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_EQ(OpenError(fifo), fifo.string() + ": not a regular file");
  EXPECT_EQ(OpenError("/dev/zero"), "/dev/zero: not a regular file");
  EXPECT_EQ(OpenError(dir_.path()), dir_.path().string() + ": not a regular file");
}

}  // namespace
}  // namespace cwloc
