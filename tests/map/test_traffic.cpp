// What a Traffic Manager looks up in the map: stop/yield signs with their stop lines,
// trigger volumes, landmarks ahead on a lane, crosswalk polygons.
#include <gtest/gtest.h>

#include "carla_towns.h"
#include "xodr_writer.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "lockstep/map/map.h"
#include "lockstep/map/map_info.h"
#include "lockstep/map/town_generator.h"

namespace lockstep::map {
namespace {

using testing::Width;
using testing::WriteAndLoad;
using testing::Xodr;

// Road "in" (x 0..50, lanes 1 and -1) ends in junction "J"; connecting road "c"
// carries lane -1 on to x 70. A stop sign at s 45 on the right (t -4), a speed sign for
// the other direction, a 50 km/h sign on the connecting road, a crosswalk at s 20.
const Map& Crossing() {
  static const Map m = [] {
    const std::string lanes =
        "<laneSection s=\"0\"><left><lane id=\"1\" type=\"driving\">" + Width(3.5) +
        "</lane></left><center><lane id=\"0\" type=\"none\"/></center><right><lane id=\"-1\" type=\"driving\">" +
        Width(3.5) + "</lane></right></laneSection>";
    const std::string in =
        "<road id=\"in\" length=\"50\" junction=\"-1\"><link><successor elementType=\"junction\" elementId=\"J\"/></link>"
        "<planView><geometry s=\"0\" x=\"0\" y=\"0\" hdg=\"0\" length=\"50\"><line/></geometry></planView>"
        "<lanes>" + lanes + "</lanes>"
        "<objects><object id=\"cw\" type=\"crosswalk\" s=\"20\" t=\"0\" zOffset=\"0\" hdg=\"0\" length=\"3\" width=\"7\">"
        "<outline><cornerLocal u=\"-1.5\" v=\"-3.5\" z=\"0\"/><cornerLocal u=\"1.5\" v=\"-3.5\" z=\"0\"/>"
        "<cornerLocal u=\"1.5\" v=\"3.5\" z=\"0\"/><cornerLocal u=\"-1.5\" v=\"3.5\" z=\"0\"/></outline></object>"
        "<object id=\"cw2\" type=\"Crosswalk\" s=\"10\" t=\"0\" zOffset=\"0\" hdg=\"0\" length=\"2\" width=\"6\"/></objects>"
        "<signals><signal id=\"stop1\" name=\"Stop\" s=\"45\" t=\"-4\" zOffset=\"0\" orientation=\"+\" dynamic=\"no\" "
        "country=\"DE\" type=\"206\" subtype=\"-1\" value=\"-1\" height=\"2\" width=\"0.6\"/>"
        "<signal id=\"speed_back\" name=\"Speed\" s=\"30\" t=\"4\" zOffset=\"2\" orientation=\"-\" dynamic=\"no\" "
        "country=\"DE\" type=\"274\" subtype=\"-1\" value=\"30\" unit=\"km/h\" height=\"0.6\" width=\"0.6\"/></signals>"
        "</road>\n";
    const std::string c =
        "<road id=\"c\" length=\"20\" junction=\"J\"><link><predecessor elementType=\"road\" elementId=\"in\" "
        "contactPoint=\"end\"/></link><planView><geometry s=\"0\" x=\"50\" y=\"0\" hdg=\"0\" length=\"20\"><line/>"
        "</geometry></planView><lanes><laneSection s=\"0\"><center><lane id=\"0\" type=\"none\"/></center><right>"
        "<lane id=\"-1\" type=\"driving\"><link><predecessor id=\"-1\"/></link>" + Width(3.5) +
        "</lane></right></laneSection></lanes><signals><signal id=\"speed50\" name=\"Speed\" s=\"5\" t=\"-4\" "
        "orientation=\"+\" dynamic=\"no\" type=\"274\" subtype=\"-1\" value=\"50\" unit=\"km/h\"/>"
        "<signalReference id=\"stop1\" s=\"2\" t=\"-4\" orientation=\"+\"/></signals></road>\n";
    const std::string j =
        "<junction id=\"J\" name=\"J\"><connection id=\"0\" incomingRoad=\"in\" connectingRoad=\"c\" contactPoint=\"start\">"
        "<laneLink from=\"-1\" to=\"-1\"/></connection></junction>\n";
    return WriteAndLoad(Xodr(in + c + j));
  }();
  return m;
}

TEST(map_traffic, StopSignsWithStopLineAndTriggerVolume) {
  const Map& m = Crossing();
  const auto signs = m.StopSigns();
  ASSERT_EQ(signs.size(), 1u);
  const TrafficLightInfo& stop = signs[0];
  EXPECT_EQ(stop.signal_id, "stop1");
  EXPECT_EQ(stop.type, "206");
  EXPECT_EQ(stop.junction, m.JunctionById("J")->index);
  ASSERT_EQ(stop.stop_waypoints.size(), 1u);
  EXPECT_EQ(stop.stop_waypoints[0].road_id, "in");
  EXPECT_EQ(stop.stop_waypoints[0].lane, -1);
  EXPECT_NEAR(stop.stop_waypoints[0].s, 50, 1e-9);
  EXPECT_TRUE(m.TrafficLights().empty());
  // The trigger volume: the last 3 m of lane -1 before the stop line, the lane's width.
  const BoundingBox& v = stop.trigger_volume;
  EXPECT_NEAR(v.location.x(), 48.5, 1e-9);
  EXPECT_NEAR(v.location.y(), -1.75, 1e-9);
  EXPECT_NEAR(v.extent.x(), 1.5, 1e-9);
  EXPECT_NEAR(v.extent.y(), 1.75, 1e-9);
  EXPECT_TRUE(v.Contains({47.5, -1.0, 0.5}));
  EXPECT_FALSE(v.Contains({51.0, -1.75, 0.5}));   // past the stop line
  EXPECT_FALSE(v.Contains({48.5, 1.75, 0.5}));    // the other direction's lane
  EXPECT_FALSE(v.Contains({44.0, -1.75, 0.5}));   // too far back
}

TEST(map_traffic, LandmarksAheadOnTheLane) {
  const Map& m = Crossing();
  const Waypoint w = *m.WaypointXodr("in", -1, 10);
  auto found = m.LandmarksAhead(w, 100);
  ASSERT_EQ(found.size(), 2u);
  EXPECT_EQ(found[0].id, "stop1");
  EXPECT_NEAR(found[0].distance, 35, 1e-9);
  EXPECT_EQ(found[0].waypoint.lane, -1);
  EXPECT_NEAR(found[0].waypoint.s, 45, 1e-9);
  EXPECT_EQ(found[1].id, "speed50");  // on the connecting road, past the junction entry
  EXPECT_NEAR(found[1].distance, 45, 1e-9);
  EXPECT_EQ(found[1].waypoint.road_id, "c");
  EXPECT_DOUBLE_EQ(found[1].value, 50);
  EXPECT_TRUE(m.LandmarksAhead(w, 30).empty());
  // A <signalReference> repeats the stop sign on the connecting road at its own s.
  found = m.LandmarksAhead(*m.WaypointXodr("c", -1, 0.5), 10);
  ASSERT_EQ(found.size(), 2u);
  EXPECT_EQ(found[0].id, "stop1");
  EXPECT_NEAR(found[0].distance, 1.5, 1e-9);
  EXPECT_EQ(found[0].road, m.RoadIndex("c"));
  ASSERT_EQ(m.LandmarksAhead(w, 100, /*stop_at_junction=*/true).size(), 1u);
  // The other direction sees only its own sign (orientation "-"), and not behind it.
  const Waypoint back = *m.WaypointXodr("in", 1, 40);
  found = m.LandmarksAhead(back, 100);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].id, "speed_back");
  EXPECT_NEAR(found[0].distance, 10, 1e-9);
  EXPECT_TRUE(m.LandmarksAhead(*m.WaypointXodr("in", 1, 20), 100).empty());
  // Driving lane 1 from s 49 passes the stop sign's s, but the sign faces lane -1.
  found = m.LandmarksAhead(*m.WaypointXodr("in", 1, 49), 100);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].id, "speed_back");
  EXPECT_NEAR(found[0].distance, 19, 1e-9);
}

TEST(map_traffic, CrosswalkPolygons) {
  const auto zones = Crossing().Crosswalks();
  ASSERT_EQ(zones.size(), 2u);
  // Without an outline: its length along the road by its width across.
  ASSERT_EQ(zones[1].size(), 5u);
  EXPECT_NEAR(zones[1][0].x(), 9.0, 1e-9);
  EXPECT_NEAR(zones[1][0].y(), -3.0, 1e-9);
  EXPECT_NEAR(zones[1][2].x(), 11.0, 1e-9);
  EXPECT_NEAR(zones[1][2].y(), 3.0, 1e-9);
  ASSERT_EQ(zones[0].size(), 5u);
  EXPECT_EQ(zones[0].front(), zones[0].back());
  EXPECT_NEAR(zones[0][0].x(), 18.5, 1e-9);
  EXPECT_NEAR(zones[0][0].y(), -3.5, 1e-9);
  EXPECT_NEAR(zones[0][2].x(), 21.5, 1e-9);
  EXPECT_NEAR(zones[0][2].y(), 3.5, 1e-9);
  // Generated towns: one polygon per crosswalk object, across the driving lanes.
  const Map g = Map::FromString(GenerateTown(TownKind::Town2, 2017).xodr, "LockstepTown2");
  const auto gz = g.Crosswalks();
  EXPECT_EQ(static_cast<int>(gz.size()), ComputeStats(g).crosswalks);
  ASSERT_FALSE(gz.empty());
  for (const auto& poly : gz) {
    ASSERT_EQ(poly.size(), 5u);
    const Eigen::Vector3d centre = 0.25 * (poly[0] + poly[1] + poly[2] + poly[3]);
    bool on_driving = false;
    for (const LanePoint& lp : g.LanesAt(centre.x(), centre.y()))
      on_driving |= g.Nodes()[static_cast<std::size_t>(lp.node)].type == LaneType::Driving;
    EXPECT_TRUE(on_driving);
  }
}

// In the generated towns and CARLA's Town01, a vehicle 1 m before a traffic light's
// stop line is inside its trigger volume, and 1 m into the junction it is not; a
// vehicle 20 m before the stop line sees the light among the landmarks ahead.
TEST(map_traffic, TrafficLightTriggerVolumesAndLandmarks) {
  const Map g = Map::FromString(GenerateTown(TownKind::Town1, 2017).xodr, "LockstepTown1");
  for (const Map* m : {&g, &Town("Town01")}) {
    int checked = 0;
    for (const TrafficLightInfo& tl : m->TrafficLights()) {
      for (const Waypoint& stop : tl.stop_waypoints) {
        for (const Waypoint& before : m->Previous(stop, 1.0))
          EXPECT_TRUE(tl.trigger_volume.Contains(before.transform.location + Eigen::Vector3d(0, 0, 0.5)))
              << m->Name() << " light " << tl.signal_id;
        for (const Waypoint& after : m->Next(stop, 1.0))
          EXPECT_FALSE(tl.trigger_volume.Contains(after.transform.location + Eigen::Vector3d(0, 0, 0.5)))
              << m->Name() << " light " << tl.signal_id;
        for (const Waypoint& approach : m->Previous(stop, 20.0)) {
          const auto ahead = m->LandmarksAhead(approach, 30.0);
          EXPECT_TRUE(std::any_of(ahead.begin(), ahead.end(), [&](const Landmark& l) { return l.id == tl.signal_id; }))
              << m->Name() << " light " << tl.signal_id;
        }
        ++checked;
      }
    }
    EXPECT_GT(checked, 20) << m->Name();
  }
}

}  // namespace
}  // namespace lockstep::map
