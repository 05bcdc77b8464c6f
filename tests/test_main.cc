#include <gtest/gtest.h>

#include <cstdlib>
#include <iostream>

#include "tests/test_util.h"

namespace {

// Reseeds the shared PRNG before every test (like COLMAP's util/gtest_main.cc), so each test
// is reproducible on its own. CWLOC_TEST_SEED overrides the seed.
class ReseedListener : public testing::EmptyTestEventListener {
 public:
  explicit ReseedListener(uint64_t seed) : seed_(seed) {}
  void OnTestStart(const testing::TestInfo&) override { cwloc::test::Rng().seed(seed_); }

 private:
  uint64_t seed_;
};

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  uint64_t seed = 20261121;
  if (const char* env = std::getenv("CWLOC_TEST_SEED")) {
    seed = std::strtoull(env, nullptr, 10);
    std::cout << "CWLOC_TEST_SEED=" << seed << "\n";
  }
  testing::UnitTest::GetInstance()->listeners().Append(new ReseedListener(seed));
  return RUN_ALL_TESTS();
}
