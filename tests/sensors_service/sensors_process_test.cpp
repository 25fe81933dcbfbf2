// `lockstep up` with the sensors service as its own process: a LiDAR, an IMU and a GNSS
// ride a drone over the generated town (attached by the scenario's parent key), and every
// frame of the run is written once, in order: a PLY per LiDAR sample, a CSV row per
// inertial sample.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "process.h"

namespace lockstep::testing {
namespace {

using namespace std::chrono_literals;
namespace fs = std::filesystem;

std::vector<std::string> Lines(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::string> out;
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

TEST(SensorsProcess, WritesEveryFramesSamplesOnceInOrder) {
  const std::string out = fs::temp_directory_path() / ("lockstep-sensors-" + std::to_string(getpid()));
  fs::remove_all(out);
  const uint64_t ticks = 60;
  const std::string config = WriteTempFile(
      "sensors.yaml",
      "name: sensors-test\ndomain_id: " + std::to_string(TestDomain()) +
          "\nparticipant_profile: lockstep.participant.loopback\nseed: 7\nticks: " + std::to_string(ticks) + "\noutput_dir: " + out +
          "\nmap: " LOCKSTEP_TEST_TOWN_DIR "/LockstepTown1.xodr\n"
          "services:\n  - {name: air_sim, kind: air_sim}\n  - {name: sensors, kind: sensors, perception: true}\n"
          "scenario:\n"
          "  - {frame: 1, spawn: drone.generic_quad, as: d, at: [47.75, 1.75, 0]}\n"
          "  - {frame: 1, spawn: sensor.lidar.ray_cast, as: lidar, parent: d, at: [0, 0, -0.1],"
          " attributes: {range: 50, channels: 16, lower_fov: -60}}\n"
          "  - {frame: 1, spawn: sensor.other.imu, as: imu, parent: d}\n"
          "  - {frame: 1, spawn: sensor.other.gnss, as: gnss, parent: d}\n"
          "  - {frame: 2, actor: d, drone: arm}\n"
          "  - {frame: 3, actor: d, drone: takeoff}\n");
  Process up({Bin("lockstep"), "up", config});
  auto code = up.Wait(90s);
  ASSERT_TRUE(code) << "lockstep up did not finish:\n" << up.Output();
  ASSERT_EQ(*code, 0) << up.Output();
  const std::string dir = out + "/run1/sensors";
  ASSERT_TRUE(fs::exists(dir)) << up.Output();
  std::vector<fs::path> plys;
  std::string imu_csv, gnss_csv;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    const std::string name = e.path().filename();
    if (e.path().extension() == ".ply") plys.push_back(e.path());
    if (name.rfind("imu_", 0) == 0) imu_csv = e.path();
    if (name.rfind("gnss_", 0) == 0) gnss_csv = e.path();
  }
  ASSERT_EQ(plys.size(), ticks) << "one PLY per frame";
  std::sort(plys.begin(), plys.end());
  for (uint64_t k = 1; k <= ticks; ++k) {
    char name[32];
    std::snprintf(name, sizeof name, "%06llu.ply", static_cast<unsigned long long>(k));
    EXPECT_EQ(plys[k - 1].filename(), name);
  }
  // A sample from the air: the header's vertex count matches the binary payload.
  std::ifstream ply(plys.back(), std::ios::binary);
  std::string line;
  size_t vertices = 0;
  while (std::getline(ply, line) && line != "end_header") std::sscanf(line.c_str(), "element vertex %zu", &vertices);
  const auto header_end = static_cast<size_t>(ply.tellg());
  EXPECT_GT(vertices, 100u) << "the LiDAR sees the town below";
  EXPECT_EQ(fs::file_size(plys.back()), header_end + vertices * 16);
  for (const std::string& csv : {imu_csv, gnss_csv}) {
    ASSERT_FALSE(csv.empty());
    const auto rows = Lines(csv);
    ASSERT_EQ(rows.size(), ticks + 1) << csv;
    for (uint64_t k = 1; k <= ticks; ++k) EXPECT_EQ(rows[k].substr(0, rows[k].find(',')), std::to_string(k)) << csv;
  }
  // At rest on the road before take-off, the IMU reads gravity.
  double az = 0;
  ASSERT_EQ(std::sscanf(Lines(imu_csv)[2].c_str(), "%*u,%*f,%*f,%*f,%lf", &az), 1);
  EXPECT_NEAR(az, 9.81, 0.05);
  fs::remove_all(out);
}

}  // namespace
}  // namespace lockstep::testing
