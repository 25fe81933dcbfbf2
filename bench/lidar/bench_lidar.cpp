// bench_lidar: ray-cast LiDAR throughput on one core, in CARLA's Town01 (the map layer's
// meshes, the ones the renderer draws) with 100 vehicles and 50 walkers moving.
//
// The actors' motion is synthesized here (vehicles follow their lanes at 8 m/s, walkers
// pace back and forth at 1.4 m/s): the bench measures the sensors core, not ground_sim.
// A frame = moving every actor's Embree instance (top-level rebuild only) + casting the
// LiDAR's slice + building its point cloud. Prints JSON lines; the last one is the summary:
//   {"bench":"lidar","channels":32,"points_per_frame":56000,"triangles":..,"actors":150,"frame_ms":..,"mpoints_per_s":..}
// Usage: bench_lidar [--quick]
#include <algorithm>
#include <chrono>
#include <ctime>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "lockstep/map/map.h"
#include "lockstep/map/scene.h"
#include "lockstep/map/scene_mesh.h"
#include "lockstep/sensors/sensor_world.h"

using namespace lockstep;
using namespace lockstep::sensors;

namespace {

constexpr double kDt = 0.05;

double Now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }
// CPU time of this thread: the machine is shared, and "per frame on one core" is what
// the thread itself spends, not the wall time other processes stretch.
double CpuNow() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

struct Traffic {
  const map::Map* town;
  std::vector<map::Waypoint> cars;
  std::vector<map::Transform> walker_start;
  std::vector<Actor> actors;

  Traffic(const map::Map& m, size_t vehicles, size_t walkers) : town(&m) {
    const auto wps = m.GenerateWaypoints(12.0);
    for (size_t i = 0; i < vehicles && i < wps.size(); ++i) cars.push_back(wps[(i * 7919) % wps.size()]);
    const auto sidewalk = m.PedestrianSpawnPoints(10.0);
    for (size_t i = 0; i < walkers && i < sidewalk.size(); ++i) walker_start.push_back(sidewalk[(i * 104729) % sidewalk.size()]);
  }

  // The actors of frame k.
  void Advance(int k) {
    actors.clear();
    uint32_t id = 1;
    for (auto& wp : cars) {
      if (k > 0) {
        auto next = town->Next(wp, 8.0 * kDt);
        if (!next.empty()) wp = next.front();
      }
      Actor a;
      a.id = id++;
      a.kind = ActorKind::kVehicle;
      a.blueprint = "vehicle.lockstep.sedan";
      const auto& t = wp.transform;
      a.pose = MakePose(t.location.x(), t.location.y(), t.location.z() + 0.75, t.yaw);
      a.half_extents = Vec3(2.3, 1.0, 0.75);
      a.velocity = Vec3(8 * std::cos(t.yaw), 8 * std::sin(t.yaw), 0);
      actors.push_back(a);
    }
    for (size_t i = 0; i < walker_start.size(); ++i) {
      const auto& t = walker_start[i];
      const double s = 1.4 * 4.0 * std::sin(k * kDt / 4.0 + static_cast<double>(i));  // back and forth along the sidewalk
      Actor a;
      a.id = id++;
      a.kind = ActorKind::kWalker;
      a.blueprint = "walker.pedestrian.0001";
      a.pose = MakePose(t.location.x() + s * std::cos(t.yaw), t.location.y() + s * std::sin(t.yaw), t.location.z() + 0.9, t.yaw);
      a.half_extents = Vec3(0.25, 0.25, 0.9);
      actors.push_back(a);
    }
  }
};

struct Result {
  double frame_ms = 0;  // thread CPU time
  double wall_ms = 0;
  size_t rays = 0, returns = 0;
};

// `lidars` LiDARs on the first vehicles, `frames` measured frames after a warm-up.
Result Run(SensorWorld& world, Traffic& traffic, int lidars, int channels, int pps, int frames) {
  for (int i = 0; i < lidars; ++i) {
    const std::string why = world.Add({static_cast<uint32_t>(1000 + i), "sensor.lidar.ray_cast",
                                       {{"channels", std::to_string(channels)}, {"points_per_second", std::to_string(pps)},
                                        {"rotation_frequency", "20"}, {"range", "100"}, {"dropoff_general_rate", "0"},
                                        {"upper_fov", "10"}, {"lower_fov", "-30"}},
                                       static_cast<uint32_t>(1 + i * 17), MakePose(0, 0, 1.65)});
    if (!why.empty()) {
      std::fprintf(stderr, "bench_lidar: %s\n", why.c_str());
      std::exit(1);
    }
  }
  Result r;
  double busy = 0, wall = 0;
  for (int k = 1; k <= frames + 5; ++k) {
    traffic.Advance(k);
    WorldFrame f;
    f.run = 1;
    f.frame = static_cast<uint64_t>(k);
    f.sim_time = k * kDt;
    f.actors = traffic.actors;
    const double c0 = CpuNow(), t0 = Now();
    const StepOutput out = world.Step(f, kDt);
    const double c1 = CpuNow(), t1 = Now();
    if (k <= 5) continue;  // warm-up
    busy += c1 - c0;
    wall += t1 - t0;
    for (const auto& pc : out.point_clouds) r.returns += pc.data.point_count;
  }
  for (int i = 0; i < lidars; ++i) world.Remove(static_cast<uint32_t>(1000 + i));
  r.frame_ms = busy / frames * 1000;
  r.wall_ms = wall / frames * 1000;
  r.rays = static_cast<size_t>(lidars) * static_cast<size_t>(std::lround(pps * kDt / channels)) * channels;
  r.returns /= static_cast<size_t>(frames);
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  const bool quick = argc > 1 && std::strcmp(argv[1], "--quick") == 0;
  const int frames = quick ? 20 : 200;
  double t0 = Now();
  const map::Map town = map::Map::Load(std::string(LOCKSTEP_CARLA_MAPS_DIR) + "/Town01.xodr");
  const map::Scene scene = map::GenerateScene(town, 42);
  const std::vector<map::Mesh> meshes = map::BuildWorldMeshes(town, scene);
  const double t_mesh = Now() - t0;
  SensorWorld world(42);
  t0 = Now();
  world.scene().SetStatic(meshes);
  const double t_bvh = Now() - t0;
  const size_t triangles = world.scene().static_triangles();
  Traffic traffic(town, 100, 50);
  traffic.Advance(0);
  std::printf("{\"bench\":\"lidar_setup\",\"map\":\"Town01\",\"meshes\":%zu,\"triangles\":%zu,\"mesh_s\":%.3f,\"bvh_s\":%.3f,\"vehicles\":%zu,\"walkers\":%zu}\n",
              meshes.size(), triangles, t_mesh, t_bvh, traffic.cars.size(), traffic.walker_start.size());

  // Four 64-channel LiDARs at 1.3 M points/s each (65,000 rays per LiDAR per frame).
  const Result four = Run(world, traffic, 4, 64, 1300000, frames);
  std::printf("{\"bench\":\"lidar\",\"lidars\":4,\"channels\":64,\"points_per_second_each\":1300000,\"points_per_frame\":%zu,"
              "\"returns_per_frame\":%zu,\"triangles\":%zu,\"actors\":%zu,\"frame_ms\":%.3f,\"wall_ms\":%.3f,\"mpoints_per_s\":%.2f}\n",
              four.rays, four.returns, triangles, traffic.actors.size(), four.frame_ms, four.wall_ms, four.rays / four.frame_ms / 1000.0);

  // The summary: one 32-channel LiDAR casting 56,000 rays per frame (1.12 M points/s at dt 0.05).
  const Result one = Run(world, traffic, 1, 32, 1120000, frames);
  std::printf("{\"bench\":\"lidar\",\"channels\":32,\"points_per_frame\":%zu,\"returns_per_frame\":%zu,\"triangles\":%zu,\"actors\":%zu,"
              "\"frame_ms\":%.3f,\"wall_ms\":%.3f,\"mpoints_per_s\":%.2f}\n",
              one.rays, one.returns, triangles, traffic.actors.size(), one.frame_ms, one.wall_ms, one.rays / one.frame_ms / 1000.0);
  return 0;
}
