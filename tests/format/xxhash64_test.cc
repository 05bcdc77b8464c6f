#include "format/xxhash64.h"

#include <gtest/gtest.h>

#include <span>
#include <string_view>
#include <vector>

namespace cwloc {
namespace {

uint64_t HashOf(std::string_view text) {
  return XxHash64({reinterpret_cast<const uint8_t*>(text.data()), text.size()});
}

// Reference values printed by Debian's `xxhsum -H1` (xxHash 0.8.1).
TEST(XxHash64, MatchesReferenceImplementation) {
  EXPECT_EQ(HashOf(""), 0xef46db3751d8e999ULL);
  EXPECT_EQ(HashOf("abc"), 0x44bc2cf5ad770999ULL);
  EXPECT_EQ(XxHash64(std::vector<uint8_t>(100, 0)), 0x17bb1103c92c502fULL);
  std::vector<uint8_t> pattern(1000);
  for (size_t i = 0; i < pattern.size(); ++i) pattern[i] = static_cast<uint8_t>(i * 7 % 256);
  EXPECT_EQ(XxHash64(pattern), 0x25275608a9cfc168ULL);
}

TEST(XxHash64, AnEmptySpanWithoutDataHashesAsEmpty) {
  // An empty section's vector has no storage (a tile's co-visibility edges between two images
  // that share no point); UBSan checks that no offset is applied to its null pointer.
  EXPECT_EQ(XxHash64(std::span<const uint8_t>()), 0xef46db3751d8e999ULL);
  EXPECT_EQ(XxHash64(std::vector<uint8_t>()), 0xef46db3751d8e999ULL);
}

// The pattern's reference hash from pieces: every split into three, empty ones included, so
// that pieces end inside, at and across the 32-byte stripes.
TEST(XxHash64, PiecesHashAsTheWhole) {
  std::vector<uint8_t> pattern(1000);
  for (size_t i = 0; i < pattern.size(); ++i) pattern[i] = static_cast<uint8_t>(i * 7 % 256);
  const std::span<const uint8_t> whole(pattern);
  for (size_t a = 0; a <= 70; ++a) {
    for (size_t b = a; b <= 140; b += 3) {
      XxHash64Stream stream;
      stream.Update(whole.first(a));
      stream.Update(whole.subspan(a, b - a));
      stream.Update(whole.subspan(b));
      ASSERT_EQ(stream.Digest(), 0x25275608a9cfc168ULL) << a << " " << b;
    }
  }
  XxHash64Stream seeded(42);
  seeded.Update(whole.first(33));
  seeded.Update(whole.subspan(33));
  EXPECT_EQ(seeded.Digest(), XxHash64(whole, 42));
  EXPECT_NE(seeded.Digest(), XxHash64(whole));
  XxHash64Stream empty;
  empty.Update({});
  EXPECT_EQ(empty.Digest(), 0xef46db3751d8e999ULL);
}

TEST(XxHash64, HexHasSixteenLowerCaseDigits) {
  EXPECT_EQ(HashHex(0xef46db3751d8e999ULL), "ef46db3751d8e999");
  EXPECT_EQ(HashHex(0x1ULL), "0000000000000001");
}

}  // namespace
}  // namespace cwloc
