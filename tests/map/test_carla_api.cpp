// The CARLA-shaped queries: get_waypoint_xodr, OpenDRIVE ids on waypoints,
// next_until_lane_end / previous_until_lane_start, carla.Junction.
#include <gtest/gtest.h>

#include "carla_towns.h"
#include "xodr_writer.h"

#include <cmath>
#include <string>

#include "lockstep/map/map.h"

namespace lockstep::map {
namespace {

using testing::StraightRoad;
using testing::Width;
using testing::WriteAndLoad;
using testing::Xodr;

// Road "17": section 0 (s 0..40) has lanes 1, -1; section 1 (s 40..100) adds lane -2.
const Map& TwoSections() {
  static const Map m = [] {
    const std::string sec0 =
        "<laneSection s=\"0\"><left><lane id=\"1\" type=\"driving\"><link><successor id=\"1\"/></link>" +
        Width(3.5) + "</lane></left><center><lane id=\"0\" type=\"none\"/></center><right>"
        "<lane id=\"-1\" type=\"driving\"><link><successor id=\"-1\"/></link>" + Width(3.5) + "</lane></right></laneSection>";
    const std::string sec1 =
        "<laneSection s=\"40\"><left><lane id=\"1\" type=\"driving\"><link><predecessor id=\"1\"/></link>" +
        Width(3.5) + "</lane></left><center><lane id=\"0\" type=\"none\"/></center><right>"
        "<lane id=\"-1\" type=\"driving\"><link><predecessor id=\"-1\"/></link>" + Width(3.5) + "</lane>"
        "<lane id=\"-2\" type=\"sidewalk\">" + Width(2.0) + "</lane></right></laneSection>";
    return WriteAndLoad(Xodr(StraightRoad("17", 0, 100, "", sec0 + sec1)));
  }();
  return m;
}

TEST(map_carla_api, WaypointXodrLikeGetWaypointXodr) {
  const Map& m = TwoSections();
  const auto w = m.WaypointXodr("17", -1, 12.5);
  ASSERT_TRUE(w.has_value());
  EXPECT_EQ(w->road_id, "17");
  EXPECT_EQ(w->road, 0);
  EXPECT_EQ(w->section, 0);
  EXPECT_EQ(w->SectionId(), 0);
  EXPECT_EQ(w->lane, -1);
  EXPECT_EQ(w->junction_id, "-1");
  EXPECT_DOUBLE_EQ(w->s, 12.5);
  EXPECT_NEAR(w->transform.location.x(), 12.5, 1e-12);
  EXPECT_NEAR(w->transform.location.y(), -1.75, 1e-12);
  EXPECT_EQ(w->lane_type, LaneType::Driving);
  // Numeric ids as CARLA takes them.
  ASSERT_TRUE(m.WaypointXodr(17, -1, 12.5).has_value());
  EXPECT_EQ(m.WaypointXodr(17, -1, 12.5)->id, w->id);
  // Lane -2 exists only in section 1.
  EXPECT_FALSE(m.WaypointXodr("17", -2, 12.5).has_value());
  const auto side = m.WaypointXodr("17", -2, 70);
  ASSERT_TRUE(side.has_value());
  EXPECT_EQ(side->section, 1);
  EXPECT_EQ(side->lane_type, LaneType::Sidewalk);
  // At the section boundary s = 40 both sections hold s: lane -2 is found in section 1,
  // lane -1 too (the later section wins where both have the lane).
  EXPECT_EQ(m.WaypointXodr("17", -2, 40)->section, 1);
  EXPECT_EQ(m.WaypointXodr("17", -1, 40)->section, 1);
  // Nothing for what does not exist; s is not clamped.
  EXPECT_FALSE(m.WaypointXodr("17", -3, 50).has_value());
  EXPECT_FALSE(m.WaypointXodr("17", 2, 50).has_value());
  EXPECT_FALSE(m.WaypointXodr("17", 0, 50).has_value());
  EXPECT_FALSE(m.WaypointXodr("18", -1, 50).has_value());
  EXPECT_FALSE(m.WaypointXodr("17", -1, -0.1).has_value());
  EXPECT_FALSE(m.WaypointXodr("17", -1, 100).has_value());  // [0, length), as CARLA
  EXPECT_FALSE(m.WaypointXodr("17", -1, std::nan("")).has_value());
  EXPECT_TRUE(m.WaypointXodr("17", -1, 99.99).has_value());
}

TEST(map_carla_api, UntilLaneEndAndStartAcrossSections) {
  const Map& m = TwoSections();
  // Lane -1 drives with s: 12.5 -> 30 steps of 7 m to 96.5, then the road end.
  auto next = m.NextUntilLaneEnd(*m.WaypointXodr("17", -1, 12.5), 7);
  ASSERT_EQ(next.size(), 13u);
  for (std::size_t i = 0; i + 1 < next.size(); ++i) EXPECT_NEAR(next[i].s, 12.5 + 7.0 * static_cast<double>(i + 1), 1e-9);
  EXPECT_NEAR(next.back().s, 100, 1e-9);
  EXPECT_EQ(next.back().section, 1);
  auto prev = m.PreviousUntilLaneStart(*m.WaypointXodr("17", -1, 50), 7);
  ASSERT_EQ(prev.size(), 8u);  // 43, 36, ..., 1, then s = 0
  EXPECT_NEAR(prev[0].s, 43, 1e-9);
  EXPECT_EQ(prev[0].section, 1);
  EXPECT_EQ(prev[1].section, 0);
  EXPECT_NEAR(prev[6].s, 1, 1e-9);
  EXPECT_NEAR(prev.back().s, 0, 1e-9);
  // Lane 1 drives against s: its lane start is the road's end.
  prev = m.PreviousUntilLaneStart(*m.WaypointXodr("17", 1, 50), 20);
  ASSERT_EQ(prev.size(), 3u);
  EXPECT_NEAR(prev[0].s, 70, 1e-9);
  EXPECT_NEAR(prev[1].s, 90, 1e-9);
  EXPECT_NEAR(prev[2].s, 100, 1e-9);
  next = m.NextUntilLaneEnd(*m.WaypointXodr("17", 1, 50), 20);
  ASSERT_EQ(next.size(), 3u);
  EXPECT_NEAR(next[1].s, 10, 1e-9);
  EXPECT_NEAR(next[2].s, 0, 1e-9);
  EXPECT_TRUE(m.NextUntilLaneEnd(*m.WaypointXodr("17", 1, 50), 0).empty());
}

// On CARLA's towns: next_until_lane_end stays on the road and ends at its end, and the
// point after it (Next) is on another road.
TEST(map_carla_api, UntilLaneEndOnTown01) {
  const Map& m = Town("Town01");
  int checked = 0;
  for (const auto& [entry, exit] : m.Topology()) {
    const auto until = m.NextUntilLaneEnd(entry, 2.0);
    ASSERT_FALSE(until.empty());
    for (const Waypoint& w : until) EXPECT_EQ(w.road, entry.road);
    const Road& road = m.Data().roads[static_cast<std::size_t>(entry.road)];
    EXPECT_NEAR(until.back().s, entry.lane < 0 ? road.length : 0.0, 1e-9);
    const auto back = m.PreviousUntilLaneStart(until.back(), 2.0);
    ASSERT_FALSE(back.empty());
    EXPECT_NEAR(back.back().s, entry.s, 1e-9);
    ++checked;
  }
  EXPECT_GT(checked, 100);
}

// Lane change availability follows the road mark in force at s (CARLA's wp.lane_change):
// the centre line is solid for 20 m, then broken.
TEST(map_carla_api, LaneChangeFollowsMarkAlongTheLane) {
  const std::string lanes =
      "<laneSection s=\"0\"><left><lane id=\"1\" type=\"driving\">" + Width(3.5) +
      "</lane></left><center><lane id=\"0\" type=\"none\"><roadMark sOffset=\"20\" type=\"broken\"/>"
      "<roadMark sOffset=\"0\" type=\"solid\"/></lane></center><right><lane id=\"-1\" type=\"driving\">" +
      Width(3.5) + "</lane></right></laneSection>";
  const Map m = WriteAndLoad(Xodr(StraightRoad("m", 0, 40, "", lanes)));
  const Waypoint solid = *m.WaypointXodr("m", -1, 10), broken = *m.WaypointXodr("m", -1, 30);
  EXPECT_EQ(m.LeftMarking(solid)->type, RoadMarkType::Solid);
  EXPECT_EQ(m.LeftMarking(broken)->type, RoadMarkType::Broken);
  EXPECT_EQ(m.AllowedLaneChange(solid), LaneChange::None);
  EXPECT_EQ(m.AllowedLaneChange(broken), LaneChange::Left);
}

TEST(map_carla_api, JunctionObjects) {
  const Map& m = Town("Town01");
  ASSERT_EQ(m.Junctions().size(), m.Data().junctions.size());
  for (const JunctionInfo& j : m.Junctions()) {
    EXPECT_EQ(j.id, m.Data().junctions[static_cast<std::size_t>(j.index)].id);
    ASSERT_TRUE(m.JunctionById(j.id).has_value());
    EXPECT_EQ(m.JunctionById(j.id)->index, j.index);
    EXPECT_GT(j.bounding_box.extent.x(), 3.0);
    EXPECT_GT(j.bounding_box.extent.y(), 3.0);
    const auto pairs = m.JunctionWaypoints(j.index, LaneType::Any);
    ASSERT_FALSE(pairs.empty());
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e9), hi = -lo;
    for (const auto& [in, out] : pairs) {
      for (const Waypoint* w : {&in, &out}) {
        EXPECT_EQ(w->junction, j.index);
        EXPECT_EQ(w->junction_id, j.id);
        ASSERT_TRUE(m.JunctionOf(*w).has_value());
        EXPECT_EQ(m.JunctionOf(*w)->id, j.id);
        lo = lo.cwiseMin(w->transform.location);
        hi = hi.cwiseMax(w->transform.location);
        const Eigen::Vector3d d = (w->transform.location - j.bounding_box.location).cwiseAbs();
        EXPECT_LE(d.x(), j.bounding_box.extent.x() + 1e-9);
        EXPECT_LE(d.y(), j.bounding_box.extent.y() + 1e-9);
      }
    }
    // The box is that of the lane centres: its faces touch some lane's centre line,
    // not far outside the entry/exit points (turn arcs bulge a little beyond them).
    const Eigen::Vector3d box_lo = j.bounding_box.location - j.bounding_box.extent;
    const Eigen::Vector3d box_hi = j.bounding_box.location + j.bounding_box.extent;
    EXPECT_LT((lo - box_lo).head<2>().cwiseAbs().maxCoeff(), 5.0);
    EXPECT_LT((hi - box_hi).head<2>().cwiseAbs().maxCoeff(), 5.0);
  }
  const Waypoint outside = m.Topology().front().first;
  if (!outside.IsJunction()) {
    EXPECT_FALSE(m.JunctionOf(outside).has_value());
  }
  EXPECT_FALSE(m.JunctionById("no such junction").has_value());
}

}  // namespace
}  // namespace lockstep::map
