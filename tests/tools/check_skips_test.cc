// tools/check_skips.py on ctest logs: every skipped GoogleTest and pytest test is listed with its
// reason, and in CI a skip that the allowed-skips file does not allow for the build fails.
#include <gtest/gtest.h>

#include <fstream>

#include "tests/test_util.h"

namespace cwloc {
namespace {

// One test's block of a ctest LastTest.log, as ctest writes it.
std::string Block(int number, const std::string& name, const std::string& output) {
  const std::string rule(58, '-'), n = std::to_string(number) + "/9 ";
  return n + "Testing: " + name + "\n" + n + "Test: " + name + "\n" +
         "Command: \"/build/tests/some_tests\" \"--gtest_filter=" + name + "\"\n" +
         "Directory: /build/tests\n\"" + name + "\" start time: Dec 07 18:13 UTC\n" + "Output:\n" +
         rule + "\n" + output + "<end of output>\n" + "Test time =   0.01 sec\n" + rule +
         "\nTest Passed.\n\"" + name + "\" end time: Dec 07 18:13 UTC\n\"" + name +
         "\" time elapsed: 00:00:00\n" + rule + "\n\n";
}

std::string Passed(const std::string& name) {
  return "[ RUN      ] " + name + "\n[       OK ] " + name + " (3 ms)\n";
}

std::string Skipped(const std::string& name, const std::string& reason) {
  return "[ RUN      ] " + name + "\n/src/tests/x_test.cc:43: Skipped\n" + reason +
         "\n\n[  SKIPPED ] " + name +
         " (0 ms)\n[==========] 1 test from 1 test suite ran.\n"
         "[  PASSED  ] 0 tests.\n[  SKIPPED ] 1 test, listed below:\n[  SKIPPED ] " +
         name + "\n";
}

// pytest -vv -rs: two tests skipped by a fixture, one module skipped at import, one passed.
const char kPytest[] =
    "collecting ... collected 5 items / 1 skipped\n\n"
    "tests/python/test_example.py::test_golden PASSED                      [ 33%]\n"
    "tests/python/test_tracker.py::test_frames SKIPPED (shared data 'fox_video' not found "
    "(../shared/data); skipping) [ 66%]\n"
    "tests/python/test_tracker.py::test_api[2] SKIPPED (shared data 'fox_video' not found "
    "(../shared/data); skipping) [100%]\n\n"
    "=========================== short test summary info ============================\n"
    "SKIPPED [1] tests/python/test_dask.py:11: could not import 'distributed': No module named "
    "'distributed'\n"
    "SKIPPED [2] tests/python/conftest.py:19: shared data 'fox_video' not found "
    "(../shared/data); skipping\n"
    "========================= 1 passed, 3 skipped in 0.03s =========================\n";

class CheckSkipsTest : public testing::Test {
 protected:
  void SetUp() override {
    std::ofstream(dir_.path() / "LastTest.log")
        << Block(1, "IndexFileTest.Opens", Passed("IndexFileTest.Opens"))
        << Block(2, "ServeTest.TheViewerShowsThePoseTheApiReturned",
                 Skipped("ServeTest.TheViewerShowsThePoseTheApiReturned", "no node"))
        << Block(3, "All/SiftAgreementTest.Agrees/0  # GetParam() = 1600",
                 Skipped("All/SiftAgreementTest.Agrees/0", "shared data 'herz_jesu_p25' not found"))
        << Block(4, "python_tests", kPytest);
    std::ofstream(dir_.path() / "passed.log")
        << Block(1, "IndexFileTest.Opens", Passed("IndexFileTest.Opens"))
        << Block(2, "python_tests",
                 "tests/python/test_example.py::test_golden PASSED                 [100%]\n");
  }

  // check_skips.py's exit code on `log` with `allowed` as the allowed-skips file; CI unset.
  int Check(const std::string& allowed, const std::string& arguments, std::string* output,
            const std::string& log = "LastTest.log") {
    std::ofstream(dir_.path() / "allowed.txt") << "# a comment\n\n" << allowed;
    return test::RunCommand("env -u CI python3 " +
                                test::Quote(test::SourceDir() / "tools" / "check_skips.py") +
                                " --allowed " + test::Quote(dir_.path() / "allowed.txt") + " " +
                                arguments + " " + test::Quote(dir_.path() / log),
                            output);
  }

  test::TempDir dir_;
};

TEST_F(CheckSkipsTest, ListsEverySkipAndFailsInCiForOnesTheFileDoesNotAllow) {
  const std::string allowed = "release ServeTest.TheViewer* no browser in this job\n";
  std::string output;
  // Outside CI: every skip listed with its reason and the loud notice, exit 0.
  ASSERT_EQ(Check(allowed, "", &output), 0) << output;
  EXPECT_NE(output.find("5 tests skipped (4 ctest tests in "), std::string::npos) << output;
  EXPECT_NE(output.find("allowed: ServeTest.TheViewerShowsThePoseTheApiReturned: no node"),
            std::string::npos)
      << output;
  EXPECT_NE(output.find("NOT ALLOWED: All/SiftAgreementTest.Agrees/0: shared data "
                        "'herz_jesu_p25' not found"),
            std::string::npos)
      << output;
  EXPECT_NE(output.find("NOT ALLOWED: tests/python/test_tracker.py::test_frames: shared data "
                        "'fox_video' not found (../shared/data); skipping"),
            std::string::npos)
      << output;
  EXPECT_NE(output.find("NOT ALLOWED: tests/python/test_tracker.py::test_api[2]"),
            std::string::npos)
      << output;
  EXPECT_NE(output.find("NOT ALLOWED: tests/python/test_dask.py: could not import 'distributed'"),
            std::string::npos)
      << output;
  EXPECT_EQ(output.find("conftest.py"), std::string::npos) << output;  // a fixture's, not a test
  EXPECT_NE(output.find("4 TESTS DID NOT RUN"), std::string::npos) << output;

  // In CI, or with --strict: the same list, and exit 1.
  EXPECT_EQ(Check(allowed, "--strict", &output), 1) << output;
  EXPECT_NE(output.find("4 tests skipped that"), std::string::npos) << output;
  std::string in_ci;
  EXPECT_EQ(test::RunCommand("CI=true python3 " +
                                 test::Quote(test::SourceDir() / "tools" / "check_skips.py") +
                                 " --allowed " + test::Quote(dir_.path() / "allowed.txt") + " " +
                                 test::Quote(dir_.path() / "LastTest.log"),
                             &in_ci),
            1)
      << in_ci;

  // Every skip allowed (a pattern with *, a module by its file): CI passes.
  EXPECT_EQ(Check(allowed + "any All/SiftAgreementTest.* its reason\n"
                            "release tests/python/test_tracker.py::* its reason\n"
                            "release tests/python/test_dask.py its reason\n",
                  "--strict", &output),
            0)
      << output;
}

// An allowance holds for its build only; a run without skips passes.
TEST_F(CheckSkipsTest, AnAllowanceHoldsForItsBuild) {
  const std::string allowed = "asan ServeTest.* a\nasan All/* b\nasan tests/python/* c\n";
  std::string output;
  EXPECT_EQ(Check(allowed, "--strict --build asan", &output), 0) << output;
  EXPECT_EQ(Check(allowed, "--strict --build release", &output), 1) << output;
  EXPECT_EQ(Check(allowed, "--strict", &output, "passed.log"), 0) << output;
  EXPECT_NE(output.find("0 tests skipped (2 ctest tests in "), std::string::npos) << output;
}

TEST_F(CheckSkipsTest, AMalformedLineOrUnknownBuildIsRefused) {
  std::string output;
  EXPECT_NE(Check("release OnlyTwoFields\n", "", &output), 0);
  EXPECT_NE(output.find("allowed.txt:3: expected BUILD TEST REASON"), std::string::npos) << output;
  EXPECT_NE(Check("nightly Some.Test a reason\n", "", &output), 0);
  EXPECT_NE(output.find("allowed.txt:3:"), std::string::npos) << output;
}

// The repository's own file parses, and allows nothing in the release build: CI's README test
// command runs everything.
TEST_F(CheckSkipsTest, TheRepositorysFileAllowsNoReleaseSkip) {
  std::string output;
  const std::string tool = test::Quote(test::SourceDir() / "tools" / "check_skips.py");
  ASSERT_EQ(
      test::RunCommand("python3 " + tool + " --strict " + test::Quote(dir_.path() / "passed.log"),
                       &output),
      0)
      << output;
  const std::string file = test::ReadFile(test::SourceDir() / "tests" / "allowed_skips.txt");
  EXPECT_EQ(file.find("\nrelease "), std::string::npos);
  EXPECT_EQ(file.find("\nany "), std::string::npos);
}

}  // namespace
}  // namespace cwloc
