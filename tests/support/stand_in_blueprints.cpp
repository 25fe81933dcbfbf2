#include "stand_in_blueprints.h"

#include <cstdio>
#include <string>

#include "lockstep/runtime/blueprint_builder.h"

namespace lockstep::testing {
namespace {

using namespace lockstep::blueprint;
using Attrs = std::vector<msg::AttributeDeclaration>;

Attrs With(Attrs more) {
  Attrs v{String("role_name", "")};
  v.insert(v.end(), more.begin(), more.end());
  return v;
}

Attrs Noisy(const std::vector<std::string>& names) {
  Attrs v{String("role_name", "")};
  for (const auto& n : names) v.push_back(Float(n, 0, 0, 1e6));
  v.push_back(Int("noise_seed", 0, 0, 4294967295.0));
  v.push_back(Float("sensor_tick", 0, 0, 3600));
  return v;
}

}  // namespace

std::vector<msg::BlueprintDeclaration> StandInBlueprints() {
  std::vector<msg::BlueprintDeclaration> out;
  const Attrs vehicle = With({Rgb("color", "128,128,128"), Bool("sticky_control", true), Int("number_of_wheels", 4, 2, 18)});
  for (const char* id : {"vehicle.lockstep.sedan", "vehicle.lockstep.hatchback", "vehicle.lockstep.suv", "vehicle.lockstep.van",
                         "vehicle.lockstep.truck", "vehicle.lockstep.bus", "vehicle.lockstep.motorbike"}) {
    out.push_back(Make(id, msg::ACTOR_VEHICLE, vehicle));
  }
  const Attrs walker = With({Float("speed", 1.4, 0, 10), Bool("is_invincible", false)});
  for (int i = 1; i <= 10; ++i) {
    char id[40];
    std::snprintf(id, sizeof id, "walker.pedestrian.%04d", i);
    out.push_back(Make(id, msg::ACTOR_WALKER, walker));
  }
  const Attrs camera = With({Int("image_size_x", 800, 1, 3840), Int("image_size_y", 600, 1, 2160), Float("fov", 90, 1, 179),
                             Float("sensor_tick", 0, 0, 3600)});
  for (const char* id : {"sensor.camera.rgb", "sensor.camera.depth", "sensor.camera.semantic_segmentation",
                         "sensor.camera.instance_segmentation", "sensor.camera.normals"}) {
    out.push_back(Make(id, msg::ACTOR_SENSOR, camera));
  }
  const Attrs lidar = With({Int("channels", 32, 1, 256), Float("range", 10, 0.1, 1000), Int("points_per_second", 56000, 1, 10000000),
                            Float("rotation_frequency", 10, 0.1, 1000), Float("upper_fov", 10, -90, 90), Float("lower_fov", -30, -90, 90),
                            Float("horizontal_fov", 360, 1, 360), Float("sensor_tick", 0, 0, 3600)});
  out.push_back(Make("sensor.lidar.ray_cast", msg::ACTOR_SENSOR, lidar));
  out.push_back(Make("sensor.other.gnss", msg::ACTOR_SENSOR, Noisy({"noise_lat_bias", "noise_lat_stddev", "noise_lon_bias", "noise_lon_stddev"})));
  out.push_back(Make("sensor.other.imu", msg::ACTOR_SENSOR, Noisy({"noise_accel_stddev_x", "noise_gyro_stddev_x"})));
  out.push_back(Make("sensor.other.collision", msg::ACTOR_SENSOR, With({})));
  out.push_back(Make("sensor.other.lane_invasion", msg::ACTOR_SENSOR, With({})));
  // Set by the service, never by a client (CARLA's read-only attributes).
  out.push_back(Make("sensor.other.obstacle", msg::ACTOR_SENSOR,
                     With({Float("distance", 5, 0, 1000), Bool("only_dynamics", false), String("generation", "2", {}, false, false)})));
  return out;
}

}  // namespace lockstep::testing
