// bench_air: physics throughput of the air simulation core.
//
// Full sub-step = command layer + cascaded controller + rotors/drag/integration + contact
// queries (ground plane, a 4,800-triangle town mesh, one vehicle box, the other drones).
// A second case flies 100 drones through the generated town LockstepTown1 (its full dense
// mesh, as air_sim builds it from the map) between random street-level waypoints.
// Prints JSON lines; the last one is the summary read by `bench/run air`:
//   {"bench":"air","physics_hz":1000,"drones":1,"steps_per_s":...,"drones_realtime":...}
// Usage: bench_air [--quick]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <set>
#include <vector>

#include "lockstep/air/air.h"
#include "lockstep/map/map.h"
#include "lockstep/map/scene.h"
#include "lockstep/map/scene_mesh.h"
#include "lockstep/map/town_generator.h"

using namespace lockstep::air;

namespace {

double Now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// A grid of 20 x 20 buildings (boxes, 12 triangles each) on 30 m blocks.
std::shared_ptr<const StaticMesh> Town() {
  std::vector<float> v;
  std::vector<std::uint32_t> idx;
  const std::uint32_t faces[36] = {0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4,
                                   2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5};
  for (int bx = 0; bx < 20; ++bx) {
    for (int by = 0; by < 20; ++by) {
      const double x0 = bx * 30.0 + 8, y0 = by * 30.0 + 8, h = 8 + (bx * 7 + by * 3) % 20;
      const std::uint32_t base = static_cast<std::uint32_t>(v.size() / 3);
      for (int i = 0; i < 8; ++i) {
        v.push_back(static_cast<float>(x0 + ((i & 1) ? 14 : 0)));
        v.push_back(static_cast<float>(y0 + ((i & 2) ? 14 : 0)));
        v.push_back(static_cast<float>((i & 4) ? h : 0));
      }
      for (std::uint32_t f : faces) idx.push_back(base + f);
    }
  }
  return StaticMesh::Build(v, idx, 8.0);
}

struct Scenario {
  World model;
  WorldState state;
  Environment env;
  CommandId next = 1;
  Commands cmds;
  std::set<CommandId> paths;  // ids of the path commands (re-sent when they complete)
};

// N drones flying square loops along the streets at 2-6 m altitude between the buildings.
Scenario Make(int n) {
  Scenario s;
  s.model.statics.mesh = Town();
  s.env.wind = Vec3(2, 1, 0);
  VehicleBox car;
  car.id = 1000;
  car.pose.position = Vec3(3, 3, 0.75);
  car.velocity = Vec3(5, 0, 0);
  s.env.vehicles.push_back(car);
  for (int i = 0; i < n; ++i) {
    Pose spawn;
    // 400 street corners; further drones go 1 m diagonally apart and 1 m higher per layer.
    const int layer = i / 400;
    spawn.position = Vec3(3.0 + 30.0 * (i % 20) + layer, 3.0 + 30.0 * (i / 20 % 20) + layer, 0.06);
    AddDrone(&s.model, &s.state, static_cast<DroneId>(i + 1), MultirotorParams{}, spawn);
    const Vec3 p = spawn.position;
    const double z = 2.0 + (i % 5) + layer;
    s.cmds.push_back({s.next++, static_cast<DroneId>(i + 1), cmd::Arm{}});
    cmd::MoveOnPath path;
    path.path = {p + Vec3(0, 0, z), p + Vec3(0, 25, z), p + Vec3(25, 25, z), p + Vec3(25, 0, z), p + Vec3(0, 0, z)};
    path.velocity = 5;
    s.paths.insert(s.next);
    s.cmds.push_back({s.next++, static_cast<DroneId>(i + 1), path});
  }
  return s;
}

// Runs `ticks` ticks of 0.05 s and returns wall seconds. Drones that finished their loop are
// sent round again so that every sub-step is a flying one.
double Run(Scenario& s, int ticks) {
  const double t0 = Now();
  for (int k = 0; k < ticks; ++k) {
    Step(s.model, &s.state, s.cmds, s.env, 0.05);
    s.cmds.clear();
    for (const CommandReport& r : s.state.reports) {
      if (s.paths.count(r.id) != 0 &&
          (r.status == CommandStatus::kCompleted || r.status == CommandStatus::kTimedOut)) {
        const DroneState* d = s.state.Find(r.drone);
        if (d == nullptr || !d->armed) continue;
        cmd::MoveOnPath path;
        const Vec3 p = d->position;
        path.path = {p + Vec3(0, 25, 0), p + Vec3(25, 25, 0), p + Vec3(25, 0, 0), p};
        path.velocity = 5;
        s.paths.insert(s.next);
        s.cmds.push_back({s.next++, r.drone, path});
      }
    }
  }
  return Now() - t0;
}

// The generated town's static meshes (roads, sidewalks, buildings, poles, trees), as air_sim
// builds them from the map (the ground plane is the model's own).
std::shared_ptr<const StaticMesh> GeneratedTownMesh(Vec3* lo, Vec3* hi) {
  namespace lm = lockstep::map;
  const lm::GeneratedTown g = lm::GenerateTown(lm::TownKind::Town1, 0);
  const lm::Map town = lm::Map::FromString(g.xodr, g.name);
  const lm::Scene scene = lm::SceneFromYaml(g.scene_yaml, g.name + ".scene.yaml");
  std::vector<float> xyz;
  std::vector<std::uint32_t> indices;
  for (const auto& m : lm::BuildWorldMeshes(town, scene)) {
    if (m.semantic_tag == lm::semantic::kGround) continue;
    const auto base = static_cast<std::uint32_t>(xyz.size() / 3);
    xyz.insert(xyz.end(), m.vertices.begin(), m.vertices.end());
    for (auto i : m.indices) indices.push_back(base + i);
  }
  *lo = Vec3::Constant(1e30);
  *hi = Vec3::Constant(-1e30);
  for (std::size_t i = 0; i + 2 < xyz.size(); i += 3) {
    const Vec3 p(xyz[i], xyz[i + 1], xyz[i + 2]);
    *lo = lo->cwiseMin(p);
    *hi = hi->cwiseMax(p);
  }
  return StaticMesh::Build(xyz, indices, 4.0, 1);
}

// Deterministic pseudo-random numbers in [0, 1) (no wall clock, no global state).
double Uniform(std::uint64_t* x) {
  *x = *x * 6364136223846793005ull + 1442695040888963407ull;
  return static_cast<double>(*x >> 11) * 0x1.0p-53;
}

// 100 drones through the generated town: each flies a loop of random waypoints at 3-12 m over
// the town (streets, roofs, trees and poles in the way), re-sent when it completes.
void TownCase(bool quick) {
  Vec3 lo, hi;
  Scenario s;
  s.model.statics.mesh = GeneratedTownMesh(&lo, &hi);
  s.env.wind = Vec3(2, 1, 0);
  std::uint64_t rng = 7;
  auto waypoint = [&](double z) {
    return Vec3(lo.x() + (hi.x() - lo.x()) * Uniform(&rng), lo.y() + (hi.y() - lo.y()) * Uniform(&rng), z);
  };
  const int n = 100;
  for (int i = 0; i < n; ++i) {
    Pose spawn;
    spawn.position = waypoint(20.0 + 0.5 * i);  // spawned in the air, spread out
    AddDrone(&s.model, &s.state, static_cast<DroneId>(i + 1), MultirotorParams{}, spawn);
    s.cmds.push_back({s.next++, static_cast<DroneId>(i + 1), cmd::Arm{}});
    cmd::MoveOnPath path;
    for (int k = 0; k < 6; ++k) path.path.push_back(waypoint(3.0 + 9.0 * Uniform(&rng)));
    path.velocity = 5;
    path.timeout = 60;
    s.paths.insert(s.next);
    s.cmds.push_back({s.next++, static_cast<DroneId>(i + 1), path});
  }
  Run(s, 20);
  const int ticks = quick ? 20 : 100;
  const double wall = Run(s, ticks);
  int flying = 0, contacts = 0;
  for (const DroneState& d : s.state.drones) {
    flying += d.landed == LandedState::kFlying ? 1 : 0;
    contacts += static_cast<int>(d.collision.collision_count);
  }
  std::printf("{\"bench\":\"air\",\"case\":\"town_100_drones\",\"triangles\":%zu,\"drones\":%d,\"flying\":%d,"
              "\"collisions\":%d,\"real_time_factor\":%.2f,\"steps_per_s\":%.0f}\n",
              s.model.statics.mesh->triangle_count(), n, flying, contacts, ticks * 0.05 / wall,
              n * ticks * 0.05 * 1000 / wall);
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  const bool quick = argc > 1 && std::strcmp(argv[1], "--quick") == 0;
  const double physics_hz = 1000;
  // ---- one drone: sub-steps per wall second (best of 3)
  double best = 0;
  for (int rep = 0; rep < 3; ++rep) {
    Scenario s = Make(1);
    Run(s, 40);  // take off first
    const int ticks = quick ? 200 : 2000;
    const double wall = Run(s, ticks);
    const double steps = ticks * 0.05 * physics_hz;
    best = std::max(best, steps / wall);
    if (s.state.drones[0].landed != LandedState::kFlying) {
      std::fprintf(stderr, "bench_air: the benchmark drone is not flying\n");
      return 1;
    }
  }
  TownCase(quick);
  std::printf("{\"bench\":\"air\",\"case\":\"one_drone\",\"physics_hz\":%.0f,\"steps_per_s\":%.0f,\"us_per_step\":%.3f}\n",
              physics_hz, best, 1e6 / best);
  std::fflush(stdout);
  // ---- N drones: real-time factor = sim seconds / wall seconds on one core. Grow N by 2x
  // until the factor drops below 1, then bisect.
  auto rtf_of = [&](int n, bool print) {
    Scenario s = Make(n);
    Run(s, 20);
    const int ticks = quick ? 10 : 40;
    const double wall = Run(s, ticks);
    const double rtf = ticks * 0.05 / wall;
    int flying = 0;
    for (const DroneState& d : s.state.drones) flying += d.landed == LandedState::kFlying ? 1 : 0;
    if (print) {
      std::printf("{\"bench\":\"air\",\"case\":\"many_drones\",\"drones\":%d,\"flying\":%d,\"real_time_factor\":%.2f,\"steps_per_s\":%.0f}\n",
                  n, flying, rtf, n * ticks * 0.05 * physics_hz / wall);
      std::fflush(stdout);
    }
    return rtf;
  };
  int lo = 0, hi = 0;
  for (int n = 10; n <= 5000; n *= 2) {
    if (rtf_of(n, true) >= 1.0) {
      lo = n;
    } else {
      hi = n;
      break;
    }
  }
  if (hi == 0) hi = lo;
  while (hi - lo > std::max(5, lo / 20)) {
    const int mid = (lo + hi) / 2;
    if (rtf_of(mid, true) >= 1.0) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  const int realtime = lo;
  std::printf("{\"bench\":\"air\",\"physics_hz\":%.0f,\"drones\":1,\"steps_per_s\":%.0f,\"drones_realtime\":%d}\n",
              physics_hz, best, realtime);
  return 0;
}
