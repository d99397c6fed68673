#include "io/common/text_util.h"

#include <gtest/gtest.h>

namespace tolver {
namespace {

// RFC 4648 section 10 test vectors, and bytes above 127.
TEST(TextUtil, Base64MatchesRfc4648) {
  EXPECT_EQ(base64Encode(""), "");
  EXPECT_EQ(base64Encode("f"), "Zg==");
  EXPECT_EQ(base64Encode("fo"), "Zm8=");
  EXPECT_EQ(base64Encode("foo"), "Zm9v");
  EXPECT_EQ(base64Encode("foob"), "Zm9vYg==");
  EXPECT_EQ(base64Encode("fooba"), "Zm9vYmE=");
  EXPECT_EQ(base64Encode("foobar"), "Zm9vYmFy");
  EXPECT_EQ(base64Encode(std::string("\x89PNG", 4)), "iVBORw==");
}

}  // namespace
}  // namespace tolver
