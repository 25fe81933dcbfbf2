#include "lockstep/runtime/launch_config.h"
#include "lockstep/runtime/error.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <limits>

namespace lockstep {
namespace {

std::string ErrorOf(const std::string& yaml) {
  try {
    ParseLaunchConfig(yaml, "test.yaml");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(LaunchConfig, LoadsEveryKey) {
  auto c = ParseLaunchConfig(R"(
name: demo
domain_id: 7
seed: 9
ticks: 100
world:
  synchronous_mode: true
  fixed_delta_seconds: 0.02
  perception_mode: pipelined
services:
  - {name: air, kind: air_sim, restart: on-failure}
  - {name: cam, kind: render, required: false, perception: true, args: [--gpu, "0"]}
)", "t.yaml");
  EXPECT_EQ(c.name, "demo");
  EXPECT_EQ(c.domain_id, 7);
  EXPECT_EQ(c.seed, 9u);
  EXPECT_TRUE(c.world.synchronous_mode());
  EXPECT_DOUBLE_EQ(c.world.fixed_delta_seconds(), 0.02);
  EXPECT_EQ(c.world.perception_mode(), msg::PerceptionMode::PERCEPTION_PIPELINED);
  ASSERT_EQ(c.services.size(), 2u);
  EXPECT_EQ(c.services[1].args, (std::vector<std::string>{"--gpu", "0"}));
  EXPECT_EQ(c.RequiredServices(), std::vector<std::string>{"air"});
}

// Issue 21: a replacement replays at most one snapshot period with the inputs the state
// topics keep; a longer period would leave it without them.
TEST(LaunchConfig, SnapshotPeriodIsWithinWhatTheStateTopicsKeep) {
  EXPECT_EQ(ParseLaunchConfig("seed: 1\n", "t.yaml").snapshot_period, 200u);
  EXPECT_EQ(ParseLaunchConfig("snapshot_period: 20\n", "t.yaml").snapshot_period, 20u);
  EXPECT_NE(ErrorOf("snapshot_period: 249\n").find("snapshot_period"), std::string::npos);
  EXPECT_NE(ErrorOf("snapshot_period: 0\n").find("must be 1 .. 248 frames"), std::string::npos) << ErrorOf("snapshot_period: 0\n");
}

TEST(LaunchConfig, UnknownKeyIsNamedWithItsLine) {
  const std::string e = ErrorOf("name: x\nworld:\n  fixed_delta_seconds: 0.05\n  fixed_delta_second: 0.1\n");
  EXPECT_NE(e.find("test.yaml:4"), std::string::npos) << e;
  EXPECT_NE(e.find("unknown key 'world.fixed_delta_second'"), std::string::npos) << e;
}

TEST(LaunchConfig, AWeatherStepIsCarlasSetWeatherWithItsDefaults) {
  auto c = ParseLaunchConfig("scenario:\n  - {frame: 4, weather: {wind_intensity: 40, fog_density: 10}}\n", "test.yaml");
  ASSERT_EQ(c.scenario.size(), 1u);
  EXPECT_EQ(c.scenario[0].frame, 4u);
  const auto& w = c.scenario[0].command.body().weather();
  EXPECT_FLOAT_EQ(w.wind_intensity(), 40);
  EXPECT_FLOAT_EQ(w.fog_density(), 10);
  EXPECT_FLOAT_EQ(w.cloudiness(), 0);
  EXPECT_FLOAT_EQ(w.rayleigh_scattering_scale(), 0.0331f) << "CARLA's WeatherParameters() default";
  const std::string e = ErrorOf("scenario:\n  - {frame: 4, weather: {windy: 40}}\n");
  EXPECT_NE(e.find("unknown key 'scenario[0].weather.windy'"), std::string::npos) << e;
}

TEST(LaunchConfig, WrongTypeIsNamedWithItsLine) {
  const std::string e = ErrorOf("seed: 1\nticks: many\n");
  EXPECT_NE(e.find("test.yaml:2"), std::string::npos) << e;
  EXPECT_NE(e.find("'ticks' expected an integer, got 'many'"), std::string::npos) << e;
}

TEST(LaunchConfig, BadServiceEntriesAreNamed) {
  EXPECT_NE(ErrorOf("services:\n  - {kind: noop}\n").find("services[0].name' is required"), std::string::npos);
  EXPECT_NE(ErrorOf("services:\n  - {name: a, kind: noop}\n  - {name: a, kind: noop}\n").find("'a' is used twice"),
            std::string::npos);
  EXPECT_NE(ErrorOf("services:\n  - {name: a, kind: noop, restart: always}\n").find("restart"), std::string::npos);
  EXPECT_NE(ErrorOf("services: {name: a}\n").find("must be a list"), std::string::npos);
}

TEST(LaunchConfig, OutOfRangeWorldSettingsAreRejected) {
  EXPECT_NE(ErrorOf("world:\n  fixed_delta_seconds: 0\n").find("fixed_delta_seconds must be a finite number > 0"), std::string::npos);
  EXPECT_NE(ErrorOf("world:\n  perception_mode: lazy\n").find("'strict' or 'pipelined'"), std::string::npos);
  EXPECT_NE(ErrorOf("domain_id: 300\n").find("domain_id"), std::string::npos);
}

// Issue 19: CARLA accepts any positive fixed_delta_seconds (lidar_to_camera.py sets 3.0; it
// only warns when the step exceeds max_substep_delta_time x max_substeps).
TEST(LaunchConfig, StepsLongerThanOneSecondAreAcceptedAsCarlaDoes) {
  EXPECT_EQ(ErrorOf("world:\n  fixed_delta_seconds: 3.0\n"), "");
  msg::WorldSettings s = DefaultWorldSettings();
  s.fixed_delta_seconds(3.0);
  EXPECT_NO_THROW(ValidateWorldSettings(s, "world settings"));
  s.fixed_delta_seconds(-0.1);
  EXPECT_THROW(ValidateWorldSettings(s, "world settings"), InputError);
  s.fixed_delta_seconds(std::numeric_limits<double>::quiet_NaN());
  EXPECT_THROW(ValidateWorldSettings(s, "world settings"), InputError);
}

TEST(LaunchConfig, SyntaxErrorNamesTheLine) {
  const std::string e = ErrorOf("name: x\nworld: [1, 2\n");
  EXPECT_NE(e.find("test.yaml:"), std::string::npos) << e;
  EXPECT_NE(e.find("YAML syntax error"), std::string::npos) << e;
}

// Issue 7, part 4: default.yaml used to hard-code ../../build.
TEST(LaunchConfig, TheBuildDirectoryComesFromTheEnvironmentNotTheConfig) {
  setenv("LOCKSTEP_BUILD_DIR", "/somewhere/else", 1);
  const LaunchConfig c = LoadLaunchConfig(std::string(LOCKSTEP_TEST_CONFIG_DIR) + "/default.yaml");
  unsetenv("LOCKSTEP_BUILD_DIR");
  EXPECT_EQ(c.map, "/somewhere/else/maps/generated/LockstepTown1.xodr");
  EXPECT_EQ(BuildDir().empty(), false);
}

TEST(LaunchConfig, ShippedConfigsLoad) {
  for (const char* f : {"default.yaml"}) {
    EXPECT_NO_THROW(LoadLaunchConfig(std::string(LOCKSTEP_TEST_CONFIG_DIR) + "/" + f)) << f;
  }
}

}  // namespace
}  // namespace lockstep
