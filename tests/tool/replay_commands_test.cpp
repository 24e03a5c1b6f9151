// scenelod record and replay, run as a separate process (SCENELOD_TOOL_PATH).
#include <sys/wait.h>

#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tool_runner.h"

namespace {

using ToolRun = scenelod::test::ToolOutput;
const auto& slurp = scenelod::test::readText;

ToolRun tool(const std::vector<std::string>& args) { return scenelod::test::runToolSeparate(args, "replay"); }

size_t lineCount(const std::string& text) {
  size_t n = 0;
  for (char c : text) n += c == '\n';
  return n;
}

}  // namespace

TEST(ReplayCommands, RecordThenReplayWritesLogReportAndPlots) {
  if (std::string(SCENELOD_TOOL_PATH).empty()) GTEST_SKIP() << "the tool is not built";
  const std::string dir = scenelod::test::scratchDir();
  const std::string replay = dir + "/orbit.jsonl", log = dir + "/orbit_log.jsonl", report = dir + "/orbit_report.md";
  ToolRun r = tool({"record", "builtin:small", "--path", "orbit", "--frames", "40", "--budget", "1.0", "-o", replay});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(lineCount(slurp(replay)), 41u);  // header + 40 frames
  r = tool({"replay", replay, "--out", log, "--report", report});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string text = slurp(log);
  EXPECT_EQ(lineCount(text), 40u);
  EXPECT_NE(text.find("\"levels\": ["), std::string::npos);
  EXPECT_NE(text.find("\"budget_ms\": 1.0000"), std::string::npos);
  const std::string md = slurp(report);
  EXPECT_NE(md.find("frame cost vs budget"), std::string::npos);
  EXPECT_TRUE(scenelod::test::fileExists(dir + "/orbit_report_cost.png"));
  EXPECT_TRUE(scenelod::test::fileExists(dir + "/orbit_report_levels.png"));
  EXPECT_TRUE(scenelod::test::fileExists(dir + "/orbit_report_switches.png"));
  // the same replay in distance mode: no budget in the log
  r = tool({"replay", replay, "-o", log, "--distance"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(slurp(log).find("\"budget_ms\": null"), std::string::npos);
}

TEST(ReplayCommands, BadInputGivesClearErrors) {
  if (std::string(SCENELOD_TOOL_PATH).empty()) GTEST_SKIP() << "the tool is not built";
  const std::string dir = scenelod::test::scratchDir();
  ToolRun r = tool({"replay", dir + "/no_such.jsonl", "-o", dir + "/x.jsonl"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("no_such.jsonl: cannot open replay file"), std::string::npos) << r.err;
  r = tool({"replay", dir + "/no_such.jsonl"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("nothing to write"), std::string::npos) << r.err;
  r = tool({"replay", dir + "/a.jsonl", "-o", dir + "/x.jsonl", "--budget", "-1"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--budget must be > 0"), std::string::npos) << r.err;
  r = tool({"record", "builtin:small", "--path", "spiral", "-o", dir + "/x.jsonl"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--path must be orbit, flythrough or approach"), std::string::npos) << r.err;
  r = tool({"record", "builtin:small", "--path", "approach", "--from", "0.1", "-o", dir + "/x.jsonl"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--from must be in (0.15, 1e6)"), std::string::npos) << r.err;
  r = tool({"record", "builtin:small", "--path", "orbit", "--from", "10", "-o", dir + "/x.jsonl"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--from applies to --path approach"), std::string::npos) << r.err;
  r = tool({"record", dir + "/missing.glb", "-o", dir + "/x.jsonl"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("missing.glb"), std::string::npos) << r.err;
  // a replay naming a scene that does not exist
  {
    std::ofstream f(dir + "/lost.jsonl");
    f << "{\"scenelod_replay\": 1, \"scene\": \"lost_scene.json\"}\n{\"frame\": 0, \"eye\": [0,0,5], \"target\": [0,0,0]}\n";
  }
  r = tool({"replay", dir + "/lost.jsonl", "-o", dir + "/x.jsonl"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("lost_scene.json: cannot open level scene"), std::string::npos) << r.err;
}

TEST(ReplayCommands, LongRunsStreamTheirLogAndDecimateTheReportsSeries) {
  // the log streams to disk frame by frame and the report keeps at most 4,096 points a run, so memory
  // does not grow with the frame count; 9,000 frames are kept every 4th (stride 1 -> 2 -> 4)
  if (std::string(SCENELOD_TOOL_PATH).empty()) GTEST_SKIP() << "the tool is not built";
  const std::string dir = scenelod::test::scratchDir();
  const std::string replay = dir + "/long.jsonl", log = dir + "/long_log.jsonl", report = dir + "/long_report.md";
  ToolRun r = tool({"record", "builtin:small", "--path", "orbit", "--frames", "9000", "-o", replay});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = tool({"replay", replay, "--out", log, "--report", report});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(lineCount(slurp(log)), 9000u);
  EXPECT_NE(r.out.find("9000 frames"), std::string::npos) << r.out;
  const std::string md = slurp(report);
  EXPECT_NE(md.find(", 9000 frames"), std::string::npos) << md.substr(0, 400);
  EXPECT_NE(md.find("## Frame cost over time (every 40th frame)"), std::string::npos);
  EXPECT_NE(md.find("\n| 8960 | "), std::string::npos);  // the last row: a multiple of 40
  // a run that fails part-way leaves no log behind
  const std::string bad = dir + "/bad_tail.jsonl", bad_log = dir + "/bad_tail_log.jsonl";
  std::ofstream(bad) << slurp(replay) << "{\"frame\": 1, \"eye\": [0, 0, 1], \"target\": [0, 0, 0]}\n";
  r = tool({"replay", bad, "--out", bad_log});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find(bad + ":9002: frames must be in increasing order"), std::string::npos) << r.err;
  EXPECT_FALSE(scenelod::test::fileExists(bad_log));
}

// --transitions: the log gains morph, fade, previous_levels and fading; none keeps the log as it was
TEST(ReplayCommands, TransitionsAddMorphAndFadeToTheLog) {
  if (std::string(SCENELOD_TOOL_PATH).empty()) GTEST_SKIP() << "the tool is not built";
  const std::string dir = scenelod::test::scratchDir();
  const std::string replay = dir + "/tr.jsonl", none = dir + "/tr_none.jsonl", plain = dir + "/tr_plain.jsonl",
                    fade = dir + "/tr_fade.jsonl";
  ToolRun r = tool({"record", "builtin:small", "--path", "orbit", "--frames", "30", "--budget", "1.0", "-o", replay});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ASSERT_EQ(tool({"replay", replay, "-o", plain}).exit_code, 0);
  ASSERT_EQ(tool({"replay", replay, "-o", none, "--transitions", "none"}).exit_code, 0);
  EXPECT_EQ(slurp(none), slurp(plain));
  EXPECT_EQ(slurp(none).find("\"morph\""), std::string::npos);
  r = tool({"replay", replay, "-o", fade, "--transitions", "fade", "--fade-ms", "100"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string text = slurp(fade);
  EXPECT_EQ(lineCount(text), 30u);
  EXPECT_NE(text.find("\"morph\": ["), std::string::npos);
  EXPECT_NE(text.find("\"fade\": ["), std::string::npos);
  EXPECT_NE(text.find("\"previous_levels\": ["), std::string::npos);
  for (const auto& bad : std::vector<std::vector<std::string>>{{"--transitions", "dither"},
                                                             {"--fade-ms", "-1"},
                                                             {"--morph-band", "0"},
                                                             {"--morph-band", "1.5"},
                                                             {"--fade-budget-share", "2"},
                                                             {"--min-drop-px", "-1"}}) {
    std::vector<std::string> args = {"replay", replay, "-o", fade};
    args.insert(args.end(), bad.begin(), bad.end());
    r = tool(args);
    EXPECT_EQ(r.exit_code, 2) << bad[0];
    EXPECT_NE(r.err.find(bad[0]), std::string::npos) << r.err;
  }
}

// --min-drop-px 0 drops any object to fit a budget; the default keeps objects of 4 px or more
TEST(ReplayCommands, MinDropPxZeroDropsMore) {
  if (std::string(SCENELOD_TOOL_PATH).empty()) GTEST_SKIP() << "the tool is not built";
  const std::string dir = scenelod::test::scratchDir();
  const std::string replay = dir + "/md.jsonl", keep = dir + "/md_keep.jsonl", any = dir + "/md_any.jsonl";
  ASSERT_EQ(tool({"record", "builtin:small", "--path", "orbit", "--frames", "20", "--budget", "0.85", "-o", replay}).exit_code, 0);
  ASSERT_EQ(tool({"replay", replay, "-o", keep}).exit_code, 0);
  ASSERT_EQ(tool({"replay", replay, "-o", any, "--min-drop-px", "0"}).exit_code, 0);
  auto dropped = [](const std::string& text) {
    size_t total = 0, at = 0;
    while ((at = text.find("\"dropped\": ", at)) != std::string::npos) {
      at += 11;
      total += std::stoul(text.substr(at));
    }
    return total;
  };
  EXPECT_GT(dropped(slurp(any)), dropped(slurp(keep)));
}
