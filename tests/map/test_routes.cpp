#include <gtest/gtest.h>

#include "carla_towns.h"

#include <cmath>
#include <map>
#include <numbers>

#include "lockstep/map/lane_invasion.h"
#include "lockstep/map/route_planner.h"

namespace lockstep::map {
namespace {

class map_routes : public ::testing::TestWithParam<std::string> {};

TEST_P(map_routes, RouteExistsBetweenSpawnPoints) {
  const Map& m = Town(GetParam());
  const auto spawns = m.SpawnPoints();
  ASSERT_GT(spawns.size(), 20u);
  int turns = 0;
  for (std::size_t i = 0; i < 40; ++i) {
    const Transform& a = spawns[(i * 7) % spawns.size()];
    const Transform& b = spawns[(i * 13 + 5) % spawns.size()];
    const auto route = PlanRoute(m, a.location, b.location);
    ASSERT_TRUE(route) << i;
    ASSERT_GE(route->steps.size(), 1u);
    EXPECT_LT((route->steps.front().waypoint.transform.location - a.location).head<2>().norm(), 0.05);
    EXPECT_LT((route->steps.back().waypoint.transform.location - b.location).head<2>().norm(), 0.05);
    double along = 0;
    for (std::size_t k = 1; k < route->steps.size(); ++k) {
      const RouteStep& p = route->steps[k - 1];
      const RouteStep& q = route->steps[k];
      const double d = (q.waypoint.transform.location - p.waypoint.transform.location).norm();
      const bool change = q.option == RoadOption::ChangeLaneLeft || q.option == RoadOption::ChangeLaneRight;
      EXPECT_LT(d, change ? 6.0 : 2.1) << "gap in route " << i << " at step " << k;
      along += d;
      EXPECT_EQ(q.waypoint.lane_type, LaneType::Driving);
      if (q.waypoint.IsJunction()) {
        EXPECT_NE(q.option, RoadOption::LaneFollow);
        turns += q.option == RoadOption::Left || q.option == RoadOption::Right;
      } else if (!change) {
        EXPECT_EQ(q.option, RoadOption::LaneFollow);
      }
    }
    EXPECT_NEAR(along, route->length_m, 0.05 * route->length_m + 1.0);
  }
  EXPECT_GT(turns, 0);
}

// The command at each junction agrees with the heading change measured on the route.
TEST_P(map_routes, JunctionCommandsMatchHeadingChange) {
  const Map& m = Town(GetParam());
  const auto spawns = m.SpawnPoints();
  int checked = 0;
  for (std::size_t i = 0; i < 30; ++i) {
    const auto route = PlanRoute(m, spawns[(i * 11) % spawns.size()].location, spawns[(i * 3 + 17) % spawns.size()].location);
    ASSERT_TRUE(route);
    const auto& st = route->steps;
    for (std::size_t k = 1; k < st.size(); ++k) {
      if (!st[k].waypoint.IsJunction() || st[k - 1].waypoint.IsJunction()) continue;
      std::size_t e = k;
      while (e + 1 < st.size() && st[e + 1].waypoint.IsJunction()) ++e;
      if (e + 1 >= st.size()) break;
      const double turn = std::remainder(st[e + 1].waypoint.transform.yaw - st[k - 1].waypoint.transform.yaw, 2 * std::numbers::pi);
      const RoadOption expect = std::fabs(turn) < 0.5236 ? RoadOption::Straight : turn > 0 ? RoadOption::Left : RoadOption::Right;
      if (std::fabs(std::fabs(turn) - 0.5236) > 0.1) {
        EXPECT_EQ(st[k].option, expect) << "turn " << turn;
      }
      ++checked;
    }
  }
  EXPECT_GT(checked, 10);
}

TEST_P(map_routes, UnreachableGivesNothing) {
  const Map& m = Town(GetParam());
  Waypoint bogus;
  EXPECT_FALSE(PlanRoute(m, bogus, bogus));
}

INSTANTIATE_TEST_SUITE_P(Carla, map_routes, ::testing::Values("Town01", "Town02"));

// A straight two-way road: solid yellow centre line, broken white between the two
// right lanes, curb before the sidewalk.
const char* kStraightRoad = R"(<?xml version="1.0"?>
<OpenDRIVE><header revMajor="1" revMinor="6"/>
<road id="7" length="100" junction="-1">
  <type s="0" type="town"><speed max="50" unit="km/h"/></type>
  <planView><geometry s="0" x="0" y="0" hdg="0" length="100"><line/></geometry></planView>
  <lanes><laneSection s="0">
    <left><lane id="1" type="driving"><width sOffset="0" a="3.5" b="0" c="0" d="0"/>
      <roadMark sOffset="0" type="solid" color="white" width="0.12" laneChange="none"/></lane></left>
    <center><lane id="0" type="none"><roadMark sOffset="0" type="solid" color="yellow" width="0.15" laneChange="none"/></lane></center>
    <right>
      <lane id="-1" type="driving"><width sOffset="0" a="3.5" b="0" c="0" d="0"/>
        <roadMark sOffset="0" type="broken" color="white" width="0.12" laneChange="both"/></lane>
      <lane id="-2" type="driving"><width sOffset="0" a="3.5" b="0" c="0" d="0"/>
        <roadMark sOffset="0" type="curb" width="0.15" laneChange="none"/></lane>
      <lane id="-3" type="sidewalk"><width sOffset="0" a="3" b="0" c="0" d="0"/></lane>
    </right>
  </laneSection></lanes>
  <signals><signal id="1" s="50" t="-9" type="274" value="30" unit="km/h" orientation="+"/></signals>
</road></OpenDRIVE>)";

TEST(map_invasion, CrossingSolidCentreLineIsReported) {
  const Map m = Map::FromString(kStraightRoad);
  // Lane -1 centre is at y = -1.75; drive the car 2 m to the left, across y = 0.
  const Footprint before = MakeFootprint({20, -1.75}, 0, 2.2, 0.9);
  const Footprint after = MakeFootprint({21, 0.25}, 0, 2.2, 0.9);
  const auto crossed = CrossedLaneMarkings(m, before, after);
  ASSERT_EQ(crossed.size(), 1u);
  EXPECT_EQ(crossed[0].marking.type, RoadMarkType::Solid);
  EXPECT_EQ(crossed[0].marking.color, RoadMarkColor::Yellow);
  EXPECT_EQ(crossed[0].marking.lane_change, LaneChange::None);
  // Staying inside the lane crosses nothing.
  EXPECT_TRUE(CrossedLaneMarkings(m, before, MakeFootprint({25, -1.6}, 0, 2.2, 0.9)).empty());
  // Moving right into lane -2 crosses the broken line.
  const auto right = CrossedLaneMarkings(m, before, MakeFootprint({21, -3.6}, 0, 2.2, 0.9));
  ASSERT_EQ(right.size(), 1u);
  EXPECT_EQ(right[0].marking.type, RoadMarkType::Broken);
}

TEST(map_invasion, FootprintOverlapFractions) {
  const Map m = Map::FromString(kStraightRoad);
  auto own = ComputeFootprintOverlap(m, MakeFootprint({30, -1.75}, 0, 2.0, 0.9), 0);
  EXPECT_DOUBLE_EQ(own.opposite_lane, 0);
  EXPECT_DOUBLE_EQ(own.offroad, 0);
  auto wrong = ComputeFootprintOverlap(m, MakeFootprint({30, 1.75}, 0, 2.0, 0.9), 0);
  EXPECT_DOUBLE_EQ(wrong.opposite_lane, 1);
  auto half = ComputeFootprintOverlap(m, MakeFootprint({30, 0.0}, 0, 2.0, 0.9), 0);
  EXPECT_NEAR(half.opposite_lane, 0.5, 1e-9);
  auto kerb = ComputeFootprintOverlap(m, MakeFootprint({30, -8.5}, 0, 2.0, 0.9), 0);
  EXPECT_DOUBLE_EQ(kerb.offroad, 1);
  EXPECT_DOUBLE_EQ(kerb.sidewalk, 1);
  // Driving the wrong way in lane -1 counts as the opposite lane.
  EXPECT_DOUBLE_EQ(ComputeFootprintOverlap(m, MakeFootprint({30, -1.75}, std::numbers::pi, 2.0, 0.9), std::numbers::pi).opposite_lane, 1);
}

TEST(map_invasion, LaneChangePermissionFromMarks) {
  const Map m = Map::FromString(kStraightRoad);
  const Waypoint w1 = *m.NearestWaypoint({40, -1.75, 0});
  const Waypoint w2 = *m.NearestWaypoint({40, -5.25, 0});
  EXPECT_EQ(w1.lane, -1);
  EXPECT_EQ(w2.lane, -2);
  EXPECT_EQ(m.AllowedLaneChange(w1), LaneChange::Right);  // solid centre on the left, broken on the right
  EXPECT_EQ(m.AllowedLaneChange(w2), LaneChange::Left);   // curb on the right
  EXPECT_EQ(m.LeftMarking(w1)->type, RoadMarkType::Solid);
  EXPECT_EQ(m.RightMarking(w2)->type, RoadMarkType::Curb);
  const Waypoint w3 = *m.NearestWaypoint({40, 1.75, 0});
  EXPECT_EQ(w3.lane, 1);
  EXPECT_EQ(m.AllowedLaneChange(w3), LaneChange::None);
  // Speed: the 30 km/h sign at s = 50 applies after it, the road's 50 km/h before.
  EXPECT_NEAR(m.SpeedLimit(*m.NearestWaypoint({60, -1.75, 0})), 30 / 3.6, 1e-9);
  EXPECT_NEAR(m.SpeedLimit(w1), 50 / 3.6, 1e-9);
  EXPECT_NEAR(m.SpeedLimit(w3), 50 / 3.6, 1e-9);  // sign serves the other direction
  EXPECT_NEAR(m.SpeedLimitAt({70, -2.0, 0}), 30 / 3.6, 1e-9);
  EXPECT_NEAR(m.SpeedLimitAt({10, -2.0, 0}), 50 / 3.6, 1e-9);
  // Sidewalk query with a lane type mask.
  EXPECT_EQ(m.NearestWaypoint({40, -20, 0}, true, LaneType::Sidewalk)->lane, -3);
  EXPECT_FALSE(m.NearestWaypoint({40, -20, 0}, false, LaneType::Any));
  // Route with a lane change: from lane -1 to lane -2 further on.
  const auto r = PlanRoute(m, w1, m.MakeWaypoint(w2.road, w2.section, -2, 90));
  ASSERT_TRUE(r);
  bool changed = false;
  for (const RouteStep& s : r->steps) changed |= s.option == RoadOption::ChangeLaneRight;
  EXPECT_TRUE(changed);
}

}  // namespace
}  // namespace lockstep::map
