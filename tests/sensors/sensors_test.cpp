// Radar, IMU, GNSS, barometer, magnetometer, distance, obstacle, event sensors,
// sensor_tick scheduling, seeded noise and attribute checks.
#include <gtest/gtest.h>

#include <cmath>

#include "lockstep/sensors/geo.h"
#include "scenes.h"

namespace lockstep::sensors {
namespace {

using test::Frame;
using test::MakeActor;
using test::Spawn;

constexpr double kDt = 0.05;

TEST(Radar, VelocityOfAnApproachingCarMatchesItsSpeed) {
  SensorWorld w(1);
  w.scene().SetStatic({});
  ASSERT_EQ(w.Add(Spawn(10, "sensor.other.radar", {{"horizontal_fov", "4"}, {"vertical_fov", "4"}, {"points_per_second", "20000"}}, 0,
                        MakePose(0, 0, 1))),
            "");
  size_t hits = 0;
  for (int k = 1; k <= 5; ++k) {
    Actor car = MakeActor(3, ActorKind::kVehicle, "vehicle.lockstep.sedan", MakePose(30 - 12.0 * k * kDt, 0, 0.75, M_PI), Vec3(2.3, 1, 0.75));
    car.velocity = Vec3(-12, 0, 0);
    const auto out = w.Step(Frame(k, kDt, {car}), kDt);
    ASSERT_EQ(out.radar.size(), 1u);
    for (const auto& d : out.radar[0].data) {
      EXPECT_NEAR(d.velocity, -12.0, 12.0 * (1 - std::cos(3 * M_PI / 180)) + 1e-4);  // radial: within the cone's cosine
      EXPECT_NEAR(d.depth, car.pose.position.x() - 2.3, 0.03);  // along a ray up to 2 deg off the axis
      EXPECT_LE(std::abs(d.azimuth), 2.01 * M_PI / 180);
      EXPECT_LE(std::abs(d.altitude), 2.01 * M_PI / 180);
      ++hits;
    }
  }
  EXPECT_GT(hits, 1000u);
}

TEST(Radar, MovingSensorSeesStaticGeometryApproach) {
  // A radar on a car driving at 10 m/s towards a wall: the wall's radial velocity is -10.
  SensorWorld w(1);
  w.scene().SetStatic({test::Wall(50)});
  ASSERT_EQ(w.Add(Spawn(10, "sensor.other.radar", {{"horizontal_fov", "2"}, {"vertical_fov", "2"}}, 5, MakePose(2.5, 0, 0.5))), "");
  for (int k = 1; k <= 4; ++k) {
    Actor car = MakeActor(5, ActorKind::kVehicle, "vehicle.lockstep.sedan", MakePose(10.0 * k * kDt, 0, 0.75), Vec3(2.3, 1, 0.75));
    car.velocity = Vec3(10, 0, 0);
    const auto out = w.Step(Frame(k, kDt, {car}), kDt);
    if (k == 1) continue;  // its own velocity comes from the displacement since the last sample
    ASSERT_FALSE(out.radar.at(0).data.empty());
    for (const auto& d : out.radar[0].data) EXPECT_NEAR(d.velocity, -10.0, 0.01);
  }
}

TEST(Imu, AtRestReadsGravityOnZAndZeroMeanRotation) {
  SensorWorld w(9);
  ASSERT_EQ(w.Add(Spawn(10, "sensor.other.imu", {{"noise_gyro_stddev_x", "0.01"}, {"noise_gyro_stddev_y", "0.01"}, {"noise_gyro_stddev_z", "0.01"},
                                                 {"noise_accel_stddev_z", "0.02"}},
                        5, MakePose(0.5, 0.2, 1))),
            "");
  const Actor car = MakeActor(5, ActorKind::kVehicle, "vehicle.lockstep.sedan", MakePose(100, -40, 0.75, 1.0), Vec3(2.3, 1, 0.75));
  Vec3 gyro_sum = Vec3::Zero(), accel_sum = Vec3::Zero();
  const int n = 400;
  for (int k = 1; k <= n; ++k) {
    const auto out = w.Step(Frame(k, kDt, {car}), kDt);
    ASSERT_EQ(out.imu.size(), 1u);
    gyro_sum += out.imu[0].data.gyroscope;
    accel_sum += out.imu[0].data.accelerometer;
    EXPECT_NEAR(out.imu[0].data.accelerometer.z(), 9.81, 0.1);
    EXPECT_NEAR(out.imu[0].data.accelerometer.head<2>().norm(), 0.0, 0.01);
    // Compass: yaw 1 rad from east is pi/2 - 1 from north, clockwise.
    EXPECT_NEAR(out.imu[0].data.compass, M_PI / 2 - 1.0, 1e-9);
  }
  EXPECT_NEAR((gyro_sum / n).norm(), 0.0, 3 * 0.01 / std::sqrt(n) * std::sqrt(3.0));
  EXPECT_NEAR(accel_sum.z() / n, 9.81, 0.005);
}

TEST(Imu, OnACarTurningAtConstantSpeedReadsTheCentripetalAcceleration) {
  const double radius = 25, speed = 10, omega = speed / radius;  // counter-clockwise
  SensorWorld w(1);
  ASSERT_EQ(w.Add(Spawn(10, "sensor.other.imu", {{"noise_gyro_bias_stability", "0"}, {"noise_accel_bias_stability", "0"}}, 5)), "");
  for (int k = 1; k <= 100; ++k) {
    const double t = k * kDt, a = omega * t;
    Actor car = MakeActor(5, ActorKind::kVehicle, "vehicle.lockstep.sedan",
                          MakePose(radius * std::cos(a), radius * std::sin(a), 0.75, a + M_PI / 2), Vec3(2.3, 1, 0.75));
    car.velocity = Vec3(-speed * std::sin(a), speed * std::cos(a), 0);
    car.angular_velocity = Vec3(0, 0, omega);
    const auto out = w.Step(Frame(k, kDt, {car}), kDt);
    const ImuSample& s = out.imu.at(0).data;
    EXPECT_NEAR(s.gyroscope.z(), omega, 1e-9);
    if (k < 3) continue;  // the finite difference needs three samples
    // Body frame: the centre of the turn is to the left (+y). CARLA's three-point second
    // difference is centred one step back: the vector lags by omega * dt (it leans forward).
    const double centripetal = speed * speed / radius;
    EXPECT_NEAR(s.accelerometer.x(), centripetal * std::sin(omega * kDt), 0.01) << k;
    EXPECT_NEAR(s.accelerometer.y(), centripetal * std::cos(omega * kDt), 0.01) << k;
    EXPECT_NEAR(s.accelerometer.z(), 9.81, 1e-6) << k;
  }
}

// CARLA's IMU has no bias random walk: sensor.other.imu's stability attributes are 0 by
// default, so at rest with no noise the gyroscope reads exactly 0 for ever; set, they walk.
TEST(Imu, NoBiasRandomWalkByDefaultAnOptionOn) {
  for (bool walk : {false, true}) {
    SensorWorld w(4);
    std::map<std::string, std::string> attrs;
    if (walk) attrs = {{"noise_gyro_bias_stability", "0.01"}, {"noise_accel_bias_stability", "0.01"}};
    ASSERT_EQ(w.Add(Spawn(10, "sensor.other.imu", attrs, 5)), "");
    const Actor car = MakeActor(5, ActorKind::kVehicle, "vehicle.lockstep.sedan", MakePose(10, 5, 0.75, 0.3), Vec3(2.3, 1, 0.75));
    double max_gyro = 0, max_accel_xy = 0;
    for (int k = 1; k <= 400; ++k) {
      const ImuSample& s = w.Step(Frame(k, kDt, {car}), kDt).imu.at(0).data;
      max_gyro = std::max(max_gyro, s.gyroscope.norm());
      if (k > 2) max_accel_xy = std::max(max_accel_xy, s.accelerometer.head<2>().norm());
    }
    if (walk) {
      EXPECT_GT(max_gyro, 1e-3);
      EXPECT_GT(max_accel_xy, 1e-3);
    } else {
      EXPECT_EQ(max_gyro, 0.0);
      EXPECT_LT(max_accel_xy, 1e-9);
    }
  }
}

// noise_gyro_bias_{x,y,z} are CARLA's, in CARLA's gyroscope frame (Unreal's, y right): an
// angular velocity there is the FLU one as (-x, y, -z). The sample is FLU (the wire's), so
// a CARLA bias (0.1, 0.2, 0.3) reads (-0.1, 0.2, -0.3) here, and (0.1, 0.2, 0.3) in carla.
TEST(Imu, GyroBiasIsGivenInCarlasFrame) {
  SensorWorld w(4);
  ASSERT_EQ(w.Add(Spawn(10, "sensor.other.imu", {{"noise_gyro_bias_x", "0.1"}, {"noise_gyro_bias_y", "0.2"}, {"noise_gyro_bias_z", "0.3"}}, 5)),
            "");
  const Actor car = MakeActor(5, ActorKind::kVehicle, "vehicle.lockstep.sedan", MakePose(10, 5, 0.75), Vec3(2.3, 1, 0.75));
  const ImuSample& s = w.Step(Frame(1, kDt, {car}), kDt).imu.at(0).data;
  EXPECT_NEAR(s.gyroscope.x(), -0.1, 1e-12);
  EXPECT_NEAR(s.gyroscope.y(), 0.2, 1e-12);
  EXPECT_NEAR(s.gyroscope.z(), -0.3, 1e-12);
}

TEST(Gnss, KnownOffsetGivesCarlasLatitudeAndLongitude) {
  // Expected values from CARLA's formula (GeoLocation::Transform), computed apart.
  struct Case {
    GeoReference ref;
    Vec3 at;
    double lat, lon;
  };
  for (const Case& c : {Case{{49.0, 8.0, 0}, Vec3(1000, 2000, 30), 49.017963065353, 8.013692598447},
                       Case{{0.0, 0.0, 0}, Vec3(1000, 2000, 30), 0.017966305388, 0.008983152841}}) {
    SensorWorld w(1, c.ref);
    ASSERT_EQ(w.Add(Spawn(10, "sensor.other.gnss", {}, 0, MakePose(c.at.x(), c.at.y(), c.at.z()))), "");
    const auto out = w.Step(Frame(1, kDt), kDt);
    const GnssSample& g = out.gnss.at(0).data;
    EXPECT_NEAR(g.latitude, c.lat, 1e-7);
    EXPECT_NEAR(g.longitude, c.lon, 1e-7);
    EXPECT_NEAR(g.altitude, 30, 1e-9);
  }
  EXPECT_DOUBLE_EQ(ParseGeoReference("+proj=tmerc +lat_0=49.5 +lon_0=8.25 +k=1").latitude, 49.5);
  EXPECT_DOUBLE_EQ(ParseGeoReference("+proj=tmerc +lat_0=49.5 +lon_0=8.25 +k=1").longitude, 8.25);
  EXPECT_DOUBLE_EQ(ParseGeoReference("").latitude, 0.0);
}

// The one geo projection (lockstep/map/geo.h) serves air_sim's GPS calls too: moveToGPS
// goes back through FromGeo, the exact inverse.
TEST(Gnss, TheProjectionRoundTripsThroughFromGeo) {
  const GeoReference ref = ParseGeoReference("+proj=tmerc +lat_0=49.0 +lon_0=8.4 +k=1 +x_0=0 +y_0=0 +datum=WGS84");
  EXPECT_EQ(ref.latitude, 49.0);
  EXPECT_EQ(ref.longitude, 8.4);
  const Vec3 p(120.5, -340.25, 17);
  const GeoPoint g = ToGeo(ref, p);
  EXPECT_GT(g.longitude, 8.4);  // east
  EXPECT_LT(g.latitude, 49.0);  // south
  EXPECT_LT((map::FromGeo(ref, g) - p).norm(), 1e-6);
  EXPECT_NEAR(ToGeo(ref, Vec3::Zero()).latitude, 49.0, 1e-9);
}

TEST(Gnss, BiasAndNoiseApply) {
  SensorWorld w(1, GeoReference{49, 8, 0});
  ASSERT_EQ(w.Add(Spawn(10, "sensor.other.gnss", {{"noise_lat_bias", "0.001"}, {"noise_alt_stddev", "2"}})), "");
  double alt_sq = 0;
  for (int k = 1; k <= 400; ++k) {
    const auto g = w.Step(Frame(k, kDt), kDt).gnss.at(0).data;
    EXPECT_NEAR(g.latitude, 49.001, 1e-9);
    alt_sq += g.altitude * g.altitude;
    if (k == 1) {
      EXPECT_FALSE(g.fix);
    }
    if (k == 400) {
      EXPECT_TRUE(g.fix);
    }
  }
  EXPECT_NEAR(std::sqrt(alt_sq / 400), 2.0, 0.25);
}

TEST(Barometer, AltitudeFollowsTheStandardAtmosphere) {
  SensorWorld w(1);
  for (int i = 0; i < 5; ++i) {
    ASSERT_EQ(w.Add(Spawn(10 + i, "sensor.other.barometer", {{"noise_pressure_stddev", "0"}, {"drift_pressure_factor_sigma", "0"}}, 0,
                          MakePose(0, 0, 250.0 * i))),
              "");
  }
  const auto out = w.Step(Frame(1, kDt), kDt);
  ASSERT_EQ(out.barometer.size(), 5u);
  for (const auto& b : out.barometer) {
    const double z = b.pose.position.z();
    EXPECT_NEAR(b.data.altitude, z, 1.0) << z;  // pressure altitude vs geometric: 0.6 m apart at 1 km
    // ISA: p = 101325 (1 - 2.25577e-5 h)^5.25588.
    EXPECT_NEAR(b.data.pressure, 101325.0 * std::pow(1 - 2.25577e-5 * z, 5.25588), 5.0) << z;
    EXPECT_DOUBLE_EQ(b.data.qnh, 1013.25);
  }
  EXPECT_NEAR(StandardPressure(1000), 89874.6, 5);
}

TEST(Barometer, DefaultNoiseIsAirSims) {
  SensorWorld w(1);
  ASSERT_EQ(w.Add(Spawn(10, "sensor.other.barometer", {{"drift_pressure_factor_sigma", "0"}})), "");
  double sq = 0;
  for (int k = 1; k <= 1000; ++k) {
    const double p = w.Step(Frame(k, kDt), kDt).barometer.at(0).data.pressure - 101325.0;
    sq += p * p;
  }
  EXPECT_NEAR(std::sqrt(sq / 1000), 2.7, 0.2);
}

TEST(Magnetometer, DipoleFieldRotatesWithTheSensor) {
  SensorWorld w(1, GeoReference{47.637, -122.147, 0});
  ASSERT_EQ(w.Add(Spawn(10, "sensor.other.magnetometer", {{"noise_stddev", "0"}}, 0, MakePose(0, 0, 0, 0))), "");
  ASSERT_EQ(w.Add(Spawn(11, "sensor.other.magnetometer", {{"noise_stddev", "0"}}, 0, MakePose(0, 0, 0, M_PI / 2))), "");
  const auto out = w.Step(Frame(1, kDt), kDt);
  ASSERT_EQ(out.magnetometer.size(), 2u);
  const Vec3 east = out.magnetometer[0].data, north = out.magnetometer[1].data;
  // AirSim's dipole model at this point (EarthUtils comment): NED 2.50394e-05, 3.40771e-06, 3.6567e-05 T.
  EXPECT_NEAR(east.x(), 0.0340771, 2e-4);   // facing east: x = east component
  EXPECT_NEAR(east.y(), 0.250394, 2e-3);    // y (left) = north
  EXPECT_NEAR(east.z(), -0.36567, 2e-3);    // up = -down
  EXPECT_NEAR(north.x(), 0.250394, 2e-3);   // facing north: x = north component
  EXPECT_NEAR(north.y(), -0.0340771, 2e-4); // left = west
}

TEST(Distance, MeasuresToTheFirstHitAndPassesThroughItsParent) {
  SensorWorld w(1);
  w.scene().SetStatic({test::Wall(20)});
  ASSERT_EQ(w.Add(Spawn(10, "sensor.other.distance", {{"noise_stddev", "0"}}, 5, MakePose(0, 0, 0))), "");  // inside the car
  ASSERT_EQ(w.Add(Spawn(11, "sensor.other.distance", {{"noise_stddev", "0"}}, 0, MakePose(0, 5, 0, M_PI))), "");  // nothing behind
  const Actor car = MakeActor(5, ActorKind::kVehicle, "vehicle.lockstep.sedan", MakePose(2, 0, 0), Vec3(2.3, 1, 0.75));
  const auto out = w.Step(Frame(1, kDt, {car}), kDt);
  ASSERT_EQ(out.distance.size(), 2u);
  EXPECT_NEAR(out.distance[0].data.distance, 18.0, 1e-4);
  EXPECT_NEAR(out.distance[1].data.distance, 40.0, 1e-9);  // max_distance when nothing is hit
  EXPECT_DOUBLE_EQ(out.distance[1].data.min_distance, 0.2);
}

TEST(Obstacle, DetectsActorsAheadWithinTheHitRadius) {
  SensorWorld w(1);
  w.scene().SetStatic({test::Wall(4.5)});
  ASSERT_EQ(w.Add(Spawn(10, "sensor.other.obstacle", {{"distance", "20"}, {"only_dynamics", "true"}}, 5, MakePose(2.4, 0, 0))), "");
  ASSERT_EQ(w.Add(Spawn(11, "sensor.other.obstacle", {{"distance", "20"}}, 5, MakePose(2.4, 0, 0))), "");
  const Actor car = MakeActor(5, ActorKind::kVehicle, "vehicle.lockstep.sedan", MakePose(0, 0, 0), Vec3(2.3, 1, 0.75));
  // The walker stands behind the wall's plane but 0.4 m to the side of the ray: inside hit_radius.
  const Actor walker = MakeActor(6, ActorKind::kWalker, "walker.pedestrian.0001", MakePose(12, 0.4, 0), Vec3(0.25, 0.25, 0.9));
  const auto out = w.Step(Frame(1, kDt, {car, walker}), kDt);
  ASSERT_EQ(out.obstacle.size(), 2u);
  EXPECT_EQ(out.obstacle[0].data.other_actor, 6u);
  EXPECT_EQ(out.obstacle[0].data.other_kind, HitKind::kWalker);
  EXPECT_NEAR(out.obstacle[0].data.distance, 12 - 0.25 - 2.4, 1e-3);
  EXPECT_EQ(out.obstacle[1].data.other_actor, 0u);
  EXPECT_EQ(out.obstacle[1].data.other_kind, HitKind::kStatic);
  EXPECT_NEAR(out.obstacle[1].data.distance, 4.5 - 2.4, 1e-3);
  const auto none = w.Step(Frame(2, kDt, {car}), kDt);
  EXPECT_EQ(none.obstacle.size(), 1u) << "only the wall is left; the dynamic-only detector is silent";
}

TEST(EventSensors, DeliverTheirActorsEventsOnly) {
  SensorWorld w(1);
  ASSERT_EQ(w.Add(Spawn(10, "sensor.other.collision", {}, 5)), "");
  ASSERT_EQ(w.Add(Spawn(11, "sensor.other.lane_invasion", {}, 5)), "");
  const Actor car = MakeActor(5, ActorKind::kVehicle, "vehicle.lockstep.sedan", MakePose(0, 0, 0), Vec3(2.3, 1, 0.75));
  FrameEvents ev;
  ev.collisions.push_back({5, 9, HitKind::kVehicle, 14, Vec3(100, 0, 0), Vec3(1, 0, 0)});
  ev.collisions.push_back({9, 5, HitKind::kVehicle, 14, Vec3(-100, 0, 0), Vec3(1, 0, 0)});
  ev.lane_invasions.push_back({5, {LaneMarking{1, "white", 0.15f, false, false}}});
  ev.lane_invasions.push_back({7, {LaneMarking{2, "yellow", 0.15f, true, true}}});
  const auto out = w.Step(Frame(1, kDt, {car}), kDt, ev);
  ASSERT_EQ(out.collision.size(), 1u);
  EXPECT_EQ(out.collision[0].sensor, 10u);
  EXPECT_EQ(out.collision[0].data.event.other_actor, 9u);
  EXPECT_DOUBLE_EQ(out.collision[0].data.event.normal_impulse.x(), 100);
  ASSERT_EQ(out.lane_invasion.size(), 1u);
  EXPECT_EQ(out.lane_invasion[0].data.crossed.at(0).color, "white");
  EXPECT_EQ(w.Step(Frame(2, kDt, {car}), kDt).size(), 0u) << "no events, no samples";
}

// Like the render service's cameras (and CARLA's vehicle origin): a sensor attached to a
// vehicle or walker is placed relative to the bottom centre of its box, on a drone
// relative to its centre.
TEST(Mount, AttachedSensorsSitOnTheBottomOfVehiclesAndWalkersAndTheCentreOfDrones) {
  SensorWorld w(1);
  ASSERT_EQ(w.Add(Spawn(10, "sensor.other.imu", {}, 5, MakePose(1.5, 0, 2.4))), "");
  ASSERT_EQ(w.Add(Spawn(11, "sensor.other.gnss", {}, 6, MakePose(0, 0, 1.7))), "");
  ASSERT_EQ(w.Add(Spawn(12, "sensor.other.imu", {}, 7, MakePose(0, 0, -0.1))), "");
  ASSERT_EQ(w.Add(Spawn(13, "sensor.other.collision", {}, 5, MakePose(0, 0, 0))), "");
  const Actor car = MakeActor(5, ActorKind::kVehicle, "vehicle.lockstep.sedan", MakePose(10, 0, 0.8, M_PI / 2), Vec3(2.3, 1, 0.75));
  const Actor walker = MakeActor(6, ActorKind::kWalker, "walker.pedestrian.0001", MakePose(0, 3, 0.9), Vec3(0.25, 0.25, 0.9));
  const Actor drone = MakeActor(7, ActorKind::kDrone, "drone", MakePose(0, 0, 5), Vec3(0.3, 0.3, 0.1));
  FrameEvents ev;
  ev.collisions.push_back({5, 9, HitKind::kVehicle, 14, Vec3(100, 0, 0), Vec3(1, 0, 0)});
  const auto out = w.Step(Frame(1, kDt, {car, walker, drone}), kDt, ev);
  ASSERT_EQ(out.imu.size(), 2u);
  EXPECT_NEAR((out.imu[0].pose.position - Vec3(10, 1.5, 0.05 + 2.4)).norm(), 0, 1e-12) << "the car's box bottom is at 0.05";
  EXPECT_NEAR((out.imu[1].pose.position - Vec3(0, 0, 4.9)).norm(), 0, 1e-12);
  ASSERT_EQ(out.gnss.size(), 1u);
  EXPECT_NEAR((out.gnss[0].pose.position - Vec3(0, 3, 1.7)).norm(), 0, 1e-12);
  ASSERT_EQ(out.collision.size(), 1u);
  EXPECT_NEAR((out.collision[0].pose.position - Vec3(10, 0, 0.05)).norm(), 0, 1e-12);
}

// CARLA destroys only the parent; Unreal detaches its sensors keeping their world
// transform: they go on sampling where they were, standing still, unattached.
TEST(Mount, SensorsOfADestroyedParentStayWhereTheyWere) {
  SensorWorld w(1);
  ASSERT_EQ(w.Add(Spawn(10, "sensor.other.imu", {}, 5, MakePose(1.5, 0, 2.4))), "");
  ASSERT_EQ(w.Add(Spawn(11, "sensor.other.gnss", {}, 5, MakePose(0, 0, 1.7))), "");
  Actor car = MakeActor(5, ActorKind::kVehicle, "vehicle.lockstep.sedan", MakePose(10, 0, 0.8, M_PI / 2), Vec3(2.3, 1, 0.75));
  car.velocity = Vec3(0, 5, 0);
  auto out = w.Step(Frame(1, kDt, {car}), kDt);
  ASSERT_EQ(out.imu.size(), 1u);
  const Pose imu_pose = out.imu[0].pose;
  w.Remove(5);  // the car's own id: not a sensor
  w.Detach(5);
  for (int k = 2; k <= 3; ++k) {
    out = w.Step(Frame(k, kDt), kDt);  // the car is gone from the frame
    ASSERT_EQ(out.imu.size(), 1u) << "frame " << k;
    ASSERT_EQ(out.gnss.size(), 1u);
    EXPECT_EQ(out.imu[0].parent, 0u);
    EXPECT_NEAR((out.imu[0].pose.position - imu_pose.position).norm(), 0, 1e-12);
    EXPECT_NEAR((out.imu[0].pose.position - Vec3(10, 1.5, 0.05 + 2.4)).norm(), 0, 1e-12);
    EXPECT_NEAR(out.imu[0].pose.orientation.angularDistance(imu_pose.orientation), 0, 1e-12);
    EXPECT_NEAR((out.gnss[0].pose.position - Vec3(10, 0, 0.05 + 1.7)).norm(), 0, 1e-12);
  }
}

TEST(SensorTick, PointOneSecondAtDtPointZeroFiveSamplesEverySecondFrame) {
  for (const char* bp : {"sensor.other.imu", "sensor.lidar.ray_cast", "sensor.other.gnss"}) {
    SensorWorld w(1);
    w.scene().SetStatic({});
    ASSERT_EQ(w.Add(Spawn(10, bp, {{"sensor_tick", "0.1"}})), "");
    ASSERT_EQ(w.Add(Spawn(11, bp, {})), "");
    std::vector<int> sampled, every;
    for (int k = 1; k <= 200; ++k) {
      const auto out = w.Step(Frame(k, kDt), kDt);
      auto sensors = [&](auto& list) {
        for (const auto& s : list) (s.sensor == 10 ? sampled : every).push_back(k);
      };
      sensors(out.imu);
      sensors(out.point_clouds);
      sensors(out.gnss);
    }
    ASSERT_EQ(sampled.size(), 100u) << bp;
    for (size_t i = 0; i < sampled.size(); ++i) EXPECT_EQ(sampled[i], static_cast<int>(1 + 2 * i)) << bp;
    EXPECT_EQ(every.size(), 200u) << bp;
  }
}

TEST(SensorTick, NonMultipleTicksNeitherDriftNorDouble) {
  // sensor_tick 0.07 at dt 0.05: due at 0.05 + 0.07 n; sampled at the first frame at or after.
  SensorWorld w(1);
  ASSERT_EQ(w.Add(Spawn(10, "sensor.other.imu", {{"sensor_tick", "0.07"}})), "");
  int last = 0;
  double next_due = 0.05;
  for (int k = 1; k <= 400; ++k) {
    const double t = k * kDt;
    const bool sampled = !w.Step(Frame(k, kDt), kDt).imu.empty();
    const bool due = t + 1e-9 >= next_due;
    EXPECT_EQ(sampled, due) << "frame " << k;
    if (sampled) {
      while (next_due <= t + 1e-9) next_due += 0.07;
      EXPECT_GT(k, last);
      last = k;
    }
  }
}

std::vector<double> ImuStream(uint64_t run_seed, const char* noise_seed, uint32_t id = 10) {
  SensorWorld w(run_seed);
  std::map<std::string, std::string> attrs{{"noise_accel_stddev_x", "0.1"}, {"noise_gyro_stddev_z", "0.1"}};
  if (noise_seed) attrs["noise_seed"] = noise_seed;
  EXPECT_EQ(w.Add(Spawn(id, "sensor.other.imu", attrs)), "");
  std::vector<double> v;
  for (int k = 1; k <= 50; ++k) {
    const auto s = w.Step(Frame(k, kDt), kDt).imu.at(0).data;
    v.push_back(s.accelerometer.x());
    v.push_back(s.gyroscope.z());
  }
  return v;
}

TEST(Noise, StreamsAreIdenticalForTheSameSeedAndDifferForAnother) {
  EXPECT_EQ(ImuStream(42, "7"), ImuStream(42, "7"));
  EXPECT_NE(ImuStream(42, "7"), ImuStream(42, "8"));
  EXPECT_NE(ImuStream(42, nullptr), ImuStream(43, nullptr)) << "the run seed feeds the stream";
  EXPECT_NE(ImuStream(42, nullptr, 10), ImuStream(42, nullptr, 11)) << "so does the sensor id";
  // LiDAR noise as well.
  auto lidar = [](const char* seed) {
    SensorWorld w(1);
    w.scene().SetStatic({test::Wall(10)});
    EXPECT_EQ(w.Add(Spawn(10, "sensor.lidar.ray_cast", {{"noise_stddev", "0.1"}, {"noise_seed", seed}, {"range", "50"}})), "");
    return w.Step(Frame(1, kDt), kDt).point_clouds.at(0).data.data;
  };
  EXPECT_EQ(lidar("1"), lidar("1"));
  EXPECT_NE(lidar("1"), lidar("2"));
}

TEST(Attributes, BadValuesAreRejectedWithAReason) {
  SensorWorld w(1);
  EXPECT_NE(w.Add(Spawn(1, "sensor.lidar.ray_cast", {{"channels", "0"}})).find("'channels'"), std::string::npos);
  EXPECT_NE(w.Add(Spawn(1, "sensor.lidar.ray_cast", {{"range", "far"}})).find("finite number"), std::string::npos);
  EXPECT_NE(w.Add(Spawn(1, "sensor.lidar.ray_cast", {{"channels", "2.5"}})).find("integer"), std::string::npos);
  EXPECT_NE(w.Add(Spawn(1, "sensor.lidar.ray_cast_semantic", {{"noise_stddev", "1"}})).find("has no attribute 'noise_stddev'"),
            std::string::npos);
  EXPECT_NE(w.Add(Spawn(1, "sensor.lidar.ray_cast", {{"upper_fov", "-40"}})).find("upper_fov"), std::string::npos);
  EXPECT_NE(w.Add(Spawn(1, "sensor.other.obstacle", {{"only_dynamics", "maybe"}})).find("true or false"), std::string::npos);
  EXPECT_NE(w.Add(Spawn(1, "sensor.camera.rgb")).find("not a sensor blueprint"), std::string::npos);
  EXPECT_EQ(w.size(), 0u);
  EXPECT_EQ(w.Add(Spawn(1, "sensor.other.imu")), "");
  EXPECT_NE(w.Add(Spawn(1, "sensor.other.gnss")).find("exists already"), std::string::npos);
  EXPECT_EQ(CheckSensorSpawn(Spawn(2, "sensor.other.radar", {{"range", "-1"}})).find("'range'") != std::string::npos, true);
}

TEST(Blueprints, CarlaDefaults) {
  const auto* lidar = FindSensorBlueprint("sensor.lidar.ray_cast");
  ASSERT_NE(lidar, nullptr);
  Attributes a;
  ASSERT_EQ(ResolveAttributes(*lidar, {}, &a), "");
  EXPECT_EQ(a.Int("channels"), 32);
  EXPECT_DOUBLE_EQ(a.Float("range"), 10);
  EXPECT_EQ(a.Int("points_per_second"), 56000);
  EXPECT_DOUBLE_EQ(a.Float("rotation_frequency"), 10);
  EXPECT_DOUBLE_EQ(a.Float("upper_fov"), 10);
  EXPECT_DOUBLE_EQ(a.Float("lower_fov"), -30);
  EXPECT_DOUBLE_EQ(a.Float("horizontal_fov"), 360);
  EXPECT_DOUBLE_EQ(a.Float("atmosphere_attenuation_rate"), 0.004);
  EXPECT_DOUBLE_EQ(a.Float("dropoff_general_rate"), 0.45);
  EXPECT_DOUBLE_EQ(a.Float("dropoff_intensity_limit"), 0.8);
  EXPECT_DOUBLE_EQ(a.Float("dropoff_zero_intensity"), 0.4);
  EXPECT_DOUBLE_EQ(a.Float("noise_stddev"), 0);
  EXPECT_DOUBLE_EQ(a.Float("sensor_tick"), 0);
  const auto* radar = FindSensorBlueprint("sensor.other.radar");
  ASSERT_EQ(ResolveAttributes(*radar, {}, &a), "");
  EXPECT_DOUBLE_EQ(a.Float("horizontal_fov"), 30);
  EXPECT_DOUBLE_EQ(a.Float("range"), 100);
  EXPECT_EQ(a.Int("points_per_second"), 1500);
  const auto* obstacle = FindSensorBlueprint("sensor.other.obstacle");
  ASSERT_EQ(ResolveAttributes(*obstacle, {}, &a), "");
  EXPECT_DOUBLE_EQ(a.Float("distance"), 5);
  EXPECT_DOUBLE_EQ(a.Float("hit_radius"), 0.5);
  EXPECT_FALSE(a.Bool("only_dynamics"));
  EXPECT_EQ(SensorBlueprints().size(), 13u);  // with CARLA 0.9.16's sensor.other.v2x and v2x_custom
}

TEST(StateHash, ChangesWithTheSensorsState) {
  SensorWorld a(1), b(1);
  for (auto* w : {&a, &b}) {
    w->scene().SetStatic({test::Wall(10)});
    ASSERT_EQ(w->Add(Spawn(10, "sensor.lidar.ray_cast", {{"range", "50"}})), "");
  }
  EXPECT_EQ(a.StateHash(), b.StateHash());
  a.Step(Frame(1, kDt), kDt);
  EXPECT_NE(a.StateHash(), b.StateHash());
  b.Step(Frame(1, kDt), kDt);
  EXPECT_EQ(a.StateHash(), b.StateHash());
}

}  // namespace
}  // namespace lockstep::sensors
