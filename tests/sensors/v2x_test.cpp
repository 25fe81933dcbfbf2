// CARLA 0.9.16's V2X sensors (sensor.other.v2x, sensor.other.v2x_custom): CAM triggering,
// the CAM's fields, the path-loss model's states and numbers, custom messages, seeded
// fading; and the multi-hit ray trace they (and World.cast_ray) use.
#include <gtest/gtest.h>

#include <cmath>

#include "lockstep/sensors/v2x.h"
#include "scenes.h"

namespace lockstep::sensors {
namespace {

using test::Frame;
using test::MakeActor;
using test::Spawn;

constexpr double kDt = 0.05;
const Vec3 kCarHalf(2.25, 0.95, 0.75);

Actor Car(uint32_t id, double x, double y, double yaw = 0, Vec3 velocity = Vec3::Zero()) {
  Actor a = MakeActor(id, ActorKind::kVehicle, "vehicle.lincoln.mkz_2020", MakePose(x, y, kCarHalf.z(), yaw), kCarHalf);
  a.velocity = velocity;
  return a;
}

// No fading: the received power is the model's number.
const std::map<std::string, std::string> kNoFading{{"use_etsi_fading", "false"}, {"custom_fading_stddev", "0"}};

double WinnerLosHighway(double d) { return 32.4 + 20.0 * std::log10(d) + 20.0 * std::log10(5.9); }

TEST(RayScene, IntersectAllReportsEachObjectOnceNearestFirst) {
  RayScene scene;
  map::Mesh road;
  road.semantic_tag = map::semantic::kRoads;
  map::AddBox(road, Vec3(0, 0, 0.5), 200, 200, 1.0, 0);  // top face at z = 1.5
  scene.SetStatic({road, test::Wall(40)});
  scene.SetActors({MakeActor(7, ActorKind::kVehicle, "vehicle.lincoln.mkz_2020", MakePose(20, 0, 1.5 + 0.75), kCarHalf)});
  // Straight down onto the road: one point at its height, labelled Roads.
  auto down = scene.IntersectAll(Vec3(5, 3, 10), Vec3(5, 3, -10));
  ASSERT_GE(down.size(), 1u);
  EXPECT_NEAR(down[0].distance, 10 - 1.5, 1e-4);
  EXPECT_EQ(down[0].tag, map::semantic::kRoads);
  EXPECT_EQ(down.size(), 1u) << "the road's bottom face is the same object";
  // Along x at 1 m above the road: the car (entry face only), then the wall.
  auto along = scene.IntersectAll(Vec3(0, 0, 2.5), Vec3(100, 0, 2.5));
  ASSERT_EQ(along.size(), 2u);
  EXPECT_EQ(along[0].actor, 7u);
  EXPECT_EQ(along[0].tag, 14);  // Car
  EXPECT_NEAR(along[0].distance, 20 - kCarHalf.x(), 1e-4);
  EXPECT_EQ(along[1].tag, map::semantic::kBuilding);
  EXPECT_NEAR(along[1].distance, 40, 1e-4);
  EXPECT_TRUE(scene.IntersectAll(Vec3(0, 0, 2.5), Vec3(10, 0, 2.5)).empty());  // ends before the car
}

TEST(V2X, BlueprintsHaveCarlasAttributesAndDefaults) {
  const SensorBlueprint* cam = FindSensorBlueprint("sensor.other.v2x");
  const SensorBlueprint* custom = FindSensorBlueprint("sensor.other.v2x_custom");
  ASSERT_TRUE(cam && custom);
  Attributes a;
  ASSERT_EQ(ResolveAttributes(*cam, {}, &a), "");
  EXPECT_EQ(a.Float("transmit_power"), 21.5);
  EXPECT_EQ(a.Float("receiver_sensitivity"), -99.0);
  EXPECT_EQ(a.Float("frequency_ghz"), 5.9);
  EXPECT_EQ(a.Float("combined_antenna_gain"), 10.0);
  EXPECT_EQ(a.String("scenario"), "highway");
  EXPECT_EQ(a.String("path_loss_model"), "winner");
  EXPECT_EQ(a.Float("path_loss_exponent"), 2.7);
  EXPECT_EQ(a.Float("d_ref"), 1.0);
  EXPECT_EQ(a.Float("filter_distance"), 500.0);
  EXPECT_TRUE(a.Bool("use_etsi_fading"));
  EXPECT_EQ(a.Float("gen_cam_min"), 0.1);
  EXPECT_EQ(a.Float("gen_cam_max"), 1.0);
  EXPECT_FALSE(a.Bool("fixed_rate"));
  EXPECT_EQ(a.Float("noise_vel_stddev_x"), 0.0);
  EXPECT_NE(ResolveAttributes(*cam, {{"scenario", "city"}}, &a).find("expected one of highway, rural, urban"), std::string::npos);
  EXPECT_NE(ResolveAttributes(*custom, {{"gen_cam_min", "0.2"}}, &a).find("has no attribute 'gen_cam_min'"), std::string::npos);
  EXPECT_EQ(ResolveAttributes(*custom, {{"path_loss_model", "geometric"}}, &a), "");
}

TEST(V2X, CamsFollowTheTriggeringRules) {
  // A parked car sends every gen_cam_max (1 s); a car at 18 m/s each time it moved > 4 m
  // (every 5th step of 0.9 m), each received by the other.
  SensorWorld w(3);
  w.scene().SetStatic({});
  ASSERT_EQ(w.Add(Spawn(10, "sensor.other.v2x", {}, 1)), "");
  ASSERT_EQ(w.Add(Spawn(11, "sensor.other.v2x", {}, 2)), "");
  std::vector<int> parked_sent, moving_sent;  // steps at which the other received a CAM
  for (int k = 1; k <= 60; ++k) {
    const Actor moving = Car(1, 100 + 0.9 * k, 0, 0, Vec3(18, 0, 0));
    const Actor parked = Car(2, 80, 0);
    const auto out = w.Step(Frame(k, kDt, {moving, parked}), kDt);
    for (const auto& t : out.v2x) {
      ASSERT_EQ(t.data.size(), 1u);
      EXPECT_NE(t.data[0].sender, t.sensor) << "nobody receives itself";
      (t.sensor == 11 ? moving_sent : parked_sent).push_back(k);
      EXPECT_EQ(PayloadField(t.data[0].payload, kStationId), static_cast<int32_t>(t.sensor == 11 ? 1 : 2));
    }
  }
  EXPECT_EQ(parked_sent, (std::vector<int>{1, 21, 41}));
  // The moving car: its first CAM (position) leaves the speed of the last CAM at 0 (CARLA
  // evaluates the speed only when heading and position did not trigger), so the speed
  // triggers at gen_cam_min (step 3); T_GenCam = 0.1 s then repeats three times (steps 5,
  // 7, 9) before going back to gen_cam_max; from then on every 4.5 m (5 steps).
  EXPECT_EQ(moving_sent, (std::vector<int>{1, 3, 5, 7, 9, 14, 19, 24, 29, 34, 39, 44, 49, 54, 59}));
}

TEST(V2X, CamCarriesTheVehiclesState) {
  SensorWorld w(3);
  w.scene().SetStatic({});
  ASSERT_EQ(w.Add(Spawn(10, "sensor.other.v2x", {}, 1)), "");
  ASSERT_EQ(w.Add(Spawn(11, "sensor.other.v2x", {}, 2)), "");
  Actor north = Car(1, 100, 0, M_PI / 2, Vec3(0, 12.34, 0));  // facing north at 12.34 m/s
  north.light_state = 0x02 | 0x20;                             // low beam, left blinker
  const auto out = w.Step(Frame(1, kDt, {north, Car(2, 100, 30)}), kDt);
  const V2XMessage* got = nullptr;
  for (const auto& t : out.v2x) {
    if (t.sensor == 11) got = &t.data.at(0);
  }
  ASSERT_TRUE(got);
  const CamMessage cam = UnpackCam(got->payload);
  EXPECT_EQ(cam[kProtocolVersion], 2);
  EXPECT_EQ(cam[kMessageId], kMessageIdCam);
  EXPECT_EQ(cam[kStationId], 1);
  EXPECT_EQ(cam[kStationType], 5);  // passenger car
  EXPECT_EQ(cam[kHighFrequencyPresent], 1);
  EXPECT_EQ(cam[kHeadingValue], 0);  // north
  EXPECT_EQ(cam[kSpeedValue], 1234);
  EXPECT_EQ(cam[kDriveDirection], 0);
  EXPECT_EQ(cam[kVehicleLengthValue], 4500);  // CARLA's: centimetres times 10
  EXPECT_EQ(cam[kVerticalAccelerationValue], 98);  // gravity, 0.1 m/s^2
  EXPECT_EQ(cam[kLowFrequencyPresent], 1);
  EXPECT_EQ(cam[kExteriorLights], 128 | 32);
  EXPECT_EQ(cam[kGenerationDeltaTime], 50);
  EXPECT_EQ(cam[kAltitudeValue], 0);
  // Facing east: 90 degrees.
  SensorWorld w2(3);
  w2.scene().SetStatic({});
  ASSERT_EQ(w2.Add(Spawn(10, "sensor.other.v2x", {}, 1)), "");
  ASSERT_EQ(w2.Add(Spawn(11, "sensor.other.v2x", {}, 2)), "");
  const auto east = w2.Step(Frame(1, kDt, {Car(1, 100, 0, 0), Car(2, 100, 30)}), kDt);
  for (const auto& t : east.v2x) {
    if (t.sensor == 11) {
      EXPECT_EQ(PayloadField(t.data.at(0).payload, kHeadingValue), 900);
    }
  }
}

TEST(V2X, PathLossStatesAndPowers) {
  Attributes a;
  ASSERT_EQ(ResolveAttributes(*FindSensorBlueprint("sensor.other.v2x"), kNoFading, &a), "");
  PathLoss model(a);
  RayScene scene;
  scene.SetStatic({test::Wall(150)});
  Rng rng(1);
  const Actor rx = Car(1, 0, 0), tx = Car(2, 100, 0);
  WorldFrame f = Frame(1, kDt, {rx, tx});
  scene.SetActors(f.actors);
  PathState state;
  auto p = model.Receive(scene, rx, tx, 21.5, f, rng, &state);
  ASSERT_TRUE(p);
  EXPECT_EQ(state, PathState::kLos);
  EXPECT_NEAR(*p, 21.5 + 10.0 - WinnerLosHighway(100.0), 1e-3);
  // A wall between them: NLOSb, WINNER's 36.85 + 30 log10 d + 18.9 log10 f.
  const Actor behind = Car(3, 200, 0);
  f = Frame(1, kDt, {rx, behind});
  scene.SetActors(f.actors);
  p = model.Receive(scene, rx, behind, 21.5, f, rng, &state);
  ASSERT_TRUE(p);
  EXPECT_EQ(state, PathState::kNlosBuilding);
  EXPECT_NEAR(*p, 21.5 + 10.0 - (36.85 + 30.0 * std::log10(200.0) + 18.9 * std::log10(5.9)), 1e-3);
  // A truck in between: NLOSv, the LOS loss plus its knife edge.
  Actor truck = MakeActor(4, ActorKind::kVehicle, "vehicle.carlamotors.firetruck", MakePose(50, 0, 2.0), Vec3(4, 1.3, 2.0));
  f = Frame(1, kDt, {rx, tx, truck});
  scene.SetActors(f.actors);
  p = model.Receive(scene, rx, tx, 21.5, f, rng, &state);
  ASSERT_TRUE(p);
  EXPECT_EQ(state, PathState::kNlosVehicle);
  const double knife = model.KnifeEdge(50, 50, 4.0 + 0.02);
  EXPECT_GT(knife, 6.9);
  EXPECT_NEAR(*p, 21.5 + 10.0 - WinnerLosHighway(100.0) - knife, 1e-3);
  // A pedestrian in between is not traced (CARLA traces no pawns).
  Actor walker = MakeActor(5, ActorKind::kWalker, "walker.pedestrian.0001", MakePose(50, 0, 0.9), Vec3(0.3, 0.3, 2.0));
  f = Frame(1, kDt, {rx, tx, walker});
  scene.SetActors(f.actors);
  ASSERT_TRUE(model.Receive(scene, rx, tx, 21.5, f, rng, &state));
  EXPECT_EQ(state, PathState::kLos);
  // Beyond filter_distance, or below the sensitivity: nothing.
  const Actor far = Car(6, -600, 0);
  f = Frame(1, kDt, {rx, far});
  scene.SetActors(f.actors);
  EXPECT_FALSE(model.Receive(scene, rx, far, 21.5, f, rng));
  auto deaf_attrs = kNoFading;
  deaf_attrs["receiver_sensitivity"] = "-50";
  ASSERT_EQ(ResolveAttributes(*FindSensorBlueprint("sensor.other.v2x"), deaf_attrs, &a), "");
  PathLoss deaf(a);
  f = Frame(1, kDt, {rx, tx});
  scene.SetActors(f.actors);
  EXPECT_FALSE(deaf.Receive(scene, rx, tx, 21.5, f, rng));
}

TEST(V2X, GeometricModelUsesTwoRayInLineOfSight) {
  auto attrs = kNoFading;
  attrs["path_loss_model"] = "geometric";
  Attributes a;
  ASSERT_EQ(ResolveAttributes(*FindSensorBlueprint("sensor.other.v2x"), attrs, &a), "");
  PathLoss model(a);
  // Two-ray at 100 m, both antennas 1.52 m up: the direct and the ground-reflected paths.
  const double d = 100, h = 1.52, lambda = 299792458.0 / 5.9e9;
  const double refl = std::sqrt(d * d + 4 * h * h), sin_t = 2 * h / refl, cos_t = d / refl;
  const double root = std::sqrt(1.02 - cos_t * cos_t), g = (sin_t - root) / (sin_t + root), phi = 2 * M_PI / lambda * (d - refl);
  const double expected = 20 * std::log10(4 * M_PI * d / lambda / std::sqrt(std::pow(1 + g * std::cos(phi), 2) + g * g * std::pow(std::sin(phi), 2)));
  EXPECT_NEAR(model.PathLossDb(PathState::kLos, d, h, h, 0), expected, 1e-9);
  // NLOSb: log-distance from the free-space loss at d_ref (1 m) with exponent 2.7.
  EXPECT_NEAR(model.PathLossDb(PathState::kNlosBuilding, d, h, h, 0),
              20 * std::log10(4 * M_PI / lambda) + 10 * 2.7 * std::log10(d), 1e-9);
}

TEST(V2X, FadingIsSeededPerSensorAndDrawnInOrder) {
  auto run = [](uint64_t run_seed, const std::string& noise_seed) {
    SensorWorld w(run_seed);
    w.scene().SetStatic({});
    EXPECT_EQ(w.Add(Spawn(10, "sensor.other.v2x", {{"noise_seed", noise_seed}, {"fixed_rate", "true"}, {"gen_cam_min", "0"}}, 1)), "");
    EXPECT_EQ(w.Add(Spawn(11, "sensor.other.v2x", {{"noise_seed", noise_seed}, {"fixed_rate", "true"}, {"gen_cam_min", "0"}}, 2)), "");
    std::vector<float> powers;
    for (int k = 1; k <= 10; ++k) {
      for (const auto& t : w.Step(Frame(k, kDt, {Car(1, 0, 0), Car(2, 60, 0)}), kDt).v2x) powers.push_back(t.data.at(0).power_dbm);
    }
    return powers;
  };
  const auto a = run(5, "0"), b = run(5, "0"), c = run(5, "7");
  ASSERT_EQ(a.size(), 20u);  // fixed_rate: a CAM every step, both ways
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
  float lo = a[0], hi = a[0];
  for (float p : a) lo = std::min(lo, p), hi = std::max(hi, p);
  EXPECT_GT(hi - lo, 1.0f) << "ETSI fading (highway LOS: 3.3 dB) varies the power";
}

TEST(V2X, CustomMessagesGoOutOnceToTheOtherCustomSensors) {
  SensorWorld w(2);
  w.scene().SetStatic({});
  ASSERT_EQ(w.Add(Spawn(10, "sensor.other.v2x_custom", kNoFading, 1)), "");
  ASSERT_EQ(w.Add(Spawn(11, "sensor.other.v2x_custom", kNoFading, 2)), "");
  ASSERT_EQ(w.Add(Spawn(12, "sensor.other.v2x", {}, 2)), "");
  EXPECT_NE(w.V2XSend(12, "x").find("not a sensor.other.v2x_custom"), std::string::npos);
  EXPECT_NE(w.V2XSend(99, "x").find("not simulated here"), std::string::npos);
  ASSERT_EQ(w.V2XSend(10, "first"), "");
  ASSERT_EQ(w.V2XSend(10, "hello from 1"), "");  // the last text before the step goes out
  const std::vector<Actor> cars{Car(1, 0, 0), Car(2, 40, 0)};
  auto out = w.Step(Frame(1, kDt, cars), kDt);
  ASSERT_EQ(out.v2x.size(), 1u);
  EXPECT_EQ(out.v2x[0].sensor, 11u);
  ASSERT_EQ(out.v2x[0].data.size(), 1u);
  const V2XMessage& m = out.v2x[0].data[0];
  EXPECT_EQ(m.sender, 10u);
  EXPECT_EQ(CustomText(m.payload), "hello from 1");
  EXPECT_EQ(PayloadField(m.payload, kMessageId), kMessageIdCustom);
  EXPECT_EQ(PayloadField(m.payload, kStationId), 1);
  EXPECT_NEAR(m.power_dbm, 21.5 + 10.0 - WinnerLosHighway(40.0), 1e-3);
  // Sent once: the next steps carry nothing (the CAM sensor on car 2 hears no custom text).
  for (int k = 2; k <= 4; ++k) {
    for (const auto& t : w.Step(Frame(k, kDt, cars), kDt).v2x) EXPECT_NE(t.sensor, 11u);
  }
}

}  // namespace
}  // namespace lockstep::sensors
