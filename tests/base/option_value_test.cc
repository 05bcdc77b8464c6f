// The words both option tables refuse a value with (base/option_value.h): a range in words, a
// whole number within its type, a choice, and values that are not of the option's type.
#include "base/option_value.h"

#include <gtest/gtest.h>

#include <array>

#include "tests/test_util.h"

namespace cwloc {
namespace {

constexpr std::array<std::string_view, 3> kNames = {"a", "bb", "c"};
constexpr std::array<uint32_t, 3> kChoices = {0, 4, 8};

std::string Parsed(const ValueRange& range, size_t type, std::string_view text) {
  const std::string error = test::InputErrorOf([&] { ParseOptionValue("opt", range, type, text); });
  return error.empty() ? FormatOptionValue(ParseOptionValue("opt", range, type, text)) : error;
}

TEST(OptionValueTest, RealRangesInWords) {
  const size_t real = OptionTypeIndex<double>();
  EXPECT_EQ(Parsed(AboveUpTo(0, 1, ""), real, "1"), "1");
  EXPECT_EQ(Parsed(AboveUpTo(0, 1, ""), real, "0"), "--opt 0: expected a value in (0, 1]");
  EXPECT_EQ(Parsed(Inside(0, 1), real, "1"), "--opt 1: expected a value in (0, 1)");
  EXPECT_EQ(Parsed(AboveUpTo(0, 90, "degrees"), real, "90.5"),
            "--opt 90.5: expected degrees in (0, 90]");
  EXPECT_EQ(Parsed(Above(0, "metres"), real, "-0.25"),
            "--opt -0.25: expected a number of metres > 0");
  EXPECT_EQ(Parsed(AtLeast(0), real, "nan"), "--opt nan: expected a value >= 0");
  EXPECT_EQ(Parsed(AnyValue(), real, "inf"), "--opt inf: expected a value >= -inf");
  EXPECT_EQ(Parsed(AnyValue(), real, "x"), "--opt x: expected a number");
}

TEST(OptionValueTest, WholeNumbersWithinTheirTypeAndRange) {
  const size_t u32 = OptionTypeIndex<uint32_t>(), i32 = OptionTypeIndex<int32_t>();
  EXPECT_EQ(Parsed(Between(1, 64), u32, "1e1"), "10");
  EXPECT_EQ(Parsed(Between(1, 64), u32, "65"), "--opt 65: expected 1 to 64");
  EXPECT_EQ(Parsed(AtLeast(1), u32, "-3"), "--opt -3: expected at least 1");
  EXPECT_EQ(Parsed(AtLeast(1), u32, "5000000000"), "--opt 5000000000: expected 1 to 4294967295");
  EXPECT_EQ(Parsed(AnyValue(), i32, "2.5"), "--opt 2.5: expected a whole number");
  EXPECT_EQ(Parsed(AnyValue(), OptionTypeIndex<uint64_t>(), "18446744073709551616"),
            "--opt 18446744073709551616: expected at most 18446744073709551615");
  EXPECT_EQ(Parsed(OneOf(kChoices, "none"), u32, "5"), "--opt 5: expected 0 (none) or 4 or 8");
  EXPECT_EQ(Parsed(OneOf(kChoices, "none"), u32, "8"), "8");
  EXPECT_EQ(test::InputErrorOf(
                [] { OptionValueFromNumber("opt", AtLeast(1), OptionTypeIndex<uint32_t>(), 0.5); }),
            "--opt 0.5: expected a whole number");
}

TEST(OptionValueTest, SwitchesNamesAndPaths) {
  EXPECT_EQ(Parsed(AnyValue(), OptionTypeIndex<bool>(), "1"), "true");
  EXPECT_EQ(Parsed(AnyValue(), OptionTypeIndex<bool>(), "yes"),
            "--opt yes: expected true or false");
  EXPECT_EQ(Parsed(OneOf(kNames), OptionTypeIndex<std::string>(), "bb"), "bb");
  EXPECT_EQ(Parsed(OneOf(kNames), OptionTypeIndex<std::string>(), "b"),
            "--opt b: expected a, bb or c");
  EXPECT_EQ(Parsed(AnyValue(), OptionTypeIndex<std::string>(), "free text"), "free text");
  EXPECT_EQ(Parsed(AnyValue(), OptionTypeIndex<std::filesystem::path>(), "a b/c"), "a b/c");
  EXPECT_EQ(test::InputErrorOf([] {
              OptionValueFromNumber("opt", OneOf(kNames), OptionTypeIndex<std::string>(), 1);
            }),
            "--opt 1: expected a, bb or c");
}

}  // namespace
}  // namespace cwloc
