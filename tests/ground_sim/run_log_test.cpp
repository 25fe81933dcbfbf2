// The run's ground files: a row per vehicle and tick in vehicles.csv, and the infraction
// summary in infractions.json with what happened (here: a car driving into a wall).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "lockstep/ground/run_log.h"
#include "test_towns.h"

namespace lockstep::ground {
namespace {

std::string Slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

int Lines(const std::string& text) { return static_cast<int>(std::count(text.begin(), text.end(), '\n')); }

TEST(GroundRunLog, VehicleRowsEveryTickAndTheInfractionSummary) {
  const std::string dir = ::testing::TempDir() + "ground_run_log_" + std::to_string(::getpid());
  std::filesystem::remove_all(dir);
  World w(testing::StraightTown(40), 3);
  const Vec3 half = FindVehicle("vehicle.audi.tt")->half_extents;
  ASSERT_EQ(w.AddVehicle(7, "vehicle.audi.tt", {{"role_name", "hero"}}, Pose::FromYaw(Vec3(0, -1.75, half.z() + 0.02), 0)), "");
  ASSERT_EQ(w.AddVehicle(8, "vehicle.audi.tt", {}, Pose::FromYaw(Vec3(-60, -1.75, half.z() + 0.02), 0)), "");
  VehicleControl full;
  full.throttle = 1;
  ASSERT_EQ(w.ApplyControl(7, full), "");
  {
    RunLog log(dir, true);
    for (int i = 1; i <= 100; ++i) {
      w.Step(0.05);
      log.Write(w, static_cast<uint64_t>(i), i * 0.05);
    }
  }
  const std::string csv = Slurp(dir + "/vehicles.csv");
  EXPECT_EQ(Lines(csv), 1 + 2 * 100);
  EXPECT_EQ(csv.rfind("frame,sim_time_s,id,blueprint,role_name,x_m", 0), 0u);
  EXPECT_NE(csv.find("\n100,5,7,vehicle.audi.tt,hero,"), std::string::npos);
  const std::string json = Slurp(dir + "/infractions.json");
  EXPECT_NE(json.find("\"frames\": 100"), std::string::npos) << json;
  EXPECT_NE(json.find("\"vehicles\": 2"), std::string::npos) << json;
  // The hero drove into the wall (and, pushing on, bounced and touched it again): each
  // contact counts once, not once per tick in contact, in its row and in the total.
  const int hits = w.Vehicle(7)->infractions.static_collisions;
  EXPECT_GE(hits, 1);
  EXPECT_LE(hits, 3);
  EXPECT_NE(json.find("\"total\": {\"red_lights\": 0, \"stop_signs\": 0, \"vehicle_collisions\": 0, \"walker_collisions\": 0, "
                      "\"static_collisions\": " + std::to_string(hits)),
            std::string::npos)
      << json;
  // A replacement appends to the same files (no second header).
  {
    RunLog log(dir, false);
    w.Step(0.05);
    log.Write(w, 101, 5.05);
  }
  EXPECT_EQ(Lines(Slurp(dir + "/vehicles.csv")), 1 + 2 * 101);
  std::filesystem::remove_all(dir);
}

TEST(GroundRunLog, AFolderThatCannotBeMadeIsAClearError) {
  try {
    RunLog log("/proc/no_such_place/ground", true);
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/proc/no_such_place/ground"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace lockstep::ground
