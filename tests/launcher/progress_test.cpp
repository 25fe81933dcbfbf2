// The progress line and the run summary of `lockstep up`.
#include "progress.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

namespace lockstep::launcher {
namespace {

TEST(Progress, ABarOfTheDoneShareWithFiguresAndTimeLeft) {
  const Progress p{500, 2000, 25.0, 10.0, 50.0, "running"};
  const std::string line = FormatProgress(p, true, 120);
  EXPECT_EQ(line.rfind("[#######.......................] ", 0), 0u) << line;  // 25 % of 30 cells, rounded down
  EXPECT_NE(line.find(" 25% frame 500/2000, sim 25.0 s, 50.0 ticks/s, 10s elapsed, 30s left"), std::string::npos) << line;
  EXPECT_EQ(line.find("["), 0u);
}

TEST(Progress, FitsTheTerminalAndNamesAStateOtherThanRunning) {
  const Progress p{2000, 2000, 100.0, 3700.0, 0.5, "faulted"};
  const std::string wide = FormatProgress(p, true, 200);
  EXPECT_NE(wide.find("[##############################] 100%"), std::string::npos) << wide;
  EXPECT_NE(wide.find("1h01m elapsed, 0s left [faulted]"), std::string::npos) << wide;
  EXPECT_EQ(FormatProgress(p, true, 40).size(), 40u);
  EXPECT_EQ(FormatProgress(p, false, 200).find("[#"), std::string::npos) << "no bar off a terminal";
}

TEST(Progress, AnEndlessRunShowsFramesAndRateOnly) {
  const Progress p{1234, 0, 61.7, 65.0, 19.0, "running"};
  EXPECT_EQ(FormatProgress(p, true, 200), "frame 1234, sim 61.7 s, 19.0 ticks/s, 1m05s elapsed");
}

TEST(Progress, PlainLinesComeOncePerTenthOfTheRun) {
  int lines = 0;
  uint64_t last = 0;
  for (uint64_t f = 1; f <= 2000; f += 7) {
    if (PlainLineDue(f, 2000, last)) {
      ++lines;
      last = f;
    }
  }
  EXPECT_EQ(lines, 9) << "frames 200, 400, ... 1800 (2000 itself is not reached by steps of 7)";
  EXPECT_TRUE(PlainLineDue(2000, 2000, 1999));
  EXPECT_FALSE(PlainLineDue(450, 2000, 400));
  EXPECT_TRUE(PlainLineDue(500, 0, 499)) << "every 500 frames without an end";
  EXPECT_FALSE(PlainLineDue(999, 0, 500));
}

TEST(Summary, NamesTheRunItsFiguresItsServicesAndWhatTheyWrote) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("lockstep-summary-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir / "run1/sensors");
  fs::create_directories(dir / "run1/render/cam/deep");
  std::ofstream(dir / "run1/frames.csv") << std::string(100, 'x');
  std::ofstream(dir / "run1/sensors/a.ply") << std::string(3000, 'x');
  std::ofstream(dir / "run1/sensors/b.ply") << std::string(3000, 'x');
  std::ofstream(dir / "run1/render/cam/deep/f.png") << std::string(10, 'x');
  const auto groups = ScanOutputs(dir.string());
  ASSERT_EQ(groups.size(), 3u);
  EXPECT_EQ(groups[0].path, "run1/sensors");
  EXPECT_EQ(groups[0].files, 2u);
  EXPECT_EQ(groups[0].bytes, 6000u);
  EXPECT_EQ(groups[1].path, "run1");
  EXPECT_EQ(groups[2].path, "run1/render") << "grouped two levels deep";

  Summary s;
  s.name = "default";
  s.state = "stopped";
  s.frames = 2000;
  s.sim_time = 100;
  s.wall_s = 50;
  s.members = {{"air_sim", "air_sim", 2000, 1500}};
  s.output_dir = dir.string();
  s.outputs = groups;
  s.service_summaries = {{"run1/ground/summary.txt", "collisions 0\n"}};
  const std::string text = FormatSummary(s);
  EXPECT_NE(text.find("run      stopped after 2000 frame(s): 100.00 s simulated in 50.00 s of wall time (40.0 ticks/s, real-time factor 2.00)"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("air_sim              air_sim              2000           1.50"), std::string::npos) << text;
  EXPECT_NE(text.find(": 4 file(s), 6.0 KiB"), std::string::npos) << text;
  EXPECT_NE(text.find("-- run1/ground/summary.txt\ncollisions 0\n"), std::string::npos) << text;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace lockstep::launcher
