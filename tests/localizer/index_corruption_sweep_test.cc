// Issue #13's sweeps over the golden format 1.1 index (every section, the optional GEOR too)
// and the compact format 1.2 one (PQCB, PCOD, PVNN):
// every byte of the header and the section table flipped, with the stored checksums and with
// checksums recomputed over the flip; random flips inside every section; truncation at every
// boundary and at random lengths. Open refuses, or verify (what `cwloc-index verify` runs)
// reports, each one with a message naming the file; the localizer, which runs without verify
// as on a device, returns on whatever Open accepts. Built in every build, a device build under
// qemu included: it needs no SQLite and no tools.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <regex>
#include <set>
#include <span>
#include <stdexcept>

#include "app/camera_spec.h"
#include "app/feature_file.h"
#include "format/index.h"
#include "format/xxhash64.h"
#include "localizer/localizer.h"
#include "tests/localization_check.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

using testing::HasSubstr;
using testing::StartsWith;

// A golden file the sweeps damage, with the queries of its city.
struct SweptIndex {
  std::string name;  // test name suffix
  std::string file;
  std::string queries;
  bool georeferenced = false;  // the second query then gets a GPS prior

  std::filesystem::path path() const { return test::GoldenDir() / file; }
};

void PrintTo(const SweptIndex& swept, std::ostream* os) { *os << swept.file; }

const SweptIndex kSweptIndexes[] = {
    {"Format1_1", "index-1.1.cwl", "index-1.1-queries", true},
    {"Format1_2Compact", "index-1.2.cwl", "index-1.0-queries", false},
};

class IndexCorruptionSweep : public testing::TestWithParam<SweptIndex> {};

// Search budgets well below the defaults: the sweeps localize over a thousand damaged files,
// through the same code paths.
LocalizerOptions SweepOptions() {
  LocalizerOptions options;
  options.checks = 64;
  options.forward_matches = 60;
  options.back_matches = 60;
  options.max_back_clusters = 4;
  options.query_tree_checks = 16;
  return options;
}

// Two golden queries: one plain, one (when georeferenced) with a GPS prior around the city, so
// that a damaged GEOR that Open accepts is used too.
std::vector<Query> GoldenQueries(const SweptIndex& swept) {
  const auto dir = test::GoldenDir() / swept.queries;
  const auto truth = test::ReadGroundTruth(dir / "queries_gt.txt");
  std::vector<Query> queries;
  for (const std::string name : {"query_00001.jpg", "query_00002.jpg"}) {
    Query& query = queries.emplace_back();
    query.name = name;
    ReadFeatureFile(dir / (name + ".txt"), &query);
    query.camera = ParseCameraSpec(truth.at(name).camera, name);
  }
  // The city's centre (cwloc-synth --geo "47.3779 8.5403 455", tests/data/README.md).
  if (swept.georeferenced) {
    queries[1].position_prior = PositionPrior{{.latitude_deg = 47.3779,
                                               .longitude_deg = 8.5403,
                                               .height_m = std::nullopt,
                                               .radius_m = 300}};
  }
  return queries;
}

// A copy of the golden file changed in place and restored: much faster than writing a whole
// file per flip.
class ScratchIndex {
 public:
  ScratchIndex(const test::TempDir& dir, const std::filesystem::path& golden)
      : path_(dir / "index.cwl"), original_(test::ReadBytes(golden)) {
    test::WriteBytes(path_, original_);
  }

  const std::filesystem::path& path() const { return path_; }
  const std::vector<uint8_t>& original() const { return original_; }

  // Overwrites the bytes at `offset` until Restore().
  void Write(uint64_t offset, std::span<const uint8_t> bytes) {
    WriteToFile(offset, bytes);
    changed_.emplace_back(offset, bytes.size());
  }
  void Flip(uint64_t offset, uint8_t mask) {
    const uint8_t value = original_[offset] ^ mask;
    Write(offset, {&value, 1});
  }
  void Restore() {
    for (const auto& [offset, size] : changed_)
      WriteToFile(offset, std::span(original_).subspan(offset, size));
    changed_.clear();
  }

 private:
  void WriteToFile(uint64_t offset, std::span<const uint8_t> bytes) const {
    std::fstream file(path_, std::ios::binary | std::ios::in | std::ios::out);
    file.seekp(static_cast<std::streamoff>(offset));
    file.write(reinterpret_cast<const char*>(bytes.data()),
               static_cast<std::streamsize>(bytes.size()));
    if (!file.flush()) throw std::runtime_error(path_.string() + ": cannot write");
  }

  std::filesystem::path path_;
  std::vector<uint8_t> original_;
  std::vector<std::pair<uint64_t, size_t>> changed_;
};

// The golden file's section table and where it lies (at the end of the file).
struct Layout {
  std::vector<SectionEntry> sections;
  uint64_t table_offset = 0;
  uint64_t table_end = 0;
};

Layout LayoutOf(const std::filesystem::path& path) {
  const Index index = Index::Open(path);
  Layout layout;
  layout.sections.assign(index.file().sections().begin(), index.file().sections().end());
  layout.table_offset = index.file().header().section_table_offset;
  layout.table_end = layout.table_offset + layout.sections.size() * sizeof(SectionEntry);
  return layout;
}

// Every byte of the header and of the section table.
std::vector<uint64_t> HeaderAndTableOffsets(const Layout& layout) {
  std::vector<uint64_t> offsets;
  for (uint64_t i = 0; i < sizeof(FileHeader); ++i) offsets.push_back(i);
  for (uint64_t i = layout.table_offset; i < layout.table_end; ++i) offsets.push_back(i);
  return offsets;
}

// Every bit of a byte, then one of its bits (a different one for each byte).
std::vector<uint8_t> MasksFor(uint64_t offset) {
  return {0xFF, static_cast<uint8_t>(1u << (offset % 8))};
}

// What each stage said about one damaged file.
struct Outcome {
  std::string open_error;      // Index::Open's InputError
  std::string localize_error;  // the localizer's InputError
  std::string verify_error;    // VerifyChecksums', then Validate's: `cwloc-index verify`
  std::string validate_error;  // Validate's alone, as if the checksums had been fixed up
  std::vector<LocalizationResult> results;
};

// Opens, localizes `queries` without verifying (as a device does), then verifies. A crash or
// an exception other than InputError fails the test.
Outcome OpenLocalizeAndVerify(const std::filesystem::path& path, std::span<const Query> queries) {
  Outcome outcome;
  std::optional<Index> index;
  outcome.open_error = test::InputErrorOf([&] { index.emplace(Index::Open(path)); });
  if (!index) return outcome;
  outcome.localize_error = test::InputErrorOf([&] {
    const Localizer localizer(*index);
    for (const Query& query : queries) {
      outcome.results.push_back(localizer.Localize(query, SweepOptions()));
      EXPECT_TRUE(outcome.results.back().success || !outcome.results.back().failure_reason.empty())
          << query.name;
    }
  });
  // The localizer refuses what it cannot use with the file's name (a corrupt kd-forest or
  // cluster id; a prior on a file whose GEOR tag no longer reads as GEOR).
  if (!outcome.localize_error.empty()) {
    EXPECT_THAT(outcome.localize_error, HasSubstr(path.string())) << outcome.localize_error;
  }
  outcome.validate_error = test::InputErrorOf([&] { index->Validate(); });
  outcome.verify_error = test::InputErrorOf([&] {
    index->file().VerifyChecksums();
    index->Validate();
  });
  return outcome;
}

// Messages counted by kind (without their path, tags, numbers and hashes), for the summary
// each sweep prints.
class ErrorTally {
 public:
  explicit ErrorTally(std::string path) : path_(std::move(path)) {}

  void Add(const std::string& message) {
    if (message.empty()) return;
    static const std::regex kVariable("('[^']*'|[0-9a-f]{16}|[0-9]+)+");
    ++counts_[std::regex_replace(message.substr(message.find(path_) == 0 ? path_.size() : 0),
                                 kVariable, "#")];
    ++total_;
  }
  int total() const { return total_; }
  void Print(const std::string& what) const {
    std::cout << total_ << " " << what << "\n";
    for (const auto& [kind, count] : counts_) std::cout << "  " << count << " x" << kind << "\n";
  }

 private:
  std::string path_;
  std::map<std::string, int> counts_;
  int total_ = 0;
};

// What Open says about a flipped header byte: the fields it reads before the checksum have
// their own message.
std::string ExpectedHeaderError(uint64_t offset) {
  if (offset < offsetof(FileHeader, byte_order_mark))
    return ": not a cwloc index (wrong magic; expected \"CWLOCIDX\")";
  if (offset < offsetof(FileHeader, format_major)) return ": wrong byte-order mark 0x";
  if (offset < offsetof(FileHeader, format_minor)) return ": index format ";
  return ": header checksum mismatch (stored ";
}

TEST_P(IndexCorruptionSweep, EveryFlippedHeaderAndSectionTableByteIsRefusedByOpen) {
  test::TempDir dir;
  ScratchIndex file(dir, GetParam().path());
  const std::string name = file.path().string();
  const Layout layout = LayoutOf(file.path());
  // Every section of its format: 1.1's 16, 1.2's compact 17.
  ASSERT_EQ(layout.sections.size(), GetParam().georeferenced ? 16u : 17u);
  ASSERT_EQ(layout.table_end, file.original().size());

  std::map<std::string, int> flips_by_error;
  for (const uint64_t offset : HeaderAndTableOffsets(layout)) {
    for (const uint8_t mask : MasksFor(offset)) {
      SCOPED_TRACE("byte " + std::to_string(offset) + " ^ " + std::to_string(mask));
      file.Flip(offset, mask);
      const Outcome outcome = OpenLocalizeAndVerify(file.path(), {});
      file.Restore();
      // The header and table checksums cover every byte here.
      const std::string expected = offset < sizeof(FileHeader)
                                       ? ExpectedHeaderError(offset)
                                       : ": section table checksum mismatch (stored ";
      EXPECT_THAT(outcome.open_error, StartsWith(name + expected));
      if (expected.find("checksum") != std::string::npos) {
        EXPECT_THAT(outcome.open_error, HasSubstr("): the file is corrupt"));
      }
      ++flips_by_error[expected];
    }
  }
  int flips = 0;
  for (const auto& [error, count] : flips_by_error) {
    std::cout << count << " flips refused by Open with '" << error << "'\n";
    flips += count;
  }
  EXPECT_EQ(flips, 2 * (128 + int(layout.sections.size()) * 48));
}

// Fields a 1.x reader does not read: flipped under valid checksums, the file means the same.
bool IsIgnoredField(uint64_t offset, const Layout& layout) {
  auto in = [](uint64_t at, size_t begin, size_t end) { return at >= begin && at < end; };
  if (offset < sizeof(FileHeader)) {
    return in(offset, offsetof(FileHeader, format_minor), offsetof(FileHeader, header_size)) ||
           in(offset, offsetof(FileHeader, optional_features), offsetof(FileHeader, file_size)) ||
           in(offset, offsetof(FileHeader, reserved0),
              offsetof(FileHeader, section_table_checksum)) ||
           in(offset, offsetof(FileHeader, reserved), offsetof(FileHeader, header_checksum));
  }
  const uint64_t in_entry = (offset - layout.table_offset) % sizeof(SectionEntry);
  // Bit 0 of the flags only matters for a tag this reader does not know.
  return in(in_entry, offsetof(SectionEntry, flags), offsetof(SectionEntry, offset)) ||
         in(in_entry, offsetof(SectionEntry, reserved), offsetof(SectionEntry, checksum));
}

// The tag of a section that is not required: renamed, it reads as an unknown optional
// section, and the file as one without that section (no keypoints, not georeferenced).
bool IsOptionalSectionTag(uint64_t offset, const Layout& layout) {
  if (offset < layout.table_offset) return false;
  const SectionEntry& entry =
      layout.sections[(offset - layout.table_offset) / sizeof(SectionEntry)];
  return (offset - layout.table_offset) % sizeof(SectionEntry) < sizeof(entry.tag) &&
         !(entry.flags & kSectionRequired);
}

// A writer's bug or a deliberate edit: one byte flipped, then both checksums recomputed. Open's
// structural checks and verify must find all but the fields no reader reads, whose flips
// change no result.
TEST_P(IndexCorruptionSweep, FlippedHeaderAndTableBytesUnderValidChecksumsAreFoundOrIgnored) {
  test::TempDir dir;
  ScratchIndex file(dir, GetParam().path());
  const std::string name = file.path().string();
  const Layout layout = LayoutOf(file.path());
  const std::vector<Query> queries = GoldenQueries(GetParam());
  const Outcome intact = OpenLocalizeAndVerify(file.path(), queries);
  ASSERT_EQ(intact.results.size(), 2u);
  ASSERT_TRUE(intact.results[0].success && intact.results[1].success);

  const auto& original = file.original();
  int flips = 0, reported_by_verify = 0, ignored = 0, optional_renamed = 0;
  ErrorTally refused_by_open(name), refused_by_localizer(name);
  for (const uint64_t offset : HeaderAndTableOffsets(layout)) {
    // The checksums themselves are recomputed over the flip.
    if (offset >= offsetof(FileHeader, section_table_checksum) &&
        offset < offsetof(FileHeader, reserved))
      continue;
    if (offset >= offsetof(FileHeader, header_checksum) && offset < sizeof(FileHeader)) continue;
    for (const uint8_t mask : MasksFor(offset)) {
      SCOPED_TRACE("byte " + std::to_string(offset) + " ^ " + std::to_string(mask));
      std::vector<uint8_t> header(original.begin(), original.begin() + sizeof(FileHeader));
      std::vector<uint8_t> table(original.begin() + layout.table_offset,
                                 original.begin() + layout.table_end);
      (offset < sizeof(FileHeader) ? header[offset] : table[offset - layout.table_offset]) ^= mask;
      const uint64_t table_checksum = XxHash64(table);
      std::memcpy(&header[offsetof(FileHeader, section_table_checksum)], &table_checksum, 8);
      const uint64_t header_checksum =
          XxHash64({header.data(), offsetof(FileHeader, header_checksum)});
      std::memcpy(&header[offsetof(FileHeader, header_checksum)], &header_checksum, 8);
      file.Write(0, header);
      file.Write(layout.table_offset, table);
      // One query a flip, in turn: the accepted flips are many.
      const size_t query = flips % 2;
      const Outcome outcome =
          OpenLocalizeAndVerify(file.path(), std::span(queries).subspan(query, 1));
      file.Restore();
      ++flips;
      refused_by_localizer.Add(outcome.localize_error);
      if (!outcome.open_error.empty()) {
        EXPECT_THAT(outcome.open_error, StartsWith(name + ": "));
        refused_by_open.Add(outcome.open_error);
      } else if (!outcome.verify_error.empty()) {
        EXPECT_THAT(outcome.verify_error, StartsWith(name + ": "));
        ++reported_by_verify;
      } else if (IsOptionalSectionTag(offset, layout)) {
        ++optional_renamed;
      } else {
        EXPECT_TRUE(IsIgnoredField(offset, layout)) << "neither Open nor verify found it";
        ++ignored;
        ASSERT_EQ(outcome.results.size(), 1u) << outcome.localize_error;
        const LocalizationResult& result = outcome.results[0];
        const LocalizationResult& expected = intact.results[query];
        EXPECT_EQ(result.success, expected.success);
        EXPECT_EQ(result.num_inliers, expected.num_inliers);
        EXPECT_EQ(result.rotation, expected.rotation);
        EXPECT_EQ(result.translation, expected.translation);
      }
    }
  }
  EXPECT_EQ(refused_by_open.total() + reported_by_verify + optional_renamed + ignored, flips);
  std::cout << flips << " flips under valid checksums: " << reported_by_verify
            << " reported by verify, " << optional_renamed << " renamed an optional section, "
            << ignored << " in ignored fields with unchanged results, and\n";
  refused_by_open.Print("refused by Open:");
  refused_by_localizer.Print("files Open accepted refused by the localizer:");
}

TEST_P(IndexCorruptionSweep, RandomFlipsInEverySectionAreReportedAndNeverCrashTheLocalizer) {
  // Under a sanitizer half as many: every section is still flipped, sanitized, each run.
  constexpr int kFlipsPerSection = test::kSanitized ? 12 : 24;
  test::TempDir dir;
  ScratchIndex file(dir, GetParam().path());
  const std::string name = file.path().string();
  const Layout layout = LayoutOf(file.path());
  const std::vector<Query> queries = GoldenQueries(GetParam());
  auto& rng = test::Rng();
  int flips = 0, reported_by_verify = 0, found_by_validate = 0, localizations = 0, localized = 0;
  ErrorTally refused_by_open(name), refused_by_localizer(name);
  for (size_t i = 0; i < layout.sections.size(); ++i) {
    const SectionEntry& entry = layout.sections[i];
    const std::string tag = SectionTagName(entry.tag);
    for (int trial = 0; trial < kFlipsPerSection; ++trial) {
      const uint64_t offset = entry.offset + rng() % entry.size;
      const auto mask = static_cast<uint8_t>(1 + rng() % 255);
      SCOPED_TRACE(tag + " byte " + std::to_string(offset) + " ^ " + std::to_string(mask));
      file.Flip(offset, mask);
      const Outcome outcome = OpenLocalizeAndVerify(file.path(), queries);
      file.Restore();
      ++flips;
      if (!outcome.open_error.empty()) {
        // Open reads only GEOR's contents (one element, checked in full).
        EXPECT_THAT(outcome.open_error, StartsWith(name + ": section 'GEOR': "));
        refused_by_open.Add(outcome.open_error);
        continue;
      }
      refused_by_localizer.Add(outcome.localize_error);
      localizations += static_cast<int>(outcome.results.size());
      for (const LocalizationResult& result : outcome.results) localized += result.success;
      // Every section has a checksum, so verify reports every flip Open accepts.
      EXPECT_THAT(outcome.verify_error, StartsWith(name + ": section " + std::to_string(i) + " '" +
                                                   tag + "': checksum mismatch (stored "));
      reported_by_verify += !outcome.verify_error.empty();
      found_by_validate += !outcome.validate_error.empty();
    }
  }
  EXPECT_EQ(flips, kFlipsPerSection * int(layout.sections.size()));
  EXPECT_EQ(refused_by_open.total() + reported_by_verify, flips);
  std::cout << flips << " flips: " << reported_by_verify << " reported by verify ("
            << found_by_validate << " of them by Validate without the checksums), " << localizations
            << " localizations of them, " << localized << " localized, and\n";
  refused_by_open.Print("refused by Open:");
  refused_by_localizer.Print("files Open accepted refused by the localizer:");
}

// Open's message for a file of `size` bytes whose header says `full_size`.
std::string TruncationError(const std::string& name, uint64_t size, uint64_t full_size) {
  if (size < sizeof(FileHeader)) {
    return name + ": truncated: " + std::to_string(size) +
           " bytes, smaller than the 128-byte header";
  }
  return name + ": truncated or extended: the header says " + std::to_string(full_size) +
         " bytes, the file has " + std::to_string(size);
}

TEST_P(IndexCorruptionSweep, TruncationAtEveryBoundaryAndRandomLengthsIsNamed) {
  constexpr int kRandomLengths = 100;
  test::TempDir dir;
  const std::vector<uint8_t> original = test::ReadBytes(GetParam().path());
  const uint64_t full = original.size();
  const Layout layout = LayoutOf(GetParam().path());

  // Empty, inside the header, just the header, every section's and the table's start and end,
  // each +-1.
  std::set<uint64_t> boundaries = {0, 1, 8, 64, sizeof(FileHeader), layout.table_offset, full};
  for (const SectionEntry& entry : layout.sections) {
    boundaries.insert(entry.offset);
    boundaries.insert(entry.offset + entry.size);
  }
  std::set<uint64_t> lengths;
  for (const uint64_t boundary : boundaries) {
    for (const uint64_t length : {boundary - 1, boundary, boundary + 1}) {
      if (length < full) lengths.insert(length);  // also drops 0 - 1
    }
  }
  const size_t at_boundaries = lengths.size();
  auto& rng = test::Rng();
  while (lengths.size() < at_boundaries + kRandomLengths) lengths.insert(rng() % full);

  const auto path = dir / "truncated.cwl";
  for (const uint64_t length : lengths) {
    test::WriteBytes(path, std::span(original).first(length));
    EXPECT_EQ(test::InputErrorOf([&] { Index::Open(path); }),
              TruncationError(path.string(), length, full));
  }
  // One byte too many is named too.
  std::vector<uint8_t> extended = original;
  extended.push_back(0);
  test::WriteBytes(path, extended);
  EXPECT_EQ(test::InputErrorOf([&] { Index::Open(path); }),
            TruncationError(path.string(), full + 1, full));
  std::cout << lengths.size() << " truncations (" << at_boundaries << " at boundaries, "
            << kRandomLengths << " random) and one extension refused by Open\n";
}

std::string TestName(const testing::TestParamInfo<SweptIndex>& swept) { return swept.param.name; }

INSTANTIATE_TEST_SUITE_P(GoldenFiles, IndexCorruptionSweep, testing::ValuesIn(kSweptIndexes),
                         TestName);

}  // namespace
}  // namespace cwloc
