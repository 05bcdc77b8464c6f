// The command-line contract shared by every cwloc tool: --help and --version work,
// usage errors exit with code 2 and say what is wrong.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <map>
#include <string>
#include <vector>

#include "cwloc/version.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

using testing::HasSubstr;

class ToolCli : public testing::TestWithParam<std::string> {
 protected:
  int Run(const std::string& args, std::string* output) {
    return test::RunCommand(test::ToolPath(GetParam()).string() + " " + args + " </dev/null",
                            output);
  }
};

TEST_P(ToolCli, VersionPrintsToolNameAndVersion) {
  std::string output;
  ASSERT_EQ(Run("--version", &output), 0) << output;
  EXPECT_EQ(output, GetParam() + " " + kToolVersion + "\n");
}

TEST_P(ToolCli, HelpExitsZeroAndDescribesTheTool) {
  std::string output;
  ASSERT_EQ(Run("--help", &output), 0) << output;
  EXPECT_THAT(output, HasSubstr(GetParam() + ":"));
  EXPECT_THAT(output, HasSubstr("--version"));
}

TEST_P(ToolCli, UnknownOptionIsAUsageError) {
  // CLI11 reports missing required options first, so give each tool its required ones.
  const std::map<std::string, std::string> required = {{"cwloc-index", "info x.cwl"},
                                                       {"cwloc-localize", "--index x.cwl"},
                                                       {"cwloc-synth", "-o x"},
                                                       {"cwloc-serve", "--index x.cwl"}};
  std::string output;
  EXPECT_EQ(Run(required.at(GetParam()) + " --no-such-option", &output), 2) << output;
  EXPECT_THAT(output, HasSubstr("--no-such-option"));
}

// cwloc-serve in builds that have it (CWLOC_WITH_SERVE).
const std::vector<std::string> kTools = {"cwloc-index", "cwloc-localize", "cwloc-synth",
#ifdef CWLOC_TEST_SERVE
                                         "cwloc-serve"
#endif
};

INSTANTIATE_TEST_SUITE_P(AllTools, ToolCli, testing::ValuesIn(kTools), [](const auto& param_info) {
  std::string name = param_info.param;
  std::erase(name, '-');
  return name;
});

TEST(IndexCli, BuildWithoutRequiredOptionsNamesTheMissingOne) {
  std::string output;
  EXPECT_EQ(test::RunCommand(test::ToolPath("cwloc-index").string() + " build --model m -o x.cwl",
                             &output),
            2);
  EXPECT_THAT(output, HasSubstr("--database"));
}

TEST(IndexCli, NoSubcommandIsAUsageError) {
  std::string output;
  EXPECT_EQ(test::RunCommand(test::ToolPath("cwloc-index").string(), &output), 2);
  EXPECT_THAT(output, HasSubstr("subcommand"));
}

}  // namespace
}  // namespace cwloc
