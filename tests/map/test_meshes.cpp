#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include <Eigen/Geometry>

#include "lockstep/map/buildings.h"
#include "lockstep/map/crossings.h"
#include "lockstep/map/road_mesh.h"
#include "lockstep/map/scene_mesh.h"
#include "lockstep/map/town_generator.h"

namespace lockstep::map {
namespace {

Eigen::Vector3d V(const Mesh& m, std::uint32_t i) {
  return {m.vertices[3 * i], m.vertices[3 * i + 1], m.vertices[3 * i + 2]};
}

// Signed volume by the divergence theorem: positive for closed, outward-facing meshes.
double SignedVolume(const Mesh& m) {
  double v = 0;
  for (std::size_t t = 0; t < m.indices.size(); t += 3)
    v += V(m, m.indices[t]).dot(V(m, m.indices[t + 1]).cross(V(m, m.indices[t + 2]))) / 6.0;
  return v;
}

double UpArea(const Mesh& m) {
  double a = 0;
  for (std::size_t t = 0; t < m.indices.size(); t += 3) {
    const Eigen::Vector3d n = (V(m, m.indices[t + 1]) - V(m, m.indices[t])).cross(V(m, m.indices[t + 2]) - V(m, m.indices[t]));
    if (n.z() > 0) a += 0.5 * n.z();
  }
  return a;
}

void ExpectWellFormed(const Mesh& m) {
  ASSERT_EQ(m.vertices.size() % 3, 0u);
  ASSERT_EQ(m.indices.size() % 3, 0u);
  for (float f : m.vertices) ASSERT_TRUE(std::isfinite(f)) << m.name;
  for (std::uint32_t i : m.indices) ASSERT_LT(i, m.VertexCount()) << m.name;
}

TEST(map_meshes, BoxIsClosedAndOutward) {
  Mesh m;
  AddBox(m, {1, 2, 3}, 4, 2, 3, 0.7, true);
  EXPECT_EQ(m.TriangleCount(), 12u);
  EXPECT_NEAR(SignedVolume(m), 24.0, 1e-4);
  Mesh c;
  AddCylinder(c, {0, 0, 0}, 1, 2, 16);
  EXPECT_GT(SignedVolume(c) + 0.0, 0.0);
}

TEST(map_meshes, FortyEightDistinctBuildingDesigns) {
  std::set<std::vector<float>> shapes;
  std::set<std::string> names;
  for (int d = 0; d < kBuildingDesignCount; ++d) {
    Mesh m;
    AddBuilding(m, BuildingInstance{d, 0, 0, 0, 0, 20, 16, 4, 3.0});
    ExpectWellFormed(m);
    EXPECT_GE(m.TriangleCount(), 10u);
    EXPECT_LE(m.TriangleCount(), 240u);
    // Every vertex within the lot and above ground.
    for (std::size_t i = 0; i < m.VertexCount(); ++i) {
      EXPECT_LE(std::fabs(m.vertices[3 * i]), 10.01f);
      EXPECT_LE(std::fabs(m.vertices[3 * i + 1]), 8.01f);
      EXPECT_GE(m.vertices[3 * i + 2], -1e-4f);
    }
    shapes.insert(m.vertices);
    names.insert(DescribeBuildingDesign(d).Name());
  }
  EXPECT_EQ(shapes.size(), 48u);
  EXPECT_EQ(names.size(), 48u);
}

TEST(map_meshes, CarlaTownRoadMeshes) {
  const Map m = Map::Load(std::string(LOCKSTEP_CARLA_MAPS_DIR) + "/Town01.xodr");
  const std::vector<Mesh> meshes = BuildRoadMeshes(m);
  double road_area = 0;
  std::set<std::uint32_t> ids;
  for (const Mesh& mesh : meshes) {
    ExpectWellFormed(mesh);
    EXPECT_TRUE(ids.insert(mesh.instance_id).second);
    EXPECT_TRUE(mesh.semantic_tag == semantic::kRoads || mesh.semantic_tag == semantic::kSideWalks ||
                mesh.semantic_tag == semantic::kTerrain || mesh.semantic_tag == semantic::kRoadLine)
        << mesh.name;
    if (mesh.semantic_tag == semantic::kRoads) road_area += UpArea(mesh);
    if (mesh.semantic_tag == semantic::kSideWalks) {
      float top = -1e9f;
      for (std::size_t i = 2; i < mesh.vertices.size(); i += 3) top = std::max(top, mesh.vertices[i]);
      EXPECT_NEAR(top, 0.15, 1e-3) << mesh.name;
    }
  }
  // Road area from the lane widths (Town01: flat, driving + shoulder lanes).
  double expected = 0;
  for (const LaneNode& n : m.Nodes()) {
    if (n.type != LaneType::Driving && n.type != LaneType::Shoulder) continue;
    const Road& road = m.Data().roads[static_cast<std::size_t>(n.road)];
    const int steps = std::max(1, static_cast<int>(n.Length() / 0.5));
    for (int k = 0; k < steps; ++k) {
      const double s = n.s_begin + (k + 0.5) * n.Length() / steps;
      const double t = LaneSpanOf(road, static_cast<std::size_t>(n.section), n.lane, s).Center();
      const double stretch = 1.0 - EvaluateReferenceLine(road.plan_view, s).curvature * t;
      expected += LaneSpanOf(road, static_cast<std::size_t>(n.section), n.lane, s).Width() * stretch * n.Length() / steps;
    }
  }
  EXPECT_NEAR(road_area, expected, 0.01 * expected);
}

// Town01's OpenDRIVE has no crosswalk objects; the walkers cross at every junction mouth
// (crossings.h) and the markings show a zebra there: paint across the driving lanes, none
// on the sidewalks, and nothing of it with the option off.
TEST(map_meshes, JunctionMouthsOfTown01HaveZebraCrossings) {
  const Map m = Map::Load(std::string(LOCKSTEP_CARLA_MAPS_DIR) + "/Town01.xodr");
  const std::vector<MouthCrossing> mouths = JunctionMouthCrossings(m);
  ASSERT_GE(mouths.size(), 30u);
  auto paint_near = [&](const std::vector<Mesh>& meshes, const Eigen::Vector3d& p, double radius) {
    int n = 0;
    for (const Mesh& mesh : meshes) {
      if (mesh.semantic_tag != semantic::kRoadLine) continue;
      for (std::size_t i = 0; i + 2 < mesh.vertices.size(); i += 3) {
        if (std::hypot(mesh.vertices[i] - p.x(), mesh.vertices[i + 1] - p.y()) < radius) ++n;
      }
    }
    return n;
  };
  const std::vector<Mesh> with = BuildRoadMeshes(m);
  RoadMeshOptions off;
  off.junction_crosswalks = false;
  const std::vector<Mesh> without = BuildRoadMeshes(m, off);
  std::size_t at_two_metres = 0;
  for (const MouthCrossing& c : mouths) {
    const Eigen::Vector3d centre = (c.ends[0] + c.ends[1]) / 2;
    const double half = (c.ends[1] - c.ends[0]).head<2>().norm() / 2;
    ASSERT_TRUE(OnDrivingLane(m, centre));
    // Straight across the road, `setback` (2 m; 1 or 0 where 2 m would stand on a lane)
    // past the middle of the road's end, into the junction.
    EXPECT_LT(std::abs((c.ends[1] - c.ends[0]).normalized().dot(c.into_junction)), 0.02) << "road index " << c.road;
    const Road& road = m.Data().roads[static_cast<std::size_t>(c.road)];
    const double s_end = c.at_end ? road.length - 1e-3 : 1e-3;
    Eigen::Vector3d end_mid = Eigen::Vector3d::Zero();
    for (int lane : c.driving_lanes) end_mid += m.MakeWaypoint(c.road, c.section, lane, s_end).transform.location;
    end_mid /= static_cast<double>(c.driving_lanes.size());
    const double setback = (centre - end_mid).dot(c.into_junction);
    EXPECT_TRUE(std::abs(setback - 2) < 0.05 || std::abs(setback - 1) < 0.05 || std::abs(setback) < 0.05) << setback;
    if (std::abs(setback - 2) < 0.05) ++at_two_metres;
    bool in_junction = false;
    for (const LanePoint& lp : m.LanesAt(centre.x(), centre.y())) {
      in_junction |= m.Data().roads[static_cast<std::size_t>(m.Nodes()[static_cast<std::size_t>(lp.node)].road)].junction_index >= 0;
    }
    EXPECT_TRUE(in_junction || setback < 0.05) << "road index " << c.road;
    EXPECT_FALSE(OnDrivingLane(m, c.ends[0]));
    EXPECT_FALSE(OnDrivingLane(m, c.ends[1]));
    // A zebra stripe has 4 corners; the road's own lines near a mouth add some, the zebra
    // at least 4 per driving lane crossed.
    const int zebra = paint_near(with, centre, half) - paint_near(without, centre, half);
    EXPECT_GE(zebra, 4 * static_cast<int>(c.driving_lanes.size())) << "road index " << c.road;
    EXPECT_EQ(paint_near(with, c.ends[0], 0.4) - paint_near(without, c.ends[0], 0.4), 0) << "no paint on the kerb";
  }
  EXPECT_GE(at_two_metres, mouths.size() * 3 / 4);
}

// The generated towns have crosswalk objects before their signalled junctions: those mouths
// keep the object's crossing and get no second one; the others get one.
TEST(map_meshes, AMouthWithACrosswalkObjectGetsNoSecondCrossing) {
  const GeneratedTown t = GenerateTown(TownKind::Town1, 3);
  const Map m = Map::FromString(t.xodr, t.name);
  const auto objects = m.Crosswalks();
  ASSERT_GE(objects.size(), 40u);
  const std::vector<MouthCrossing> mouths = JunctionMouthCrossings(m);
  EXPECT_GE(mouths.size(), 4u) << "mouths without an object still get a crossing";
  for (const MouthCrossing& c : mouths) {
    const Eigen::Vector3d centre = (c.ends[0] + c.ends[1]) / 2;
    for (const auto& poly : objects) {
      Eigen::Vector3d o = Eigen::Vector3d::Zero();
      for (const auto& p : poly) o += p;
      o /= static_cast<double>(poly.size());
      EXPECT_GT((o - centre).head<2>().norm(), 10.0) << "a second crossing next to a crosswalk object, road index " << c.road;
    }
  }
}

TEST(map_meshes, WorldTriangleBudgetAndUniqueInstances) {
  for (TownKind kind : {TownKind::Town1, TownKind::Town2}) {
    const GeneratedTown t = GenerateTown(kind, 3);
    const Map m = Map::FromString(t.xodr, t.name);
    const std::vector<Mesh> world = BuildWorldMeshes(m, SceneFromYaml(t.scene_yaml));
    std::set<std::uint32_t> ids;
    std::set<int> tags;
    for (const Mesh& mesh : world) {
      ExpectWellFormed(mesh);
      EXPECT_TRUE(ids.insert(mesh.instance_id).second) << mesh.name;
      tags.insert(mesh.semantic_tag);
    }
    for (int tag : {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 24}) EXPECT_TRUE(tags.count(tag)) << "tag " << tag;
    const std::size_t tris = TotalTriangles(world);
    EXPECT_LT(tris, 178000u) << t.name;
    EXPECT_GT(tris, 5000u);
  }
}

}  // namespace
}  // namespace lockstep::map
