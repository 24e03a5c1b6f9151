#include "scenelod/lodcore/json_limits.h"

#include <string>

#include <gtest/gtest.h>

using namespace scenelod;

namespace {

size_t depth(const std::string& s) { return jsonNestingDepth(s.data(), s.size()); }

}  // namespace

TEST(JsonDepth, CountsArraysAndObjects) {
  EXPECT_EQ(depth("42"), 0u);
  EXPECT_EQ(depth("[]"), 1u);
  EXPECT_EQ(depth("{\"a\": [1, {\"b\": []}], \"c\": {}}"), 4u);
  EXPECT_EQ(depth(std::string(20000, '[') + std::string(20000, ']')), 20000u);
}

TEST(JsonDepth, BracketsInsideStringsDoNotCount) {
  EXPECT_EQ(depth("[\"[[[[{{{{\"]"), 1u);
  EXPECT_EQ(depth("[\"a \\\" [[[ \\\\\", [2]]"), 2u);  // an escaped quote does not end the string
}

TEST(JsonDepth, MalformedTextStillGetsANumber) {
  EXPECT_EQ(depth("]]]["), 1u);
  EXPECT_EQ(depth("[[[\"unterminated"), 3u);
}
