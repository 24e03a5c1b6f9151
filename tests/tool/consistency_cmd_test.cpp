// `scenelod consistency`: Low & Tan's plate-5 experiment through the tool, on the bunny.
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "tool/tool_runner.h"

namespace {

using scenelod::test::runTool;

struct Row {
  size_t triangles = 0, changed = 0;
  bool found = false;
};

Row rowOf(const std::string& output, const std::string& method) {
  std::istringstream in(output);
  std::string line;
  Row row;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::string name;
    if (fields >> name && name == method && fields >> row.triangles >> row.changed) row.found = true;
  }
  return row;
}

TEST(ConsistencyCommand, FloatingCellsKeepTheBunnyUniformCellsDoNot) {
  SCENELOD_REQUIRE_BUNNY();
  const auto r = runTool("consistency '" + scenelod::test::bunnyPath() + "' --cell-rel 0.02");
  ASSERT_EQ(r.code, 0) << r.output;
  for (const char* method : {"floating-nearest", "floating-heaviest"}) {
    const Row row = rowOf(r.output, method);
    ASSERT_TRUE(row.found) << method << "\n" << r.output;
    EXPECT_GT(row.triangles, 1000u) << method;
    EXPECT_LE(row.changed, row.triangles / 100) << method;
  }
  const Row uniform = rowOf(r.output, "uniform");
  ASSERT_TRUE(uniform.found) << r.output;
  EXPECT_GT(uniform.changed, uniform.triangles / 2);
}

TEST(ConsistencyCommand, BadArgumentsAreRefused) {
  auto r = runTool("consistency");
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.output.find("expected one input file"), std::string::npos) << r.output;
  r = runTool("consistency /nonexistent/model.obj");
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.output.find("/nonexistent/model.obj"), std::string::npos) << r.output;
  r = runTool("consistency x.obj --cell-rel -1");
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.output.find("--cell-rel must be a finite number > 0"), std::string::npos) << r.output;
}

}  // namespace
