// cwloc-synth killed at random moments (docs/reliability.md): the destination holds the old
// scene or the new one, never a mix or nothing, and the next run removes what the killed one
// left beside it.
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <string>
#include <vector>

#include "tests/test_util.h"

namespace cwloc {
namespace {

namespace fs = std::filesystem;

TEST(SynthKillTest, KilledRunsLeaveTheOldOrTheNewSceneAndTheNextRunCleansUp) {
  test::TempDir dir;
  const fs::path city = dir / "city";
  const std::string tool = test::ToolPath("cwloc-synth").string();
  // Two scenes that differ (the seed), both small: the golden index's city.
  auto args_for = [&](const char* seed) {
    return std::vector<std::string>{tool,  "--blocks",         "1",  "--features-per-image",
                                    "150", "--camera-spacing", "8",  "--queries",
                                    "4",   "--motifs",         "24", "--threads",
                                    "1",   "--seed",           seed, "--overwrite",
                                    "-o",  city.string()};
  };
  auto run = [&](const char* seed) { return test::Wait(test::Spawn(args_for(seed))) == 0; };
  // Scene 2 measured for its duration and bytes, then scene 1 as the previous one.
  const auto start = std::chrono::steady_clock::now();
  ASSERT_TRUE(run("2"));
  const auto duration = std::chrono::steady_clock::now() - start;
  const std::string new_gt = test::ReadFile(city / "queries_gt.txt");
  const std::string new_db = test::ReadFile(city / "database.db");
  ASSERT_TRUE(run("1"));
  const std::string old_gt = test::ReadFile(city / "queries_gt.txt");
  const std::string old_db = test::ReadFile(city / "database.db");
  ASSERT_NE(old_gt, new_gt);

  auto& rng = test::Rng();
  std::vector<pid_t> killed;
  for (int kill_number = 0; kill_number < 12; ++kill_number) {
    const pid_t pid = test::Spawn(args_for("2"));
    killed.push_back(pid);
    const bool finished = test::KillAfter(pid, duration * (rng() % 1000) / 1000);
    // The destination is a whole scene: the old one, or the new one if the run finished.
    const std::string gt = test::ReadFile(city / "queries_gt.txt");
    const std::string db = test::ReadFile(city / "database.db");
    const bool is_old = gt == old_gt && db == old_db;
    const bool is_new = gt == new_gt && db == new_db;
    EXPECT_TRUE(is_old || is_new) << "a mixed or missing scene after kill " << kill_number;
    for (const auto& entry : fs::directory_iterator(dir.path())) {
      const std::string name = entry.path().filename().string();
      if (entry.path() == city) continue;
      // Only killed runs' temporary folders may remain.
      EXPECT_TRUE(test::IsKilledWritersTemporary(name, city.filename().string(), killed))
          << name << " after kill " << kill_number;
    }
    // Back to the old scene for the next kill.
    if (is_new || finished) {
      ASSERT_TRUE(run("1"));
    }
  }
  // A complete run removes every killed run's folder.
  ASSERT_TRUE(run("1"));
  EXPECT_EQ(test::ListDir(dir.path()), std::vector<fs::path>{city});
}

}  // namespace
}  // namespace cwloc
