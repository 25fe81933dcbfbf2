// `lockstep serve`: where a map name is found and the launch config it runs.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "lockstep/runtime/error.h"
#include "lockstep/runtime/launch_config.h"
#include "serve.h"

namespace lockstep::launcher {
namespace {

namespace fs = std::filesystem;

class ServeTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::path(::testing::TempDir()) / ("serve_test_" + std::to_string(::getpid()));
    fs::create_directories(root_ / "checkout" / "build" / "maps" / "generated");
    fs::create_directories(root_ / "checkout" / "build" / "bin");
    fs::create_directories(root_ / "shared" / "maps" / "carla");
    std::ofstream(root_ / "shared" / "maps" / "carla" / "Town01.xodr") << "<OpenDRIVE/>";
    std::ofstream(root_ / "checkout" / "build" / "maps" / "generated" / "LockstepTown1.xodr") << "<OpenDRIVE/>";
    unsetenv("LOCKSTEP_MAPS_PATH");
  }
  void TearDown() override { fs::remove_all(root_); }
  std::string Build() const { return (root_ / "checkout" / "build").string(); }
  fs::path root_;
};

TEST_F(ServeTest, AMapNameIsFoundWhereLoadWorldLooks) {
  const auto search = MapSearchPath(Build());
  EXPECT_EQ(fs::path(FindMap("Town01", search)), (root_ / "shared" / "maps" / "carla" / "Town01.xodr").lexically_normal());
  EXPECT_EQ(fs::path(FindMap("LockstepTown1", search)),
            (root_ / "checkout" / "build" / "maps" / "generated" / "LockstepTown1.xodr").lexically_normal());
  const std::string file = (root_ / "shared" / "maps" / "carla" / "Town01.xodr").string();
  EXPECT_EQ(FindMap(file, search), fs::path(file).lexically_normal().string()) << "a path is taken as it is";
  try {
    FindMap("Town99", search);
    FAIL() << "an unknown map";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no map 'Town99'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("maps/carla"), std::string::npos) << "names where it looked: " << e.what();
  }
  // $LOCKSTEP_MAPS_PATH comes first.
  fs::create_directories(root_ / "mine");
  std::ofstream(root_ / "mine" / "Town01.xodr") << "<OpenDRIVE/>";
  setenv("LOCKSTEP_MAPS_PATH", (root_ / "mine").c_str(), 1);
  EXPECT_EQ(fs::path(FindMap("Town01", MapSearchPath(Build()))), (root_ / "mine" / "Town01.xodr").lexically_normal());
  unsetenv("LOCKSTEP_MAPS_PATH");
}

TEST_F(ServeTest, TheConfigRunsEveryBuiltServiceFreeRunningAtRealTime) {
  for (const char* p : {"lockstep_ground_sim", "lockstep_render"}) std::ofstream(root_ / "checkout" / "build" / "bin" / p) << "";
  const auto services = BuiltServices(Build());
  ASSERT_EQ(services, (std::vector<std::string>{"ground_sim", "render"}));
  ServeOptions o;
  o.domain = 7;
  const std::string map = (root_ / "shared" / "maps" / "carla" / "Town01.xodr").string();
  const LaunchConfig c = ParseLaunchConfig(ServeConfig(o, map, services), "serve.yaml");
  EXPECT_EQ(c.domain_id, 7);
  EXPECT_EQ(c.map, map);
  EXPECT_FALSE(c.world.synchronous_mode()) << "CARLA's server starts asynchronous";
  EXPECT_EQ(c.world.real_time_factor(), 1.0);
  EXPECT_EQ(c.world.fixed_delta_seconds(), 0.05);
  EXPECT_EQ(c.ticks, 0u) << "runs until Ctrl-C";
  ASSERT_EQ(c.services.size(), 2u);
  EXPECT_EQ(c.services[0].kind, "ground_sim");
  EXPECT_FALSE(c.services[0].perception);
  EXPECT_EQ(c.services[1].kind, "render");
  EXPECT_TRUE(c.services[1].perception);
}

}  // namespace
}  // namespace lockstep::launcher
