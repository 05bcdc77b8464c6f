// The option table on every surface: for each option, cwloc-localize, the C API and the C++ API
// accept its default and refuse a value outside its range with the same message.
#include "app/option_table.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <optional>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <variant>
#include <vector>

#include "cwloc/cwloc.h"
#include "cwloc/cwloc.hpp"
#include "tests/test_util.h"

namespace cwloc {
namespace {

// A value the option refuses, as text, and as a number where it has one.
struct OutOfRange {
  std::string text;
  std::optional<double> number;
};

std::optional<OutOfRange> OutOfRangeValue(const OptionSpec& spec, const OptionValue& value) {
  const ValueRange& range = spec.range;
  if (!range.names.empty()) return OutOfRange{"no-such-" + std::string(spec.flag), std::nullopt};
  if (std::holds_alternative<bool>(value)) return std::nullopt;  // a switch: no value to give
  // Below the bottom of the range, or of the type's (0 for unsigned types).
  double below = std::isfinite(range.min) ? range.min : 0.0;
  if (!range.min_open || !std::holds_alternative<double>(value)) below -= 1;
  const std::string text = FormatOptionValue(below);
  return OutOfRange{text, below};
}

class OptionTableTest : public ::testing::Test {
 protected:
  static std::string IndexPath() { return test::GoldenDir() / "index-1.1.cwl"; }
  static std::string QueryPath() {
    return test::GoldenDir() / "index-1.1-queries" / "query_00001.jpg.txt";
  }

  struct ToolRun {
    int exit_code = 0;
    std::string stderr_text;  // and stdout's, which is empty when it fails
  };

  // cwloc-localize with the golden index, one of its queries and extra arguments.
  static ToolRun Localize(const std::vector<std::string>& extra) {
    std::string command = test::Quote(test::ToolPath("cwloc-localize")) + " --index " +
                          test::Quote(IndexPath()) + " --features " + test::Quote(QueryPath()) +
                          " --image-size '640 480' -q";
    for (const std::string& arg : extra) command += " " + test::Quote(arg);
    ToolRun run;
    run.exit_code = test::RunCommand("(" + command + " 2>&1 >/dev/null)", &run.stderr_text);
    return run;
  }
};

TEST_F(OptionTableTest, EverySurfaceAcceptsTheDefaults) {
  const QueryOptions defaults;
  const api::Options api_defaults;
  cwloc_options* c_options = nullptr;
  ASSERT_EQ(cwloc_options_create(&c_options), CWLOC_OK);
  for (const OptionSpec& spec : OptionTable()) {
    SCOPED_TRACE(spec.flag);
    const OptionValue value = spec.get(defaults);
    const std::string text = FormatOptionValue(value);
    const std::string flag = "--" + std::string(spec.flag);
    if (const bool* on = std::get_if<bool>(&value)) {
      const ToolRun run = Localize({*on ? flag : "--no-" + std::string(spec.flag)});
      // --no-NAME exists only for a switch that is on by default.
      if (*on) {
        EXPECT_LE(run.exit_code, 1) << run.stderr_text;
      }
    } else {
      const ToolRun run = Localize({flag, text});
      EXPECT_LE(run.exit_code, 1) << run.stderr_text;
    }
    EXPECT_EQ(cwloc_options_set_text(c_options, std::string(spec.flag).c_str(), text.c_str()),
              CWLOC_OK)
        << cwloc_last_error();
    api::Options options;
    EXPECT_NO_THROW(options.Set(std::string(spec.flag), text));
  }
  cwloc_options_destroy(c_options);
  // The C++ defaults are the table's.
#define CWLOC_OPTION(field, type, flag, ...)                           \
  EXPECT_EQ(OptionValue(std::in_place_type<type>, api_defaults.field), \
            FindOption(flag).get(defaults))                            \
      << flag;
#include "app/option_table.inc"
#undef CWLOC_OPTION
}

TEST_F(OptionTableTest, EverySurfaceRefusesAValueOutOfRangeWithTheSameMessage) {
  const QueryOptions defaults;
  cwloc_options* c_options = nullptr;
  ASSERT_EQ(cwloc_options_create(&c_options), CWLOC_OK);
  int refused = 0;
  for (const OptionSpec& spec : OptionTable()) {
    SCOPED_TRACE(spec.flag);
    const std::optional<OutOfRange> bad = OutOfRangeValue(spec, spec.get(defaults));
    if (!bad) continue;
    ++refused;
    const std::string name(spec.flag);
    const std::string message = "--" + name + " " + bad->text + ": expected ";

    const ToolRun run = Localize({"--" + name, bad->text});
    EXPECT_EQ(run.exit_code, 2);
    ASSERT_EQ(run.stderr_text.rfind("cwloc-localize: error: " + message, 0), 0u) << run.stderr_text;
    const std::string cli_message =
        run.stderr_text.substr(std::string("cwloc-localize: error: ").size());
    EXPECT_EQ(cli_message.back(), '\n');
    const std::string expected = cli_message.substr(0, cli_message.size() - 1);

    EXPECT_EQ(cwloc_options_set_text(c_options, name.c_str(), bad->text.c_str()),
              CWLOC_ERROR_INVALID_ARGUMENT);
    EXPECT_EQ(cwloc_last_error(), expected);
    if (bad->number) {
      EXPECT_EQ(cwloc_options_set(c_options, name.c_str(), *bad->number),
                CWLOC_ERROR_INVALID_ARGUMENT);
      EXPECT_EQ(cwloc_last_error(), expected);
    }
    api::Options options;
    try {
      options.Set(name, bad->text);
      ADD_FAILURE() << "accepted " << bad->text;
    } catch (const api::Error& e) {
      EXPECT_EQ(e.code(), api::ErrorCode::kInvalidArgument);
      EXPECT_EQ(e.what(), expected);
    }
  }
  cwloc_options_destroy(c_options);
  EXPECT_GE(refused, 20);  // every option but the switches
}

// A field set out of range in the C++ struct is refused when the query runs, with the message.
TEST_F(OptionTableTest, TheCppApiChecksItsFieldsWhenTheQueryRuns) {
  const api::Localizer localizer = api::Localizer::Open(IndexPath());
  const api::Features features = api::ReadFeatureFile(QueryPath());
  api::Camera camera;
  camera.width = 640;
  camera.height = 480;
  camera.calibration = api::Calibration::kUnknown;
  api::Options options;
  options.back_matches = 0;
  try {
    localizer.Localize(features, camera, options);
    FAIL() << "--nb 0 accepted";
  } catch (const api::Error& e) {
    EXPECT_EQ(e.code(), api::ErrorCode::kInvalidArgument);
    EXPECT_STREQ(e.what(), "--nb 0: expected at least 1");
  }
  options = api::Options();
  options.max_features = 3'000'000'000u;
  EXPECT_THROW(localizer.Localize(features, camera, options), api::Error);
  options = api::Options();
  options.min_ransac_iterations = 200;
  options.max_ransac_iterations = 100;
  try {
    localizer.Localize(features, camera, options);
    FAIL() << "min > max accepted";
  } catch (const api::Error& e) {
    EXPECT_STREQ(e.what(),
                 "--min-ransac-iterations 200: expected at most --max-ransac-iterations 100");
  }
}

TEST(OptionTable, MessagesNameTheFlagAndTheRange) {
  QueryOptions options;
  auto message = [&](std::string_view flag, std::string_view text) -> std::string {
    try {
      SetOption(&options, flag, ParseOption(FindOption(flag), text));
    } catch (const InputError& e) {
      return e.what();
    }
    return "accepted";
  };
  EXPECT_EQ(message("nb", "0"), "--nb 0: expected at least 1");
  EXPECT_EQ(message("nb", "2.5"), "--nb 2.5: expected a whole number");
  EXPECT_EQ(message("nb", "twelve"), "--nb twelve: expected a whole number");
  EXPECT_EQ(message("nb", "5000000000"), "--nb 5000000000: expected 1 to 4294967295");
  EXPECT_EQ(message("nb", "1e3"), "accepted");
  EXPECT_EQ(options.localizer.back_matches, 1000u);
  EXPECT_EQ(message("k", "64"), "--k 64: expected 1 to 63");
  EXPECT_EQ(message("max-features", "3000000000"),
            "--max-features 3000000000: expected 1 to 2147483647");
  EXPECT_EQ(message("max-features", "2147483647"), "accepted");
  EXPECT_EQ(options.photo.sift.max_num_features, 2147483647);
  EXPECT_EQ(message("ratio", "1.5"), "--ratio 1.5: expected a value in (0, 1]");
  EXPECT_EQ(message("ratio", "nan"), "--ratio nan: expected a value in (0, 1]");
  EXPECT_EQ(message("max-error", "inf"), "--max-error inf: expected a number of pixels > 0");
  EXPECT_EQ(message("ransac-confidence", "1"), "--ransac-confidence 1: expected a value in (0, 1)");
  EXPECT_EQ(message("prior-gravity-sigma", "90"), "accepted");
  EXPECT_EQ(message("matcher", "psychic"),
            "--matcher psychic: expected cluster-wise, global-ratio or cluster-exhaustive");
  EXPECT_EQ(message("refine", "maybe"), "--refine maybe: expected true or false");
  EXPECT_EQ(message("seed", "18446744073709551615"), "accepted");
  EXPECT_EQ(options.localizer.seed, std::numeric_limits<uint64_t>::max());
  EXPECT_EQ(message("seed", "-1"), "--seed -1: expected at least 0");
  EXPECT_THROW(FindOption("warp-speed"), InputError);
}

// The flags cwloc-localize --help lists.
std::set<std::string> LocalizeFlags() {
  std::string help;
  EXPECT_EQ(test::RunCommand(test::Quote(test::ToolPath("cwloc-localize")) + " --help", &help), 0);
  std::set<std::string> flags = {"--help", "--version"};
  const std::regex flag(R"(--[a-z][a-z0-9-]*)");
  for (std::sregex_iterator it(help.begin(), help.end(), flag), end; it != end; ++it)
    flags.insert(it->str());
  return flags;
}

// Where the API and cwloc-localize are documented, every --flag said of cwloc-localize exists:
// on a line, a flag belongs to the last tool named before it (cwloc-localize when none is).
TEST(OptionTable, DocsAndHeadersNameOnlyFlagsThatExist) {
  const std::set<std::string> flags = LocalizeFlags();
  for (const OptionSpec& spec : OptionTable())
    EXPECT_TRUE(flags.count("--" + std::string(spec.flag))) << spec.flag << " is not a flag";
  const std::filesystem::path source = test::SourceDir();
  std::vector<std::pair<std::string, std::string>> texts;  // file, text
  for (const char* file : {"api/include/cwloc/cwloc.hpp", "api/include/cwloc/cwloc.h",
                           "app/option_table.inc", "docs/api.md"})
    texts.emplace_back(file, test::ReadFile(source / file));
  const std::string cli = test::ReadFile(source / "docs/cli.md");
  const size_t section = cli.find("\n## cwloc-localize");
  ASSERT_NE(section, std::string::npos);
  texts.emplace_back("docs/cli.md", cli.substr(section, cli.find("\n## ", section + 1) - section));
  const std::regex token(R"((cwloc-[a-z]+|cmake|colmap|ctest)|(--[a-z][a-z0-9-]*))");
  int checked = 0;
  for (const auto& [file, text] : texts) {
    ASSERT_FALSE(text.empty()) << file;
    std::istringstream lines(text);
    for (std::string line; std::getline(lines, line);) {
      std::string tool = "cwloc-localize";
      for (std::sregex_iterator it(line.begin(), line.end(), token), end; it != end; ++it) {
        if ((*it)[1].matched) {
          tool = it->str();
        } else if (tool == "cwloc-localize") {
          ++checked;
          EXPECT_TRUE(flags.count(it->str())) << file << ": " << it->str() << " in: " << line;
        }
      }
    }
  }
  EXPECT_GE(checked, 40);
}

}  // namespace
}  // namespace cwloc
