// The ROS 2 forms of Lockstep samples (ros2_bridge/convert.h): CARLA's names, topics,
// stamps and layouts.
#include "convert.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

namespace lockstep::ros2 {
namespace {

msg::FrameStamp Stamp(uint64_t frame, double dt) {
  msg::FrameStamp s;
  s.run(1);
  s.frame(frame);
  s.sim_time(static_cast<double>(frame) * dt);
  return s;
}

ActorInfo Actor(uint32_t id, const std::string& bp, uint32_t parent, std::map<std::string, std::string> attrs = {}) {
  ActorInfo a;
  a.id = id;
  a.blueprint = bp;
  a.parent = parent;
  a.attributes = std::move(attrs);
  return a;
}

TEST(Ros2Convert, TimeIsCarlasSecondsAndTruncatedNanoseconds) {
  auto t = RosTime(12.345);
  double whole = 0;
  EXPECT_EQ(t.sec(), 12);
  EXPECT_EQ(t.nanosec(), static_cast<uint32_t>(std::modf(12.345, &whole) * 1e9));
  t = RosTime(0.05 * 3);  // frame 3 at dt 0.05
  EXPECT_EQ(t.sec(), 0);
  EXPECT_EQ(t.nanosec(), static_cast<uint32_t>(0.05 * 3 * 1e9));
  EXPECT_EQ(RosTime(0).sec(), 0);
  EXPECT_EQ(RosTime(0).nanosec(), 0u);
}

TEST(Ros2Convert, NamesAndTopicsFollowCarlasRosNames) {
  std::map<uint32_t, ActorInfo> actors;
  actors[5] = Actor(5, "vehicle.tesla.model3", 0, {{"role_name", "hero"}});
  actors[6] = Actor(6, "sensor.camera.rgb", 5, {{"role_name", "front"}});
  actors[7] = Actor(7, "sensor.lidar.ray_cast", 5);
  actors[8] = Actor(8, "vehicle.audi.tt", 0, {{"role_name", "autopilot"}});
  actors[9] = Actor(9, "sensor.other.gnss", 0);
  EXPECT_EQ(BaseTopic(actors[5], actors), "rt/carla/hero");
  EXPECT_EQ(BaseTopic(actors[6], actors), "rt/carla/hero/front");
  EXPECT_EQ(BaseTopic(actors[7], actors), "rt/carla/hero/ray_cast7");
  EXPECT_EQ(RosName(actors[8]), "vehicle8");
  EXPECT_EQ(BaseTopic(actors[9], actors), "rt/carla/gnss9");
  EXPECT_TRUE(TakesControl(actors[5]));
  EXPECT_FALSE(TakesControl(actors[8]));
  EXPECT_TRUE(TakesControl(Actor(3, "vehicle.x", 0, {{"role_name", "ego"}})));
  EXPECT_FALSE(TakesControl(Actor(4, "walker.pedestrian.0001", 0, {{"role_name", "hero"}})));
}

TEST(Ros2Convert, PerFrameSensorsAreThoseACarlaClientWaitsFor) {
  EXPECT_EQ(SensorKindOf("sensor.camera.rgb"), SensorKind::kCamera);
  EXPECT_EQ(SensorKindOf("sensor.lidar.ray_cast"), SensorKind::kLidar);
  EXPECT_EQ(SensorKindOf("sensor.lidar.ray_cast_semantic"), SensorKind::kSemanticLidar);
  EXPECT_EQ(SensorKindOf("sensor.other.radar"), SensorKind::kNone);
  EXPECT_TRUE(PerFrame(SensorKind::kCamera, 0, 0.05));
  EXPECT_TRUE(PerFrame(SensorKind::kImu, 0.05, 0.05));
  EXPECT_FALSE(PerFrame(SensorKind::kLidar, 0.5, 0.05));
  EXPECT_FALSE(PerFrame(SensorKind::kCollision, 0, 0.05));
}

TEST(Ros2Convert, ImageIsBgra8WithTheFramesStamp) {
  msg::Image i;
  i.stamp(Stamp(7, 0.05));
  i.width(4);
  i.height(2);
  i.step(16);
  i.encoding(static_cast<uint32_t>(msg::ImageEncoding::IMAGE_BGRA8));
  i.data(std::vector<uint8_t>(32, 9));
  std::string why;
  auto r = ToRosImage(i, "front", &why);
  ASSERT_TRUE(r.has_value()) << why;
  EXPECT_EQ(r->encoding(), "bgra8");
  EXPECT_EQ(r->step(), 16u);
  EXPECT_EQ(r->width(), 4u);
  EXPECT_EQ(r->height(), 2u);
  EXPECT_EQ(r->is_bigendian(), 0);
  EXPECT_EQ(r->data().size(), 32u);
  EXPECT_EQ(r->header().frame_id(), "front");
  EXPECT_EQ(r->header().stamp().sec(), RosTime(0.35).sec());
  EXPECT_EQ(r->header().stamp().nanosec(), RosTime(0.35).nanosec());
  i.encoding(static_cast<uint32_t>(msg::ImageEncoding::IMAGE_DEPTH_F32));
  EXPECT_EQ(ToRosImage(i, "d", &why)->encoding(), "32FC1");
  i.encoding(static_cast<uint32_t>(msg::ImageEncoding::IMAGE_DVS_EVENTS));
  EXPECT_FALSE(ToRosImage(i, "dvs", &why).has_value());
  EXPECT_NE(why.find("DVS"), std::string::npos);
}

TEST(Ros2Convert, CameraInfoIsThePinholeOfTheFov) {
  const auto info = ToCameraInfo(800, 600, M_PI / 2, RosTime(1), "front");
  EXPECT_EQ(info.distortion_model(), "plumb_bob");
  EXPECT_NEAR(info.k()[0], 400.0, 1e-9);  // 800 / (2 tan 45 deg)
  EXPECT_NEAR(info.k()[4], 400.0, 1e-9);
  EXPECT_EQ(info.k()[2], 400.0);
  EXPECT_EQ(info.k()[5], 300.0);
  EXPECT_EQ(info.k()[8], 1.0);
  EXPECT_EQ(info.p()[0], info.k()[0]);
  EXPECT_EQ(info.p()[10], 1.0);
  EXPECT_EQ(info.d().size(), 5u);
  EXPECT_TRUE(info.roi().do_rectify());
}

TEST(Ros2Convert, PointCloud2IsXyzIntensityFloat32) {
  msg::PointCloud c;
  c.stamp(Stamp(3, 0.1));
  c.format(msg::PointFormat::POINTS_XYZI);
  c.point_count(2);
  c.point_step(16);
  const float pts[8] = {1, 2, 3, 0.5f, -1, -2, -3, 0.25f};
  std::vector<uint8_t> bytes(sizeof pts);
  std::memcpy(bytes.data(), pts, sizeof pts);
  c.data(bytes);
  const auto r = ToPointCloud2(c, "lidar");
  ASSERT_EQ(r.fields().size(), 4u);
  const char* names[] = {"x", "y", "z", "intensity"};
  for (size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(r.fields()[i].name(), names[i]);
    EXPECT_EQ(r.fields()[i].offset(), 4 * i);
    EXPECT_EQ(r.fields()[i].datatype(), 7);
    EXPECT_EQ(r.fields()[i].count(), 1u);
  }
  EXPECT_EQ(r.height(), 1u);
  EXPECT_EQ(r.width(), 2u);
  EXPECT_EQ(r.point_step(), 16u);
  EXPECT_EQ(r.row_step(), 32u);
  EXPECT_FALSE(r.is_bigendian());
  EXPECT_FALSE(r.is_dense());
  EXPECT_EQ(r.data(), bytes);  // FLU already: no axis flip
  EXPECT_EQ(r.header().frame_id(), "lidar");
}

TEST(Ros2Convert, EgoControlBecomesTheVehiclesControl) {
  carla_msgs::msg::dds_::CarlaEgoVehicleControl_ c;
  c.throttle(0.7f);
  c.steer(-0.2f);
  c.brake(0.1f);
  c.reverse(true);
  c.gear(-1);
  c.manual_gear_shift(true);
  const auto v = FromEgoControl(c, 42);
  EXPECT_EQ(v.actor(), 42u);
  EXPECT_FLOAT_EQ(v.throttle(), 0.7f);
  EXPECT_FLOAT_EQ(v.steer(), -0.2f);
  EXPECT_FLOAT_EQ(v.brake(), 0.1f);
  EXPECT_TRUE(v.reverse());
  EXPECT_EQ(v.gear(), -1);
  EXPECT_TRUE(v.manual_gear_shift());
}

}  // namespace
}  // namespace lockstep::ros2
