#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <set>

#include "lockstep/map/error.h"
#include "lockstep/map/lane_invasion.h"
#include "lockstep/map/map.h"
#include "lockstep/map/map_info.h"
#include "lockstep/map/route_planner.h"
#include "lockstep/map/scene.h"
#include "lockstep/map/town_generator.h"

namespace lockstep::map {
namespace {

struct Generated {
  GeneratedTown town;
  Map map;
};

const Generated& Get(TownKind kind, std::uint64_t seed = 42) {
  static std::map<std::pair<int, std::uint64_t>, std::unique_ptr<Generated>> cache;
  auto key = std::make_pair(static_cast<int>(kind), seed);
  auto it = cache.find(key);
  if (it == cache.end()) {
    GeneratedTown t = GenerateTown(kind, seed);
    Map m = Map::FromString(t.xodr, t.name);
    it = cache.emplace(key, std::make_unique<Generated>(Generated{std::move(t), std::move(m)})).first;
  }
  return *it->second;
}

class map_generated : public ::testing::TestWithParam<TownKind> {};

TEST_P(map_generated, SameSeedSameBytes) {
  const GeneratedTown a = GenerateTown(GetParam(), 1234);
  const GeneratedTown b = GenerateTown(GetParam(), 1234);
  EXPECT_EQ(a.xodr, b.xodr);
  EXPECT_EQ(a.scene_yaml, b.scene_yaml);
  const GeneratedTown c = GenerateTown(GetParam(), 1235);
  EXPECT_NE(a.xodr, c.xodr);
  EXPECT_NE(a.scene_yaml, c.scene_yaml);
}

TEST_P(map_generated, ReadsBackWithSameStatistics) {
  const Generated& g = Get(GetParam());
  const MapStats st = ComputeStats(g.map);
  EXPECT_EQ(st.roads, g.town.roads);
  EXPECT_EQ(st.junctions, g.town.junctions);
  EXPECT_EQ(st.traffic_lights, g.town.traffic_lights);
  EXPECT_NEAR(st.road_length_m, g.town.road_length_m, 1e-3 * g.town.roads);
  EXPECT_NEAR(st.junction_road_length_m, g.town.junction_road_length_m, 1e-3 * g.town.roads);
  EXPECT_NEAR(st.driving_lane_length_m, g.town.driving_lane_length_m, 2e-3 * g.town.roads);
  const double streets = st.road_length_m - st.junction_road_length_m;
  if (GetParam() == TownKind::Town1) {
    EXPECT_GE(streets, 2900.0);
    EXPECT_GT(st.traffic_lights, 20);
  } else {
    EXPECT_NEAR(streets, 1400.0, 60.0);
  }
  // The JSON carries the same numbers.
  const std::string json = StatsToJson(st);
  EXPECT_NE(json.find("\"roads\":" + std::to_string(g.town.roads) + ","), std::string::npos) << json;
  for (const char* key : {"\"junctions\":", "\"road_length_m\":", "\"junction_road_length_m\":", "\"driving_lane_length_m\":", "\"spawn_points\":"})
    EXPECT_NE(json.find(key), std::string::npos) << key;
}

TEST_P(map_generated, ConnectedLanesMeetAndEveryJunctionIsReachable) {
  const Map& m = Get(GetParam()).map;
  std::set<int> visited;
  int edges = 0;
  for (const LaneNode& n : m.Nodes()) {
    if (n.type != LaneType::Driving) continue;
    EXPECT_FALSE(n.successors.empty()) << "dead end on road " << m.Data().roads[static_cast<std::size_t>(n.road)].id;
    const Waypoint a = m.MakeWaypoint(n.road, n.section, n.lane, n.ExitS());
    for (int next : n.successors) {
      const LaneNode& k = m.Nodes()[static_cast<std::size_t>(next)];
      const Waypoint b = m.MakeWaypoint(k.road, k.section, k.lane, k.EntryS());
      EXPECT_LT((a.transform.location - b.transform.location).norm(), 0.01);
      EXPECT_NEAR(std::remainder(a.transform.yaw - b.transform.yaw, 2 * 3.14159265358979323846), 0.0, 1e-6);
      ++edges;
    }
    for (const Waypoint& w : m.Next(a, 5.0))
      if (w.IsJunction()) visited.insert(w.junction);
  }
  EXPECT_GT(edges, 50);
  EXPECT_EQ(visited.size(), m.Data().junctions.size());
}

TEST_P(map_generated, RoutesBetweenSceneSpawnPoints) {
  const Generated& g = Get(GetParam());
  const Scene scene = SceneFromYaml(g.town.scene_yaml, "scene");
  ASSERT_GT(scene.vehicle_spawn_points.size(), 50u);
  ASSERT_GT(scene.pedestrian_spawn_points.size(), 50u);
  const auto& sp = scene.vehicle_spawn_points;
  std::set<RoadOption> seen;
  for (std::size_t i = 0; i < 30; ++i) {
    const SpawnPoint& a = sp[(i * 17) % sp.size()];
    const SpawnPoint& b = sp[(i * 29 + 3) % sp.size()];
    const auto r = PlanRoute(g.map, Eigen::Vector3d(a.x, a.y, a.z), Eigen::Vector3d(b.x, b.y, b.z));
    ASSERT_TRUE(r);
    for (const RouteStep& s : r->steps) seen.insert(s.option);
  }
  EXPECT_TRUE(seen.count(RoadOption::Left));
  EXPECT_TRUE(seen.count(RoadOption::Right));
  EXPECT_TRUE(seen.count(RoadOption::Straight));
  EXPECT_TRUE(seen.count(RoadOption::LaneFollow));
}

TEST_P(map_generated, CrossingSolidCentreLine) {
  const Map& m = Get(GetParam()).map;
  int checked = 0;
  for (const Waypoint& w : m.GenerateWaypoints(30.0)) {
    if (w.IsJunction() || w.lane != -1) continue;
    const auto left = m.LeftMarking(w);
    ASSERT_TRUE(left);
    const Eigen::Vector2d c = w.transform.location.head<2>();
    const Eigen::Vector2d to_left(-std::sin(w.transform.yaw), std::cos(w.transform.yaw));
    const auto crossed = CrossedLaneMarkings(m, MakeFootprint(c, w.transform.yaw, 2.2, 0.9),
                                             MakeFootprint(c + 2.0 * to_left, w.transform.yaw, 2.2, 0.9));
    ASSERT_EQ(crossed.size(), 1u);
    EXPECT_EQ(crossed[0].marking.type, left->type);
    if (left->type == RoadMarkType::Solid) {
      EXPECT_EQ(crossed[0].marking.color, RoadMarkColor::Yellow);
      EXPECT_EQ(m.AllowedLaneChange(w), LaneChange::None);
      ++checked;
    }
  }
  EXPECT_GT(checked, 0);
}

TEST_P(map_generated, SceneIsPlausible) {
  const Generated& g = Get(GetParam());
  const Scene scene = SceneFromYaml(g.town.scene_yaml, "scene");
  EXPECT_EQ(SceneToYaml(scene), g.town.scene_yaml);  // lossless round trip
  EXPECT_GT(scene.buildings.size(), 40u);
  EXPECT_GT(scene.vegetation.size(), 40u);
  std::set<int> designs;
  for (const BuildingInstance& b : scene.buildings) {
    designs.insert(b.design);
    EXPECT_TRUE(g.map.LanesAt(b.x, b.y).empty()) << "building on a road at " << b.x << "," << b.y;
  }
  if (GetParam() == TownKind::Town1) {
    EXPECT_GE(designs.size(), 40u);
  }
  int lights = 0;
  for (const PropInstance& p : scene.props) lights += p.kind == "traffic_light";
  EXPECT_EQ(lights, g.town.traffic_lights);
}

TEST_P(map_generated, TrafficLightsGuardSignalisedJunctions) {
  const Generated& g = Get(GetParam());
  const auto lights = g.map.TrafficLights();
  ASSERT_EQ(static_cast<int>(lights.size()), g.town.traffic_lights);
  std::map<int, int> per_junction;
  for (const TrafficLightInfo& tl : lights) {
    ASSERT_EQ(tl.stop_waypoints.size(), 1u) << tl.signal_id;
    ASSERT_GE(tl.junction, 0);
    EXPECT_FALSE(tl.controller_id.empty());
    ++per_junction[tl.junction];
    const Waypoint& w = tl.stop_waypoints.front();
    EXPECT_LT((tl.pose.location - w.transform.location).head<2>().norm(), 10.0);
    for (const Waypoint& n : g.map.Next(w, 1.0)) EXPECT_EQ(n.junction, tl.junction);
  }
  for (const auto& [junction, count] : per_junction) EXPECT_GE(count, 3) << junction;  // one per approach
}

INSTANTIATE_TEST_SUITE_P(Towns, map_generated, ::testing::Values(TownKind::Town1, TownKind::Town2));

TEST(map_scene, YamlErrorsNameKeyAndLine) {
  try {
    SceneFromYaml("format: lockstep-scene/1\nbuildings:\n  - {design: 1, x: 0, y: 0, width: 5, storeys: 2}\n", "s.yaml");
    FAIL() << "no error";
  } catch (const MapError& e) {
    EXPECT_NE(std::string(e.what()).find("s.yaml:3: missing key 'depth'"), std::string::npos) << e.what();
  }
  try {
    SceneFromYaml("format: lockstep-scene/1\nvegetation:\n  - {kind: tree, x: a, y: 0, height: 1, radius: 1}\n", "s.yaml");
    FAIL() << "no error";
  } catch (const MapError& e) {
    EXPECT_NE(std::string(e.what()).find("s.yaml:3: key 'x' is not a number"), std::string::npos) << e.what();
  }
  EXPECT_THROW(SceneFromYaml("format: [unclosed\n", "s.yaml"), MapError);
  EXPECT_THROW(SceneFromYaml("format: other/2\n", "s.yaml"), MapError);
}

TEST(map_scene, AnyMapGetsADeterministicScene) {
  const Map m = Map::Load(std::string(LOCKSTEP_CARLA_MAPS_DIR) + "/Town01.xodr");
  const std::string a = SceneToYaml(GenerateScene(m, 5)), b = SceneToYaml(GenerateScene(m, 5));
  EXPECT_EQ(a, b);
  EXPECT_NE(a, SceneToYaml(GenerateScene(m, 6)));
  const Scene s = SceneFromYaml(a);
  EXPECT_GT(s.buildings.size(), 50u);
  int lights = 0;
  for (const PropInstance& p : s.props) lights += p.kind == "traffic_light";
  EXPECT_EQ(lights, 36);  // one pole per signal in Town01
}

}  // namespace
}  // namespace lockstep::map
