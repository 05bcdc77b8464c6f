// A corrupt index must give an error or a (meaningless) result, never a crash or an
// out-of-bounds read: the localizer reads big arrays without verifying checksums first.
#include <gtest/gtest.h>

#include <cstring>
#include <fstream>

#include "app/database/database_queries.h"
#include "format/index.h"
#include "localizer/localizer.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

TEST(CorruptIndex, RandomWordsInAnySectionNeverCrashTheLocalizer) {
  test::TempDir dir;
  std::string output;
  ASSERT_EQ(test::RunCommand(test::ToolPath("cwloc-synth").string() +
                                 " --preset demo --queries 3 -o " + (dir / "city").string(),
                             &output),
            0)
      << output;
  ASSERT_EQ(test::RunCommand(test::ToolPath("cwloc-index").string() + " build --model " +
                                 (dir / "city" / "mapping_model" / "bin").string() +
                                 " --database " + (dir / "city" / "database.db").string() + " -o " +
                                 (dir / "city.cwl").string(),
                             &output),
            0)
      << output;
  const DatabaseQueries database(dir / "city" / "database.db");
  std::vector<Query> queries;
  std::ifstream list(dir / "city" / "query_list.txt");
  for (std::string name; std::getline(list, name);) queries.push_back(database.Load(name));
  ASSERT_EQ(queries.size(), 3u);

  const std::vector<uint8_t> original = test::ReadBytes(dir / "city.cwl");
  std::vector<SectionEntry> sections;
  {
    const Index index = Index::Open(dir / "city.cwl");
    sections.assign(index.file().sections().begin(), index.file().sections().end());
  }
  std::mt19937_64& rng = test::Rng();
  int errors = 0, results = 0;
  for (const SectionEntry& section : sections) {
    if (section.tag == section::kManifest || section.size < 4) continue;
    // Under a sanitizer one trial per section (each still gets 8 words): three took 34 s.
    for (int trial = 0; trial < (test::kSanitized ? 1 : 3); ++trial) {
      std::vector<uint8_t> bytes = original;
      // Overwrite a few 32-bit words with large or random values: out-of-range indices.
      for (int word = 0; word < 8; ++word) {
        const uint64_t at = section.offset + (rng() % (section.size / 4)) * 4;
        const uint32_t value =
            (rng() & 1) ? static_cast<uint32_t>(rng()) : 0xFFFFFFF0u + (rng() % 16);
        std::memcpy(bytes.data() + at, &value, 4);
      }
      const auto path = dir / "corrupt.cwl";
      test::WriteBytes(path, bytes);
      try {
        const Index index = Index::Open(path);
        const Localizer localizer(index);
        for (const Query& query : queries) {
          localizer.Localize(query, LocalizerOptions{});
          ++results;
        }
      } catch (const InputError&) {
        ++errors;
      }
    }
  }
  EXPECT_GT(results + errors, 0);
}

}  // namespace
}  // namespace cwloc
