// What the HTTP layer makes of a request's bytes before a handler sees them (serve/
// http_message.h): multipart/form-data parts, exactly, and every malformed body refused with
// its message; URL escapes.
#include "serve/http_message.h"

#include <gtest/gtest.h>

#include <string>

#include "base/error.h"

namespace cwloc {
namespace {

const std::string kType = "multipart/form-data; boundary=XyZ";

std::string Part(const std::string& headers, const std::string& content) {
  return "--XyZ\r\n" + headers + "\r\n\r\n" + content + "\r\n";
}

TEST(ParseMultipart, GivesEachPartItsNameFileNameTypeAndBytes) {
  const std::string jpeg("\xff\xd8\r\n--Xy\0Z\xff\xd9", 12);  // a near-boundary and a NUL inside
  const std::string body =
      "preamble\r\n" +
      Part(
          "Content-Disposition: form-data; name=\"image\"; filename=\"a b.jpg\"\r\n"
          "Content-Type: image/jpeg",
          jpeg) +
      Part("content-disposition: form-data; name=options", R"({"nb": 5})") +
      Part("Content-Disposition: form-data; name=\"image\"", "second image") + "--XyZ--\r\n";
  const std::vector<FormPart> parts = ParseMultipart(kType, body);
  ASSERT_EQ(parts.size(), 2u);
  EXPECT_EQ(parts[0].name, "image");
  EXPECT_EQ(parts[0].filename, "a b.jpg");
  EXPECT_EQ(parts[0].content_type, "image/jpeg");
  EXPECT_EQ(parts[0].content, jpeg);  // the first of two parts with one name
  EXPECT_EQ(parts[1].name, "options");
  EXPECT_EQ(parts[1].filename, "");
  EXPECT_EQ(parts[1].content, R"({"nb": 5})");
  // An empty form, and a quoted boundary.
  EXPECT_TRUE(ParseMultipart(kType, "--XyZ--").empty());
  EXPECT_EQ(ParseMultipart("multipart/form-data; boundary=\"XyZ\"",
                           Part("Content-Disposition: form-data; name=a", "1") + "--XyZ--")
                .size(),
            1u);
}

void ExpectRefused(const std::string& type, const std::string& body, const std::string& message) {
  try {
    ParseMultipart(type, body);
    ADD_FAILURE() << "accepted: " << body;
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), message) << body;
  }
}

TEST(ParseMultipart, RefusesWhatIsMalformedSayingWhat) {
  const std::string named = "Content-Disposition: form-data; name=a";
  ExpectRefused("multipart/form-data", "--XyZ--",
                "multipart body: no boundary in its Content-Type");
  ExpectRefused(kType, "nothing", "multipart body: no boundary line");
  ExpectRefused(kType, "--XyZ\r\n" + named + "\r\n\r\ncontent with no end",
                "multipart body: a part has no closing boundary");
  ExpectRefused(kType, "--XyZ\r\n" + named + "\r\n\r\n1\r\n--XyZ",
                "multipart body: a boundary line ends badly");
  ExpectRefused(kType, "--XyZ\r\n" + named + "\r\n--XyZ--",
                "multipart body: a part's headers do not end");
  ExpectRefused(kType, Part("Content-Type: text/plain", "1") + "--XyZ--",
                "multipart body: a part without Content-Disposition's name");
  ExpectRefused(kType, Part("no colon here", "1") + "--XyZ--",
                "multipart body: a part's header has no ':'");
  ExpectRefused(kType, "--XyZjunk", "multipart body: a boundary line ends badly");
}

TEST(DecodeUrlComponent, DecodesEscapesAndRefusesBrokenOnes) {
  EXPECT_EQ(DecodeUrlComponent("a%20b+c%2Fd%c3%a9"), "a b c/d\xc3\xa9");
  EXPECT_EQ(DecodeUrlComponent(""), "");
  EXPECT_FALSE(DecodeUrlComponent("%"));
  EXPECT_FALSE(DecodeUrlComponent("%2"));
  EXPECT_FALSE(DecodeUrlComponent("%zz"));
}

}  // namespace
}  // namespace cwloc
