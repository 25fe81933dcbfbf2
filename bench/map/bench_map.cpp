// bench_map [maps_dir]: parse, nearest-waypoint, waypoint generation and routing
// timings for CARLA's Town01/Town02 (from maps_dir) and the two generated towns.
// Prints one JSON line per town; the last line is the Town01 summary.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "lockstep/map/map.h"
#include "lockstep/map/route_planner.h"
#include "lockstep/map/scene_mesh.h"
#include "lockstep/map/town_generator.h"

namespace lm = lockstep::map;
using Clock = std::chrono::steady_clock;

namespace {

double Ms(Clock::duration d) { return std::chrono::duration<double, std::milli>(d).count(); }

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}
double Percentile(std::vector<double> v, double p) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[std::min(v.size() - 1, static_cast<std::size_t>(p * static_cast<double>(v.size())))];
}

struct Result {
  std::string town;
  double parse_ms, nearest_us, nearest_p99_us, gen_ms, route_ms, scene_ms, meshes_ms;
  std::size_t waypoints, triangles;
};

Result Run(const std::string& town, const std::string& xodr_text) {
  Result r{};
  r.town = town;
  std::vector<double> parse;
  for (int i = 0; i < 5; ++i) {
    const auto t0 = Clock::now();
    lm::Map m = lm::Map::FromString(xodr_text, town);
    parse.push_back(Ms(Clock::now() - t0));
  }
  r.parse_ms = Median(parse);
  const lm::Map map = lm::Map::FromString(xodr_text, town);
  // Query points: near lane centres (+-6 m), where agents and sensors ask.
  const auto wps = map.GenerateWaypoints(1.0, lm::LaneType::Driving | lm::LaneType::Sidewalk);
  std::mt19937_64 rng(7);
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < 20000; ++i) {
    const lm::Waypoint& w = wps[rng() % wps.size()];
    const double dx = static_cast<double>(rng() % 12001) / 1000.0 - 6.0, dy = static_cast<double>(rng() % 12001) / 1000.0 - 6.0;
    pts.push_back(w.transform.location + Eigen::Vector3d(dx, dy, 0));
  }
  std::vector<double> us;
  us.reserve(pts.size());
  double sink = 0;
  for (const Eigen::Vector3d& p : pts) {
    const auto t0 = Clock::now();
    const auto w = map.NearestWaypoint(p);
    us.push_back(std::chrono::duration<double, std::micro>(Clock::now() - t0).count());
    if (w) sink += w->s;
  }
  r.nearest_us = Median(us);
  r.nearest_p99_us = Percentile(us, 0.99);
  std::vector<double> gen;
  for (int i = 0; i < 5; ++i) {
    const auto t0 = Clock::now();
    r.waypoints = map.GenerateWaypoints(2.0).size();
    gen.push_back(Ms(Clock::now() - t0));
  }
  r.gen_ms = Median(gen);
  const auto spawns = map.SpawnPoints();
  std::vector<double> route;
  for (std::size_t i = 0; i < 50 && !spawns.empty(); ++i) {
    const auto t0 = Clock::now();
    const auto rt = lm::PlanRoute(map, spawns[(i * 7) % spawns.size()].location, spawns[(i * 13 + 5) % spawns.size()].location);
    route.push_back(Ms(Clock::now() - t0));
    if (rt) sink += rt->length_m;
  }
  r.route_ms = Median(route);
  auto t0 = Clock::now();
  const lm::Scene scene = lm::GenerateScene(map, 0);
  r.scene_ms = Ms(Clock::now() - t0);
  t0 = Clock::now();
  r.triangles = lm::TotalTriangles(lm::BuildWorldMeshes(map, scene));
  r.meshes_ms = Ms(Clock::now() - t0);
  if (sink == 42.0) std::puts("");  // keep the work observable
  return r;
}

void Print(const Result& r, bool summary) {
  if (summary) {
    std::printf("{\"bench\":\"map\",\"town\":\"%s\",\"parse_ms\":%.3f,\"nearest_waypoint_us\":%.3f,"
                "\"generate_waypoints_2m_ms\":%.3f,\"route_ms\":%.3f}\n",
                r.town.c_str(), r.parse_ms, r.nearest_us, r.gen_ms, r.route_ms);
    return;
  }
  std::printf("{\"bench\":\"map\",\"town\":\"%s\",\"parse_ms\":%.3f,\"nearest_waypoint_us\":%.3f,"
              "\"nearest_waypoint_p99_us\":%.3f,\"generate_waypoints_2m_ms\":%.3f,\"waypoints_2m\":%zu,"
              "\"route_ms\":%.3f,\"scene_ms\":%.3f,\"world_meshes_ms\":%.3f,\"world_triangles\":%zu}\n",
              r.town.c_str(), r.parse_ms, r.nearest_us, r.nearest_p99_us, r.gen_ms, r.waypoints, r.route_ms, r.scene_ms,
              r.meshes_ms, r.triangles);
}

std::string Slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace

int main(int argc, char** argv) {
  const std::string dir = argc > 1 ? argv[1] : LOCKSTEP_CARLA_MAPS_DIR;
  try {
    std::vector<Result> results;
    for (const char* town : {"Town01", "Town02"}) {
      const std::string text = Slurp(dir + "/" + town + ".xodr");
      if (text.empty()) {
        std::fprintf(stderr, "bench_map: cannot read %s/%s.xodr\n", dir.c_str(), town);
        return 1;
      }
      results.push_back(Run(town, text));
    }
    for (lm::TownKind k : {lm::TownKind::Town1, lm::TownKind::Town2}) {
      const lm::GeneratedTown g = lm::GenerateTown(k, 0);
      results.push_back(Run(g.name, g.xodr));
    }
    for (const Result& r : results) Print(r, false);
    Print(results.front(), true);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_map: %s\n", e.what());
    return 1;
  }
  return 0;
}
