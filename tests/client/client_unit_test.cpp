// Client pieces with no bus: AirSim NED conversions, the blueprint library built from
// declarations, sensor topics by blueprint, snapshots.
#include <gtest/gtest.h>

#include <cmath>

#include "lockstep/client/blueprint_library.h"
#include "lockstep/client/client.h"
#include "lockstep/client/multirotor.h"
#include "lockstep/runtime/blueprint_builder.h"

namespace lockstep::client {
namespace {

constexpr double kPi = 3.14159265358979323846;

msg::Vector3 V(double x, double y, double z) {
  msg::Vector3 v;
  v.x(x);
  v.y(y);
  v.z(z);
  return v;
}

TEST(Ned, PositionsAreNorthEastDownFromHome) {
  const msg::Vector3 home = V(100, 50, 2);
  const Ned n = EnuToNed(V(103, 54, 12), home);  // 3 m east, 4 m north, 10 m up
  EXPECT_DOUBLE_EQ(n.x, 4);
  EXPECT_DOUBLE_EQ(n.y, 3);
  EXPECT_DOUBLE_EQ(n.z, -10);
  const msg::Vector3 back = NedToEnu(n, home);
  EXPECT_DOUBLE_EQ(back.x(), 103);
  EXPECT_DOUBLE_EQ(back.y(), 54);
  EXPECT_DOUBLE_EQ(back.z(), 12);
}

TEST(Ned, HeadingsTurnFromEastCounterClockwiseToNorthClockwise) {
  EXPECT_NEAR(NedYawDegToEnu(0), kPi / 2, 1e-12);   // north
  EXPECT_NEAR(NedYawDegToEnu(90), 0, 1e-12);        // east
  EXPECT_NEAR(std::remainder(EnuYawToNedDeg(kPi) - 270, 360), 0, 1e-9);  // west
  for (double yaw : {0.0, 0.3, kPi / 2, 2.0, -1.0}) {
    msg::Quaternion q;
    q.w(std::cos(yaw / 2));
    q.z(std::sin(yaw / 2));
    const NedQuaternion n = EnuToNedQuaternion(q);
    // NED yaw of an FRD body from its quaternion.
    const double ned_yaw = std::atan2(2 * (n.w * n.z + n.x * n.y), 1 - 2 * (n.y * n.y + n.z * n.z));
    EXPECT_NEAR(std::remainder(ned_yaw - (kPi / 2 - yaw), 2 * kPi), 0, 1e-9) << yaw;
    const msg::Quaternion r = NedToEnuQuaternion(n);
    EXPECT_NEAR(std::abs(r.w() * q.w() + r.z() * q.z() + r.x() * q.x() + r.y() * q.y()), 1, 1e-9);
  }
}

TEST(Ned, NoseUpPitchIsPositiveInFrd) {
  const double pitch_flu = -0.2;  // FLU: negative pitch = nose up
  msg::Quaternion q;
  q.w(std::cos(pitch_flu / 2));
  q.y(std::sin(pitch_flu / 2));
  const NedQuaternion n = EnuToNedQuaternion(q);
  const double pitch_frd = std::asin(2 * (n.w * n.y - n.z * n.x));
  EXPECT_NEAR(pitch_frd, 0.2, 1e-9);
}

TEST(Blueprints, LibraryIsTheUnionOfDeclarationsAndFiltersLikeCarla) {
  namespace bp = lockstep::blueprint;
  std::map<std::string, std::vector<msg::BlueprintDeclaration>> decl;
  decl["ground_sim"] = {bp::Make("vehicle.tesla.model3", msg::ActorKind::ACTOR_VEHICLE, {bp::Rgb("color", "255,0,0")}),
                        bp::Make("walker.pedestrian.0001", msg::ActorKind::ACTOR_WALKER, {})};
  decl["render_a"] = {bp::Make("sensor.camera.rgb", msg::ActorKind::ACTOR_SENSOR, {})};
  decl["render_b"] = {bp::Make("sensor.camera.rgb", msg::ActorKind::ACTOR_SENSOR, {})};
  const BlueprintLibrary lib(decl);
  EXPECT_EQ(lib.size(), 3u);
  EXPECT_EQ(lib.Filter("vehicle.*").size(), 1u);
  EXPECT_EQ(lib.Filter("tesla").size(), 1u);  // by tag
  EXPECT_EQ(lib.Filter("*").size(), 3u);
  EXPECT_EQ(lib.Filter("sensor.camera.r?b").size(), 1u);
  EXPECT_TRUE(lib.Find("walker.pedestrian.0001").has_value());
  EXPECT_FALSE(lib.Find("walker.pedestrian").has_value());
  EXPECT_EQ(lib.Owners("sensor.camera.rgb"), (std::vector<std::string>{"render_a", "render_b"}));
  EXPECT_EQ(lib.Find("vehicle.tesla.model3")->attributes()[0].id().to_string(), "color");
}

TEST(Sensors, BlueprintsMapToTheirTopics) {
  SensorType t;
  ASSERT_TRUE(SensorTypeOf("sensor.camera.depth", &t));
  EXPECT_EQ(t, SensorType::kImage);
  ASSERT_TRUE(SensorTypeOf("sensor.lidar.ray_cast_semantic", &t));
  EXPECT_EQ(t, SensorType::kPointCloud);
  ASSERT_TRUE(SensorTypeOf("sensor.other.gnss", &t));
  EXPECT_EQ(t, SensorType::kGnss);
  ASSERT_TRUE(SensorTypeOf("sensor.other.collision", &t));
  EXPECT_FALSE(IsPerFrame(t));
  EXPECT_FALSE(SensorTypeOf("vehicle.tesla.model3", &t));
}

TEST(Snapshot, FindsActorsOfEveryKind) {
  Snapshot s;
  s.ground = msg::GroundState();
  s.air = msg::AirState();
  msg::VehicleState v;
  v.actor(7);
  v.blueprint("vehicle.a");
  s.ground->vehicles().push_back(v);
  msg::DroneState d;
  d.actor(9);
  s.air->drones().push_back(d);
  msg::TrafficLightState l;
  l.actor(1);
  s.ground->traffic_lights().push_back(l);
  EXPECT_EQ(s.Actors().size(), 3u);
  EXPECT_EQ(s.Find(7)->kind, msg::ActorKind::ACTOR_VEHICLE);
  EXPECT_EQ(s.Find(9)->kind, msg::ActorKind::ACTOR_DRONE);
  EXPECT_EQ(s.Find(1)->kind, msg::ActorKind::ACTOR_TRAFFIC_LIGHT);
  EXPECT_FALSE(s.Find(8).has_value());
}

}  // namespace
}  // namespace lockstep::client
