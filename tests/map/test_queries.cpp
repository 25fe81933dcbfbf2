#include <gtest/gtest.h>

#include "carla_towns.h"

#include <cmath>
#include <map>
#include <numbers>
#include <set>

#include "lockstep/map/map.h"

namespace lockstep::map {
namespace {

class map_carla : public ::testing::TestWithParam<std::string> {};

// Every lane-graph edge between two roads (road links and junction lane links) must
// join lane centres: the exit of one lane lies within 1 cm of the entry of the next.
TEST_P(map_carla, ConnectedLanesMeetWithinOneCentimetre) {
  const Map& m = Town(GetParam());
  int edges = 0;
  for (const LaneNode& n : m.Nodes()) {
    if (n.type != LaneType::Driving) continue;
    const Waypoint a = m.MakeWaypoint(n.road, n.section, n.lane, n.ExitS());
    for (int next : n.successors) {
      const LaneNode& k = m.Nodes()[static_cast<std::size_t>(next)];
      const Waypoint b = m.MakeWaypoint(k.road, k.section, k.lane, k.EntryS());
      EXPECT_LT((a.transform.location - b.transform.location).norm(), 0.01)
          << "road " << m.Data().roads[static_cast<std::size_t>(n.road)].id << " lane " << n.lane << " -> road "
          << m.Data().roads[static_cast<std::size_t>(k.road)].id << " lane " << k.lane;
      ++edges;
    }
  }
  EXPECT_GT(edges, 100);
}

// Road-level links: where a road links to a road, every lane with a lane link has
// both borders within 1 cm of the linked lane's borders (all lane types, not only driving).
TEST_P(map_carla, RoadLinksTouch) {
  const Map& m = Town(GetParam());
  const OpenDrive& od = m.Data();
  int checked = 0;
  for (const Road& r : od.roads) {
    for (bool at_end : {false, true}) {
      const RoadLink& l = at_end ? r.successor : r.predecessor;
      if (l.kind != RoadLink::Kind::Road) continue;
      const Road& o = od.roads[static_cast<std::size_t>(od.road_index.at(l.element_id))];
      const std::size_t sec = at_end ? r.sections.size() - 1 : 0;
      const std::size_t osec = l.contact == ContactPoint::End ? o.sections.size() - 1 : 0;
      const double s = at_end ? r.length : 0.0, os = l.contact == ContactPoint::End ? o.length : 0.0;
      for (const Lane& lane : r.sections[sec].lanes) {
        for (int to : at_end ? lane.successors : lane.predecessors) {
          if (!o.sections[osec].Find(to)) continue;
          const LaneSpan a = LaneSpanOf(r, sec, lane.id, s), b = LaneSpanOf(o, osec, to, os);
          const double d_in = (RoadToWorld(r, s, a.t_inner) - RoadToWorld(o, os, b.t_inner)).norm();
          const double d_in_x = (RoadToWorld(r, s, a.t_inner) - RoadToWorld(o, os, b.t_outer)).norm();
          const double d_out = (RoadToWorld(r, s, a.t_outer) - RoadToWorld(o, os, b.t_outer)).norm();
          const double d_out_x = (RoadToWorld(r, s, a.t_outer) - RoadToWorld(o, os, b.t_inner)).norm();
          // Roads that meet head to head mirror the lane sides: inner meets inner either way.
          EXPECT_LT(std::min(d_in + d_out, d_in_x + d_out_x), 0.02) << "road " << r.id << " lane " << lane.id
                                                                     << " -> road " << o.id << " lane " << to;
          ++checked;
        }
      }
    }
  }
  EXPECT_GT(checked, 100);
}

// Each planView record ends where the next one starts: checks the arc evaluation
// against the file's own start points.
TEST_P(map_carla, PlanViewRecordsAreContinuous) {
  const Map& m = Town(GetParam());
  int joints = 0;
  for (const Road& r : m.Data().roads) {
    for (std::size_t i = 0; i + 1 < r.plan_view.size(); ++i) {
      const Geometry& g = r.plan_view[i];
      const Geometry& n = r.plan_view[i + 1];
      const Pose2 end = EvaluateGeometry(g, g.length);
      EXPECT_LT(std::hypot(end.x - n.x, end.y - n.y), 0.01) << "road " << r.id << " record " << i;
      EXPECT_NEAR(std::remainder(end.hdg - n.hdg, 2 * std::numbers::pi), 0.0, 1e-3) << "road " << r.id;
      ++joints;
    }
  }
  EXPECT_GT(joints, 100);
}

TEST_P(map_carla, NextWalksThroughEveryJunction) {
  const Map& m = Town(GetParam());
  std::set<int> visited;
  int walks = 0;
  for (const LaneNode& n : m.Nodes()) {
    if (n.type != LaneType::Driving || n.successors.empty()) continue;
    // From 1 m before the exit, walk 15 m: no dead end where the file has successors.
    const double back = std::min(1.0, n.Length());
    const Waypoint start = m.MakeWaypoint(n.road, n.section, n.lane, n.ExitS() - (n.Forward() ? back : -back));
    Waypoint w = start;
    for (int step = 0; step < 15; ++step) {
      const auto next = m.Next(w, 1.0);
      ASSERT_FALSE(next.empty()) << "dead end after road " << m.Data().roads[static_cast<std::size_t>(w.road)].id
                                 << " lane " << w.lane;
      w = next.back();
      if (w.IsJunction()) visited.insert(w.junction);
      EXPECT_LT((next.front().transform.location - start.transform.location).norm(), 20.0);
    }
    ++walks;
  }
  EXPECT_EQ(visited.size(), m.Data().junctions.size());
  EXPECT_GT(walks, 50);
}

TEST_P(map_carla, NextThenPreviousReturns) {
  const Map& m = Town(GetParam());
  for (const Waypoint& w : m.GenerateWaypoints(20.0)) {
    for (const Waypoint& n : m.Next(w, 7.0)) {
      const auto back = m.Previous(n, 7.0);
      ASSERT_FALSE(back.empty());
      double best = 1e9;
      for (const Waypoint& b : back) best = std::min(best, (b.transform.location - w.transform.location).norm());
      EXPECT_LT(best, 0.05);
      // Travel direction: the next point lies ahead of the yaw.
      const Eigen::Vector3d d = n.transform.location - w.transform.location;
      EXPECT_GT(d.dot(w.transform.Forward()), 0.0);
    }
  }
}

TEST_P(map_carla, NearestWaypointRecoversLane) {
  const Map& m = Town(GetParam());
  int checked = 0;
  for (const Waypoint& w : m.GenerateWaypoints(3.0)) {
    if (w.IsJunction()) continue;  // junction lanes overlap by design
    const LaneNode& node = m.Nodes()[static_cast<std::size_t>(m.NodeOf(w))];
    if (w.s - node.s_begin < 0.5 || node.s_end - w.s < 0.5) continue;  // shared with the next road
    const double off = 0.3 * w.lane_width;
    const Eigen::Vector3d side(-std::sin(w.transform.yaw), std::cos(w.transform.yaw), 0);
    const Eigen::Vector3d p = w.transform.location + off * side + Eigen::Vector3d(0, 0, 1.0);
    const auto got = m.NearestWaypoint(p);
    ASSERT_TRUE(got);
    EXPECT_EQ(got->road, w.road);
    EXPECT_EQ(got->lane, w.lane);
    EXPECT_NEAR(got->s, w.s, 1e-3);
    const auto inside = m.NearestWaypoint(p, false, LaneType::Any);
    ASSERT_TRUE(inside);
    EXPECT_EQ(inside->lane, w.lane);
    ++checked;
  }
  EXPECT_GT(checked, 500);
}

TEST_P(map_carla, NearestWaypointMatchesBruteForce) {
  const Map& m = Town(GetParam());
  const auto all = m.GenerateWaypoints(0.25, LaneType::Driving | LaneType::Sidewalk);
  const Eigen::Vector2d lo = m.BoundsMin(), hi = m.BoundsMax();
  std::uint64_t state = 12345;
  auto rnd = [&] { state = state * 6364136223846793005ull + 1442695040888963407ull; return (state >> 11) * (1.0 / 9007199254740992.0); };
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector3d p(lo.x() - 20 + rnd() * (hi.x() - lo.x() + 40), lo.y() - 20 + rnd() * (hi.y() - lo.y() + 40), 0);
    const auto got = m.NearestWaypoint(p, true, LaneType::Driving | LaneType::Sidewalk);
    ASSERT_TRUE(got);
    double best = 1e18;
    for (const Waypoint& w : all) best = std::min(best, (w.transform.location - p).head<2>().norm());
    EXPECT_LT((got->transform.location - p).head<2>().norm(), best + 0.05) << p.transpose();
  }
}

TEST_P(map_carla, LaneNeighboursAndMarkings) {
  const Map& m = Town(GetParam());
  int opposite = 0;
  for (const Waypoint& w : m.GenerateWaypoints(10.0)) {
    if (w.IsJunction()) continue;
    const auto left = m.LeftLane(w);
    if (left && left->lane_type == LaneType::Driving) {
      // CARLA towns are two-way, one lane each way: the left neighbour drives the other way.
      const double dyaw = std::remainder(left->transform.yaw - w.transform.yaw, 2 * std::numbers::pi);
      EXPECT_NEAR(std::fabs(dyaw), std::numbers::pi, 0.05);
      ++opposite;
      // The left neighbour sits to the left of the travel direction.
      const Eigen::Vector3d d = left->transform.location - w.transform.location;
      EXPECT_GT(-std::sin(w.transform.yaw) * d.x() + std::cos(w.transform.yaw) * d.y(), 0.0);
    }
    const auto right = m.RightLane(w);
    ASSERT_TRUE(right);  // shoulder or sidewalk
    EXPECT_NE(right->lane_type, LaneType::Driving);
    ASSERT_TRUE(m.RightMarking(w));
    ASSERT_TRUE(m.LeftMarking(w));
  }
  EXPECT_GT(opposite, 100);
}

TEST_P(map_carla, TopologyAndSpawnPoints) {
  const Map& m = Town(GetParam());
  const auto topo = m.Topology();
  EXPECT_GT(topo.size(), 60u);
  for (const auto& [a, b] : topo) EXPECT_EQ(a.road, b.road);
  std::size_t junction_pairs = 0;
  for (std::size_t j = 0; j < m.Data().junctions.size(); ++j) {
    const auto pairs = m.JunctionWaypoints(static_cast<int>(j));
    EXPECT_FALSE(pairs.empty());
    junction_pairs += pairs.size();
  }
  EXPECT_GT(junction_pairs, 40u);
  const auto spawns = m.SpawnPoints();
  EXPECT_GT(spawns.size(), 60u);
  for (const Transform& t : spawns) {
    const auto w = m.NearestWaypoint(t.location);
    ASSERT_TRUE(w);
    EXPECT_LT((w->transform.location - t.location).head<2>().norm(), 0.01);
  }
}

TEST_P(map_carla, SpeedLimits) {
  const Map& m = Town(GetParam());
  for (const Waypoint& w : m.GenerateWaypoints(25.0)) {
    const double v = m.SpeedLimit(w);
    EXPECT_GT(v, 20 / 3.6);
    EXPECT_LT(v, 100 / 3.6);
  }
}

INSTANTIATE_TEST_SUITE_P(Carla, map_carla, ::testing::Values("Town01", "Town02"));

}  // namespace
}  // namespace lockstep::map

namespace lockstep::map {
namespace {

// Each traffic light controls driving lanes whose stop point is the mouth of the
// junction it guards, and it stands on the right of the traffic it controls.
TEST_P(map_carla, TrafficLightsControlJunctionApproaches) {
  const Map& m = Town(GetParam());
  const auto lights = m.TrafficLights();
  EXPECT_EQ(lights.size(), GetParam() == "Town01" ? 36u : 24u);
  for (const TrafficLightInfo& tl : lights) {
    ASSERT_FALSE(tl.stop_waypoints.empty()) << tl.signal_id;
    EXPECT_GE(tl.junction, 0) << tl.signal_id;
    for (const Waypoint& w : tl.stop_waypoints) {
      EXPECT_EQ(w.lane_type, LaneType::Driving);
      // The light is within 15 m of the stop point, to its right.
      const Eigen::Vector3d d = tl.pose.location - w.transform.location;
      EXPECT_LT(d.head<2>().norm(), 15.0) << tl.signal_id;
      EXPECT_LT(-std::sin(w.transform.yaw) * d.x() + std::cos(w.transform.yaw) * d.y(), 0.0) << tl.signal_id;
      // Driving on from the stop point enters the light's junction.
      bool enters = false;
      for (const Waypoint& n : m.Next(w, 2.0)) enters |= n.junction == tl.junction;
      EXPECT_TRUE(enters) << tl.signal_id;
    }
  }
}

}  // namespace
}  // namespace lockstep::map
