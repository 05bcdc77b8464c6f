// The build option table (indexer/build_option_table.inc): its ranges are the kd-forest's and
// the format's own, its values parse and land where the table says, and one function checks
// them with the messages every surface prints.
#include "indexer/build_option_table.h"

#include <gmock/gmock.h>

#include <algorithm>
#include <set>
#include <stdexcept>
#include <vector>

#include "kdtree/descriptor_codes.h"
#include "kdtree/descriptor_distance.h"
#include "kdtree/kd_forest_builder.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

std::string ValidationError(const IndexBuildOptions& options, const IndexBuildFlags& flags = {}) {
  return test::InputErrorOf([&] { ValidateBuildOptions(options, flags); });
}

TEST(BuildOptionTableTest, FlagsAreUniqueAndTheDefaultsAreInRange) {
  std::set<std::string_view> flags;
  for (const BuildOptionSpec& spec : BuildOptionTable()) {
    EXPECT_TRUE(flags.insert(spec.flag).second) << spec.flag;
    EXPECT_FALSE(spec.help.empty()) << spec.flag;
    EXPECT_EQ(&FindBuildOption(spec.flag), &spec);
  }
  EXPECT_EQ(flags.size(), 15u);
  EXPECT_EQ(ValidationError(IndexBuildOptions()), "");
  EXPECT_EQ(test::InputErrorOf([] { FindBuildOption("tree"); }), "unknown option 'tree'");
}

// The table's leaf-size range is BuildKdForest's: the largest it accepts passes, one more is
// refused before anything is read instead of inside the kd-forest build.
TEST(BuildOptionTableTest, LeafSizeIsTheKdForestsRange) {
  IndexBuildOptions options;
  options.forest.max_leaf_size = kMaxKdLeafSize;
  EXPECT_EQ(ValidationError(options), "");
  std::vector<uint8_t> descriptors(16 * kDescriptorDim, 7);
  EXPECT_NO_THROW(BuildKdForest(descriptors, options.forest));
  options.forest.max_leaf_size = kMaxKdLeafSize + 1;
  EXPECT_EQ(ValidationError(options), "--leaf-size 255: expected 1 to 254");
  EXPECT_THROW(BuildKdForest(descriptors, options.forest), std::invalid_argument);
  options.forest.max_leaf_size = 0;
  EXPECT_EQ(ValidationError(options), "--leaf-size 0: expected 1 to 254");

  options = IndexBuildOptions();
  options.forest.num_trees = kMaxKdTrees + 1;
  EXPECT_EQ(ValidationError(options), "--trees 65: expected 1 to 64");
  EXPECT_THROW(BuildKdForest(descriptors, options.forest), std::invalid_argument);
}

// --code-bytes' choices are 0 and exactly the code sizes the format accepts.
TEST(BuildOptionTableTest, CodeBytesChoicesAreTheFormatsCodeSizes) {
  ASSERT_EQ(kCodeBytesChoices.front(), 0u);
  for (uint32_t code_bytes = 1; code_bytes <= 256; ++code_bytes) {
    const bool choice = std::find(kCodeBytesChoices.begin(), kCodeBytesChoices.end(), code_bytes) !=
                        kCodeBytesChoices.end();
    EXPECT_EQ(choice, IsValidCodeBytes(code_bytes)) << code_bytes;
    IndexBuildOptions options;
    options.code_bytes = code_bytes;
    EXPECT_EQ(ValidationError(options),
              choice ? ""
                     : "--code-bytes " + std::to_string(code_bytes) +
                           ": expected 0 (full descriptors) or 4, 8, 16, 32 or 64");
  }
}

TEST(BuildOptionTableTest, FlagsMembersAreCheckedToo) {
  IndexBuildFlags flags;
  flags.clusters = 0;
  EXPECT_EQ(ValidationError(IndexBuildOptions(), flags), "--clusters 0: expected at least 1");
  flags.clusters = 1;
  EXPECT_EQ(ValidationError(IndexBuildOptions(), flags), "");
  IndexBuildOptions options;
  options.georeferencing.fit.default_sigma_m = -0.5;
  EXPECT_EQ(ValidationError(options), "--georef-sigma -0.5: expected a number of metres > 0");
  options.georeferencing.fit.default_sigma_m = std::numeric_limits<double>::infinity();
  EXPECT_EQ(ValidationError(options), "--georef-sigma inf: expected a number of metres > 0");
}

TEST(BuildOptionTableTest, TextParsesAsTheOptionsType) {
  const auto parse_error = [](std::string_view flag, std::string_view text) {
    return test::InputErrorOf([&] { ParseBuildOption(FindBuildOption(flag), text); });
  };
  EXPECT_EQ(ParseBuildOption(FindBuildOption("trees"), "3"), OptionValue(uint32_t{3}));
  EXPECT_EQ(ParseBuildOption(FindBuildOption("threads"), "-2"), OptionValue(int32_t{-2}));
  EXPECT_EQ(ParseBuildOption(FindBuildOption("seed"), "18446744073709551615"),
            OptionValue(UINT64_MAX));
  EXPECT_EQ(ParseBuildOption(FindBuildOption("georef-sigma"), "2.5"), OptionValue(2.5));
  EXPECT_EQ(ParseBuildOption(FindBuildOption("model-frame"), "ecef"),
            OptionValue(std::string("ecef")));
  EXPECT_EQ(ParseBuildOption(FindBuildOption("georef"), "a b.txt"),
            OptionValue(std::filesystem::path("a b.txt")));
  EXPECT_EQ(parse_error("trees", "four"), "--trees four: expected a whole number");
  EXPECT_EQ(parse_error("trees", "1.5"), "--trees 1.5: expected a whole number");
  EXPECT_EQ(parse_error("trees", "-1"), "--trees -1: expected 1 to 64");
  EXPECT_EQ(parse_error("seed", "-1"), "--seed -1: expected at least 0");
  EXPECT_EQ(parse_error("seed", "18446744073709551616"),
            "--seed 18446744073709551616: expected at most 18446744073709551615");
  EXPECT_EQ(parse_error("georef-sigma", "five"), "--georef-sigma five: expected a number");
  EXPECT_EQ(FormatOptionValue(OptionValue(5.0)), "5");
  EXPECT_EQ(FormatOptionValue(OptionValue(0.25)), "0.25");
}

// A value lands where the table says, and --trees and --code-bytes are marked given, so that
// --compact keeps them (ApplyBuildFlags).
TEST(BuildOptionTableTest, ValuesLandInTheirMembersAndMarkTheGivenOnes) {
  IndexBuildOptions options;
  IndexBuildFlags flags;
  const auto set = [&](std::string_view flag, const OptionValue& value) {
    FindBuildOption(flag).set(value, &options, &flags);
  };
  set("leaf-size", uint32_t{16});
  set("clusters", uint32_t{3});
  set("compact", true);
  set("model-frame", std::string("ecef"));
  EXPECT_EQ(options.forest.max_leaf_size, 16u);
  EXPECT_EQ(flags.clusters, 3u);
  EXPECT_EQ(options.georeferencing.model_frame, "ecef");
  EXPECT_FALSE(flags.trees_given);
  EXPECT_FALSE(flags.code_bytes_given);
  ApplyBuildFlags(flags, &options);
  EXPECT_EQ(options.forest.num_trees, kCompactTrees);
  EXPECT_EQ(options.code_bytes, kCompactCodeBytes);

  set("trees", uint32_t{5});
  set("code-bytes", uint32_t{0});
  EXPECT_TRUE(flags.trees_given);
  EXPECT_TRUE(flags.code_bytes_given);
  ApplyBuildFlags(flags, &options);
  EXPECT_EQ(options.forest.num_trees, 5u);
  EXPECT_EQ(options.code_bytes, 0u);
  EXPECT_EQ(FindBuildOption("clusters").get(IndexBuildOptions(), IndexBuildFlags()), std::nullopt);
}

}  // namespace
}  // namespace cwloc
