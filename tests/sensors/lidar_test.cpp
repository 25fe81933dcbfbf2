// LiDAR: ranges, per-tick slices, points per rotation, drop-off, semantic classes, and
// actors (cars, walkers, drones) as moving instances.
#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "scenes.h"

namespace lockstep::sensors {
namespace {

using test::Frame;
using test::MakeActor;
using test::Spawn;

constexpr double kDt = 0.05;

TEST(Lidar, RangesToAWallMatchWithinTheNoise) {
  for (double noise : {0.0, 0.05}) {
    SensorWorld w(1);
    w.scene().SetStatic({test::Wall(12.0)});
    ASSERT_EQ(w.Add(Spawn(10, "sensor.lidar.ray_cast",
                          {{"range", "100"}, {"noise_stddev", std::to_string(noise)}, {"dropoff_general_rate", "0"},
                           {"upper_fov", "5"}, {"lower_fov", "-5"}, {"channels", "8"}},
                          0, MakePose(0, 0, 1))),
              "");
    size_t points = 0;
    double error_sq = 0;
    for (int k = 1; k <= 2; ++k) {
      const auto out = w.Step(Frame(k, kDt), kDt);
      ASSERT_EQ(out.point_clouds.size(), 1u);
      const auto& pc = out.point_clouds[0].data;
      for (size_t i = 0; i < pc.point_count; ++i) {
        const Vec3 p = pc.Point(i);
        ASSERT_GT(p.x(), 0) << "only the wall ahead can return";
        // Noise moves the point along its ray: x = 12 + dir.x * n, |n| < 5 sigma.
        EXPECT_NEAR(p.x(), 12.0, noise > 0 ? 5 * noise : 1e-3) << "point " << i;
        const double along = (p.x() - 12.0) / (p.x() / p.norm());  // the noise along the ray
        error_sq += along * along;
        const double d = std::hypot(12.0, std::hypot(p.y(), p.z() - 0));
        // CARLA: intensity from the distance before the noise.
        if (noise == 0) {
          EXPECT_NEAR(pc.Intensity(i), std::exp(-0.004 * p.norm()), 1e-5);
        }
        (void)d;
        ++points;
      }
    }
    EXPECT_GT(points, 500u);
    EXPECT_NEAR(std::sqrt(error_sq / points), noise, noise > 0 ? 0.1 * noise : 1e-4) << "the noise has noise_stddev";
  }
}

TEST(Lidar, PointsPerRotationEqualPointsPerSecondOverFrequencyWithinOneColumn) {
  struct Case {
    int channels;
    int pps;
    double frequency;
  };
  for (const Case c : {Case{32, 56000, 10}, Case{64, 100000, 20}, Case{16, 30000, 5}, Case{1, 1000, 10}}) {
    SensorWorld w(1);
    w.scene().SetStatic(test::Room(20));
    ASSERT_EQ(w.Add(Spawn(10, "sensor.lidar.ray_cast",
                          {{"channels", std::to_string(c.channels)}, {"points_per_second", std::to_string(c.pps)},
                           {"rotation_frequency", std::to_string(c.frequency)}, {"range", "100"}, {"dropoff_general_rate", "0"},
                           {"dropoff_intensity_limit", "0"}})),
              "");
    const int ticks = static_cast<int>(std::lround(1.0 / (c.frequency * kDt)));
    size_t total = 0;
    for (int k = 1; k <= ticks; ++k) {
      const auto pc = w.Step(Frame(k, kDt), kDt).point_clouds.at(0).data;
      size_t sum = 0;
      for (auto n : pc.points_per_channel) sum += n;
      EXPECT_EQ(sum, pc.point_count);
      ASSERT_EQ(pc.points_per_channel.size(), static_cast<size_t>(c.channels));
      // Every channel sweeps the same slice: CARLA rounds pps * dt / channels half away from zero.
      for (auto n : pc.points_per_channel) EXPECT_EQ(n, static_cast<uint32_t>(std::lround(c.pps * kDt / c.channels)));
      total += pc.point_count;
    }
    const double expected = c.pps / c.frequency;
    EXPECT_LE(std::abs(static_cast<double>(total) - expected), c.channels) << c.channels << " channels, " << c.pps << " pps";
  }
}

TEST(Lidar, EachTickEmitsTheSliceSweptDuringIt) {
  // 10 Hz at dt 0.05: the first tick sweeps CARLA's yaw [-180, 0) (left half in FLU),
  // the second [0, 180) (right half); together one full turn, no overlap.
  SensorWorld w(1);
  w.scene().SetStatic(test::Room(20));
  ASSERT_EQ(w.Add(Spawn(10, "sensor.lidar.ray_cast", {{"range", "100"}, {"dropoff_general_rate", "0"}, {"dropoff_intensity_limit", "0"}})), "");
  for (int turn = 0; turn < 3; ++turn) {
    for (int half = 0; half < 2; ++half) {
      const int k = 2 * turn + half + 1;
      const auto pc = w.Step(Frame(k, kDt), kDt).point_clouds.at(0).data;
      ASSERT_GT(pc.point_count, 0u);
      double min_az = 10, max_az = -10;
      for (size_t i = 0; i < pc.point_count; ++i) {
        const Vec3 p = pc.Point(i);
        const double az = std::atan2(p.y(), p.x());
        min_az = std::min(min_az, az);
        max_az = std::max(max_az, az);
        if (half == 0) {
          EXPECT_GE(p.y(), -1e-3) << "tick " << k;
        } else {
          EXPECT_LE(p.y(), 1e-3) << "tick " << k;
        }
      }
      // The slice spans (almost) its whole half turn.
      EXPECT_GT(max_az - min_az, M_PI * 0.97) << "tick " << k;
    }
  }
}

TEST(Lidar, SliceFollowsElapsedTimeWithSensorTick) {
  // sensor_tick 0.1 at dt 0.05: each sample covers 0.1 s of rotation (a full turn at 10 Hz).
  SensorWorld w(1);
  w.scene().SetStatic(test::Room(20));
  ASSERT_EQ(w.Add(Spawn(10, "sensor.lidar.ray_cast",
                        {{"range", "100"}, {"dropoff_general_rate", "0"}, {"dropoff_intensity_limit", "0"}, {"sensor_tick", "0.1"}})),
            "");
  w.Step(Frame(1, kDt), kDt);  // the first sample covers one step
  w.Step(Frame(2, kDt), kDt);
  const auto out = w.Step(Frame(3, kDt), kDt);
  ASSERT_EQ(out.point_clouds.size(), 1u);
  EXPECT_EQ(out.point_clouds[0].data.point_count, 32u * 175u);  // round(56000 * 0.1 / 32) = 175
}

TEST(Lidar, GeneralDropOffRemovesTheConfiguredShare) {
  SensorWorld w(3);
  w.scene().SetStatic(test::Room(20));
  ASSERT_EQ(w.Add(Spawn(10, "sensor.lidar.ray_cast", {{"range", "100"}, {"dropoff_intensity_limit", "0"}})), "");  // rate 0.45
  size_t total = 0;
  for (int k = 1; k <= 20; ++k) total += w.Step(Frame(k, kDt), kDt).point_clouds.at(0).data.point_count;
  const double kept = static_cast<double>(total) / (20 * 32 * 88);
  EXPECT_NEAR(kept, 0.55, 0.02);
}

TEST(Lidar, IntensityDropOffFollowsCarla) {
  // Intensity exp(-0.004 d) at 30 m = 0.887 > 0.8: always kept. With limit 1 every point
  // is below it and kept with CARLA's probability 0.4 / 1 * I + (1 - 0.4) (about 0.955 here).
  for (const char* limit : {"0.8", "1"}) {
    SensorWorld w(5);
    w.scene().SetStatic({test::Wall(30)});
    ASSERT_EQ(w.Add(Spawn(10, "sensor.lidar.ray_cast",
                          {{"range", "100"}, {"dropoff_general_rate", "0"}, {"dropoff_intensity_limit", limit},
                           {"upper_fov", "1"}, {"lower_fov", "-1"}, {"horizontal_fov", "20"}})),
              "");
    size_t total = 0;
    for (int k = 1; k <= 40; ++k) total += w.Step(Frame(k, kDt), kDt).point_clouds.at(0).data.point_count;
    const double rays = 40.0 * 32 * 88;
    if (std::string(limit) == "0.8") {
      EXPECT_EQ(total, static_cast<size_t>(rays));
    } else {
      const double i30 = std::exp(-0.004 * 30.0);  // near the axis; off-axis rays are a bit longer
      EXPECT_NEAR(total / rays, 0.4 * i30 + 0.6, 0.01);
    }
  }
}

// CARLA's RayCastLidar: a point of intensity I at or below dropoff_intensity_limit is kept
// with probability (dropoff_zero_intensity / limit) I + (1 - dropoff_zero_intensity): an
// intensity of 0 is dropped with probability dropoff_zero_intensity, one at the limit
// always kept. Here I = 0.5 (attenuation 0.1 / m at ln 2 / 0.1 m), limit 1, zero 0.8:
// kept 0.8 * 0.5 + 0.2 = 0.6 (the inverted model would keep 0.2 * 0.5 + 0.8 = 0.9).
TEST(Lidar, IntensityDropOffKeepsZeroOverLimitTimesIntensityPlusOneMinusZero) {
  const double d = std::log(2.0) / 0.1;
  SensorWorld w(11);
  w.scene().SetStatic({test::Wall(d)});
  ASSERT_EQ(w.Add(Spawn(10, "sensor.lidar.ray_cast",
                        {{"range", "100"}, {"dropoff_general_rate", "0"}, {"dropoff_intensity_limit", "1"},
                         {"dropoff_zero_intensity", "0.8"}, {"atmosphere_attenuation_rate", "0.1"}, {"channels", "1"},
                         {"upper_fov", "0"}, {"lower_fov", "0"}, {"horizontal_fov", "2"}, {"points_per_second", "200000"}})),
            "");
  size_t kept = 0, rays = 0;
  double intensity_sum = 0;
  for (int k = 1; k <= 20; ++k) {
    const auto pc = w.Step(Frame(k, kDt), kDt).point_clouds.at(0).data;
    kept += pc.point_count;
    rays += 10000;  // round(200000 * 0.05 / 1)
    for (size_t i = 0; i < pc.point_count; ++i) intensity_sum += pc.Intensity(i);
  }
  ASSERT_GT(kept, 0u);
  const double mean_i = intensity_sum / kept;
  EXPECT_NEAR(mean_i, 0.5, 1e-4) << "the rays hit the wall at ln 2 / 0.1 m (within 1 deg of the axis)";
  // 200000 rays: the kept share's standard deviation is 0.0011.
  EXPECT_NEAR(static_cast<double>(kept) / rays, 0.8 / 1.0 * mean_i + (1 - 0.8), 0.006);
}

// dropoff_general_rate: CARLA drops each ray before it is cast when U[0, 1) < the rate.
TEST(Lidar, GeneralDropOffKeepsOneMinusTheRate) {
  for (double rate : {0.0, 0.2, 0.9}) {
    SensorWorld w(12);
    w.scene().SetStatic(test::Room(20));
    ASSERT_EQ(w.Add(Spawn(10, "sensor.lidar.ray_cast",
                          {{"range", "100"}, {"dropoff_general_rate", std::to_string(rate)}, {"dropoff_intensity_limit", "0"}})),
              "");
    size_t total = 0;
    for (int k = 1; k <= 20; ++k) total += w.Step(Frame(k, kDt), kDt).point_clouds.at(0).data.point_count;
    EXPECT_NEAR(static_cast<double>(total) / (20 * 32 * 88), 1 - rate, rate == 0 ? 0 : 0.01) << "rate " << rate;
  }
}

TEST(Lidar, RainAttenuatesReturns) {
  SensorWorld w(5);
  w.set_weather(Weather{100.0, 0});
  w.scene().SetStatic({test::Wall(40)});
  ASSERT_EQ(w.Add(Spawn(10, "sensor.lidar.ray_cast",
                        {{"range", "100"}, {"dropoff_general_rate", "0"}, {"upper_fov", "1"}, {"lower_fov", "-1"}, {"horizontal_fov", "20"}})),
            "");
  float max_i = 0;
  const auto pc = w.Step(Frame(1, kDt), kDt).point_clouds.at(0).data;
  for (size_t i = 0; i < pc.point_count; ++i) max_i = std::max(max_i, pc.Intensity(i));
  EXPECT_NEAR(max_i, std::exp(-(0.004 + 0.01) * 40), 1e-4);  // full rain adds 0.01 / m
}

TEST(Lidar, FogAttenuatesReturns) {
  size_t counts[2];
  for (int fog = 0; fog < 2; ++fog) {
    SensorWorld w(5);
    w.set_weather(Weather{0, fog ? 100.0 : 0.0});
    w.scene().SetStatic({test::Wall(40)});
    ASSERT_EQ(w.Add(Spawn(10, "sensor.lidar.ray_cast",
                          {{"range", "100"}, {"dropoff_general_rate", "0"}, {"upper_fov", "1"}, {"lower_fov", "-1"}, {"horizontal_fov", "20"}})),
              "");
    counts[fog] = 0;
    float max_i = 0;
    for (int k = 1; k <= 10; ++k) {
      const auto pc = w.Step(Frame(k, kDt), kDt).point_clouds.at(0).data;
      counts[fog] += pc.point_count;
      for (size_t i = 0; i < pc.point_count; ++i) max_i = std::max(max_i, pc.Intensity(i));
    }
    if (fog) {
      EXPECT_NEAR(max_i, std::exp(-(0.004 + 0.03) * 40), 1e-4);  // full fog adds 0.03 / m
    }
  }
  // Without fog every return (I = 0.85) is above the 0.8 limit; with it I = exp(-0.034 * 40)
  // = 0.257 and CARLA's drop-off keeps 0.4 / 0.8 * I + 0.6 of them.
  EXPECT_NEAR(static_cast<double>(counts[1]) / counts[0], 0.5 * std::exp(-0.034 * 40) + 0.6, 0.01);
}

TEST(SemanticLidar, ClassesAndObjectsAtKnownHits) {
  SensorWorld w(1);
  map::Mesh road;
  road.semantic_tag = map::semantic::kRoads;
  road.instance_id = 3;
  road.AddQuad({-100, -100, 0}, {100, -100, 0}, {100, 100, 0}, {-100, 100, 0}, {0, 0, 1});
  w.scene().SetStatic({road, test::Wall(15)});
  const Actor car = MakeActor(42, ActorKind::kVehicle, "vehicle.lockstep.sedan", MakePose(0, 8, 0.75, M_PI / 2), Vec3(2.3, 1, 0.75));
  ASSERT_EQ(w.Add(Spawn(10, "sensor.lidar.ray_cast_semantic", {{"range", "50"}}, 0, MakePose(0, 0, 1))), "");
  std::set<uint32_t> tags;
  size_t car_points = 0;
  for (int k = 1; k <= 2; ++k) {
    const auto out = w.Step(Frame(k, kDt, {car}), kDt);
    const auto& pc = out.point_clouds.at(0).data;
    ASSERT_TRUE(pc.semantic);
    ASSERT_EQ(pc.point_step, 24u);
    for (size_t i = 0; i < pc.point_count; ++i) {
      const Vec3 p = pc.Point(i) + Vec3(0, 0, 1);  // world (the sensor is not rotated)
      tags.insert(pc.Tag(i));
      EXPECT_GE(pc.CosIncidence(i), 0.f);
      EXPECT_LE(pc.CosIncidence(i), 1.f + 1e-5f);
      if (std::abs(p.z()) < 1e-3) {
        EXPECT_EQ(pc.Tag(i), map::semantic::kRoads) << p.transpose();
        EXPECT_EQ(pc.Object(i), 0u);  // static geometry: no actor (as CARLA)
        // Ground hit straight below-ish: cos incidence = sensor height / distance.
        EXPECT_NEAR(pc.CosIncidence(i), 1.0 / pc.Point(i).norm(), 1e-3);
      } else if (std::abs(p.x() - 15) < 1e-3) {
        EXPECT_EQ(pc.Tag(i), map::semantic::kBuilding);
      } else {
        EXPECT_EQ(pc.Tag(i), 14u) << p.transpose();  // Car
        EXPECT_EQ(pc.Object(i), 42u);
        EXPECT_NEAR(p.y(), 8 - 2.3, 1e-3) << "the car's near side (it faces north)";
        ++car_points;
      }
    }
  }
  EXPECT_GT(car_points, 10u);
  EXPECT_EQ(tags, (std::set<uint32_t>{map::semantic::kRoads, map::semantic::kBuilding, 14}));
}

TEST(Lidar, SeesADroneAndAWalkerAndFollowsThemEachTick) {
  SensorWorld w(1);
  w.scene().SetStatic({});
  ASSERT_EQ(w.Add(Spawn(10, "sensor.lidar.ray_cast_semantic", {{"range", "60"}, {"upper_fov", "30"}, {"lower_fov", "-30"}, {"channels", "64"},
                                                               {"points_per_second", "500000"}})),
            "");
  ASSERT_EQ(w.Add(Spawn(11, "sensor.lidar.ray_cast", {{"range", "60"}, {"upper_fov", "30"}, {"lower_fov", "-30"}, {"channels", "64"},
                                                      {"points_per_second", "500000"}, {"dropoff_general_rate", "0"}})),
            "");
  for (double shift : {0.0, 3.0}) {  // actors move: their instances follow
    const Actor drone = MakeActor(7, ActorKind::kDrone, "drone.generic_quad", MakePose(6 + shift, 0, 3), Vec3(0.3, 0.3, 0.1));
    const Actor walker = MakeActor(8, ActorKind::kWalker, "walker.pedestrian.0001", MakePose(-5 - shift, 2, 0), Vec3(0.25, 0.25, 0.9));
    std::map<uint32_t, size_t> by_object;
    size_t xyzi_near_drone = 0, xyzi_near_walker = 0;
    for (int k = 1; k <= 2; ++k) {
      const auto out = w.Step(Frame(k, kDt, {drone, walker}), kDt);
      for (const auto& pcs : out.point_clouds) {
        const auto& pc = pcs.data;
        for (size_t i = 0; i < pc.point_count; ++i) {
          const Vec3 p = pc.Point(i);
          if (pc.semantic) {
            ++by_object[pc.Object(i)];
            if (pc.Object(i) == 7) {
              EXPECT_EQ(pc.Tag(i), 21u);
            }
            if (pc.Object(i) == 8) {
              EXPECT_EQ(pc.Tag(i), 12u);
            }
          } else {
            if ((p - drone.pose.position).cwiseAbs().maxCoeff() < 0.31) ++xyzi_near_drone;
            if ((p - walker.pose.position).cwiseAbs().maxCoeff() < 0.91) ++xyzi_near_walker;
          }
        }
      }
    }
    EXPECT_GT(by_object[7], 0u) << "drone at shift " << shift;
    EXPECT_GT(by_object[8], 0u) << "walker at shift " << shift;
    EXPECT_GT(xyzi_near_drone, 0u);
    EXPECT_GT(xyzi_near_walker, 0u);
  }
  EXPECT_EQ(w.scene().actor_count(), 2u);
  w.Step(Frame(3, kDt, {}), kDt);
  EXPECT_EQ(w.scene().actor_count(), 0u) << "actors that left the frame leave the scene";
}

TEST(Lidar, AttachedToAMovingCarScansFromItsPose) {
  SensorWorld w(1);
  w.scene().SetStatic({test::Wall(30)});
  ASSERT_EQ(w.Add(Spawn(10, "sensor.lidar.ray_cast",
                        {{"range", "100"}, {"dropoff_general_rate", "0"}, {"upper_fov", "0"}, {"lower_fov", "0"}, {"channels", "1"},
                         {"horizontal_fov", "10"}},
                        5, MakePose(1, 0, 1.5))),
            "");
  for (int k = 1; k <= 5; ++k) {
    const double x = 2.0 * k;
    const Actor car = MakeActor(5, ActorKind::kVehicle, "vehicle.lockstep.sedan", MakePose(x, 0, 0.7), Vec3(2, 1, 0.7));
    const auto out = w.Step(Frame(k, kDt, {car}), kDt);
    const auto& pc = out.point_clouds.at(0).data;
    ASSERT_GT(pc.point_count, 0u);
    for (size_t i = 0; i < pc.point_count; ++i) EXPECT_NEAR(pc.Point(i).x(), 30 - (x + 1), 1e-3);
    EXPECT_NEAR(out.point_clouds[0].pose.position.x(), x + 1, 1e-9);
  }
}

}  // namespace
}  // namespace lockstep::sensors
