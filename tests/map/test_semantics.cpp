// OpenDRIVE semantics that an independent reader checked us against: lane links only
// from link elements, waypoint yaw along the lane centre, paramPoly3 by arc length,
// <border> as the outer edge. Each test writes its own small .xodr.
#include <gtest/gtest.h>

#include "carla_towns.h"
#include "xodr_writer.h"

#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

#include "lockstep/map/map.h"
#include "lockstep/map/town_generator.h"

namespace lockstep::map {
namespace {

using testing::StraightRoad;
using testing::Width;
using testing::WriteAndLoad;
using testing::ParseErrorOf;
using testing::Xodr;

std::vector<int> Successors(const Map& m, const std::string& road, int section, int lane) {
  const int n = m.NodeOf(m.RoadIndex(road), section, lane);
  EXPECT_GE(n, 0) << road << " " << lane;
  return n < 0 ? std::vector<int>{} : m.Nodes()[static_cast<std::size_t>(n)].successors;
}

// Road A (two driving lanes, no lane links) runs into road B, which is shifted 3.5 m
// right by its laneOffset: B's lane -1 continues A's lane -2 (B says so with
// <predecessor id="-2"/>), A's lane -1 ends, and B's lane -2 is of type none.
TEST(map_lane_links, OnlyExplicitLinksAcrossRoads) {
  const std::string a = StraightRoad(
      "A", 0, 50, "<link><successor elementType=\"road\" elementId=\"B\" contactPoint=\"start\"/></link>",
      "<laneSection s=\"0\"><center><lane id=\"0\" type=\"none\"/></center><right>"
      "<lane id=\"-1\" type=\"driving\">" + Width(3.5) + "</lane>"
      "<lane id=\"-2\" type=\"driving\">" + Width(3.5) + "</lane></right></laneSection>");
  const std::string b = StraightRoad(
      "B", 50, 50, "<link><predecessor elementType=\"road\" elementId=\"A\" contactPoint=\"end\"/></link>",
      "<laneSection s=\"0\"><center><lane id=\"0\" type=\"none\"/></center><right>"
      "<lane id=\"-1\" type=\"driving\"><link><predecessor id=\"-2\"/></link>" + Width(3.5) + "</lane>"
      "<lane id=\"-2\" type=\"none\">" + Width(3.5) + "</lane></right></laneSection>",
      "<laneOffset s=\"0\" a=\"-3.5\" b=\"0\" c=\"0\" d=\"0\"/>");
  const Map m = WriteAndLoad(Xodr(a + b));
  const int b1 = m.NodeOf(m.RoadIndex("B"), 0, -1);
  EXPECT_TRUE(Successors(m, "A", 0, -1).empty()) << "lane -1 of A has no link: it must end";
  EXPECT_EQ(Successors(m, "A", 0, -2), std::vector<int>{b1}) << "B's lane -1 names A's lane -2 as predecessor";
  EXPECT_TRUE(m.Nodes()[static_cast<std::size_t>(m.NodeOf(m.RoadIndex("B"), 0, -2))].predecessors.empty());
  // Driving on: no sideways jump, no lane of type none.
  const Waypoint from = m.MakeWaypoint(m.RoadIndex("A"), 0, -2, 45);
  const auto next = m.Next(from, 10);
  ASSERT_EQ(next.size(), 1u);
  EXPECT_EQ(next[0].road_id, "B");
  EXPECT_EQ(next[0].lane, -1);
  EXPECT_EQ(next[0].lane_type, LaneType::Driving);
  EXPECT_NEAR(next[0].transform.location.y(), from.transform.location.y(), 1e-9);
  EXPECT_TRUE(m.Next(m.MakeWaypoint(m.RoadIndex("A"), 0, -1, 45), 10).empty());
}

// The same lane drop inside one road: lane -1 narrows to nothing over section 0, lane
// -2 becomes lane -1 of section 1 (named only by section 1's predecessor list).
TEST(map_lane_links, OnlyExplicitLinksAcrossSections) {
  const std::string c = StraightRoad(
      "C", 0, 100, "",
      "<laneSection s=\"0\"><center><lane id=\"0\" type=\"none\"/></center><right>"
      "<lane id=\"-1\" type=\"driving\">" + Width(3.5, -0.07) + "</lane>"
      "<lane id=\"-2\" type=\"driving\">" + Width(3.5) + "</lane></right></laneSection>"
      "<laneSection s=\"50\"><center><lane id=\"0\" type=\"none\"/></center><right>"
      "<lane id=\"-1\" type=\"driving\"><link><predecessor id=\"-2\"/></link>" + Width(3.5) + "</lane>"
      "<lane id=\"-2\" type=\"none\">" + Width(1.0) + "</lane></right></laneSection>");
  const Map m = WriteAndLoad(Xodr(c));
  EXPECT_TRUE(Successors(m, "C", 0, -1).empty());
  EXPECT_EQ(Successors(m, "C", 0, -2), std::vector<int>{m.NodeOf(0, 1, -1)});
  const auto next = m.Next(m.MakeWaypoint(0, 0, -2, 45), 10);
  ASSERT_EQ(next.size(), 1u);
  EXPECT_EQ(next[0].lane, -1);
  EXPECT_NEAR(next[0].transform.location.y(), -1.75, 1e-9);
}

// The lane-link rule must not cut CARLA's towns or the generated ones: every driving
// lane still continues and is reached (no false dead ends), and every junction is entered.
TEST(map_lane_links, NoDeadEndsInTowns) {
  std::vector<std::pair<std::string, const Map*>> towns = {{"Town01", &Town("Town01")}, {"Town02", &Town("Town02")}};
  const Map g1 = Map::FromString(GenerateTown(TownKind::Town1, 2017).xodr, "LockstepTown1");
  const Map g2 = Map::FromString(GenerateTown(TownKind::Town2, 2017).xodr, "LockstepTown2");
  towns.emplace_back("LockstepTown1", &g1);
  towns.emplace_back("LockstepTown2", &g2);
  for (const auto& [name, m] : towns) {
    int driving = 0;
    std::vector<bool> entered(m->Data().junctions.size(), false);
    for (const LaneNode& n : m->Nodes()) {
      if (n.type != LaneType::Driving) continue;
      ++driving;
      EXPECT_FALSE(n.successors.empty()) << name << " road " << m->Data().roads[static_cast<std::size_t>(n.road)].id
                                         << " lane " << n.lane << " is a dead end";
      EXPECT_FALSE(n.predecessors.empty()) << name << " road " << m->Data().roads[static_cast<std::size_t>(n.road)].id
                                           << " lane " << n.lane << " is never entered";
      for (int k : n.successors) {
        const LaneNode& t = m->Nodes()[static_cast<std::size_t>(k)];
        EXPECT_EQ(t.type, LaneType::Driving) << name << ": a driving lane continues into a lane of another type";
        const int j = m->Data().roads[static_cast<std::size_t>(t.road)].junction_index;
        if (j >= 0) entered[static_cast<std::size_t>(j)] = true;
      }
    }
    EXPECT_GT(driving, 50) << name;
    for (std::size_t j = 0; j < entered.size(); ++j) EXPECT_TRUE(entered[j]) << name << " junction " << j;
  }
}

// A turn pocket: lane -2 widens from 0 to 3.5 m over 20 m (smoothstep cubic), on a
// straight road and on an arc with a sloped laneOffset. The waypoint yaw must be the
// direction of the lane centre (finite differences of waypoint positions).
TEST(map_waypoint_yaw, FollowsWideningAndOffset) {
  const double L = 15, W = 3.5;
  const std::string lanes =
      "<laneSection s=\"0\"><center><lane id=\"0\" type=\"none\"/></center>"
      "<left><lane id=\"1\" type=\"driving\">" + Width(0, 0, 3 * W / (L * L), -2 * W / (L * L * L)) + "</lane></left><right>"
      "<lane id=\"-1\" type=\"driving\">" + Width(3.5) + "</lane>"
      "<lane id=\"-2\" type=\"driving\">" + Width(0, 0, 3 * W / (L * L), -2 * W / (L * L * L)) + "</lane></right></laneSection>";
  const std::string straight = StraightRoad("S", 0, L, "", lanes);
  const std::string arc =
      "<road id=\"R\" length=\"15\" junction=\"-1\"><planView><geometry s=\"0\" x=\"0\" y=\"50\" hdg=\"0.3\" "
      "length=\"15\"><arc curvature=\"0.04\"/></geometry></planView><lanes>"
      "<laneOffset s=\"0\" a=\"0.2\" b=\"0.05\" c=\"0\" d=\"0\"/>" + lanes + "</lanes></road>\n";
  const Map m = WriteAndLoad(Xodr(straight + arc));
  double worst_reference_error = 0;
  for (int road = 0; road < 2; ++road) {
    for (int lane : {-2, -1, 1}) {
      for (double s = 1; s < L; s += 1) {
        const Waypoint w = m.MakeWaypoint(road, 0, lane, s);
        const double h = 1e-5;
        const Eigen::Vector3d d = m.MakeWaypoint(road, 0, lane, s + h).transform.location -
                                  m.MakeWaypoint(road, 0, lane, s - h).transform.location;
        const double along = std::atan2(d.y(), d.x()) + (lane > 0 ? std::numbers::pi : 0.0);
        EXPECT_NEAR(std::remainder(w.transform.yaw - along, 2 * std::numbers::pi), 0.0, 1e-6)
            << "road " << road << " lane " << lane << " s " << s;
        const double ref = EvaluateReferenceLine(m.Data().roads[static_cast<std::size_t>(road)].plan_view, s).hdg +
                           (lane > 0 ? std::numbers::pi : 0.0);
        worst_reference_error = std::max(worst_reference_error, std::fabs(std::remainder(along - ref, 2 * std::numbers::pi)));
      }
    }
  }
  // The reference heading alone would be off by this much (the bug this guards).
  EXPECT_GT(worst_reference_error * 180 / std::numbers::pi, 8.0);
}

// Arc length of u(p), v(p) from 0 to p, by an independent fine trapezoid sum.
struct Curve {
  double bu, cu, du, bv, cv, dv;
  double Speed(double p) const {
    const double u1 = bu + 2 * cu * p + 3 * du * p * p, v1 = bv + 2 * cv * p + 3 * dv * p * p;
    return std::hypot(u1, v1);
  }
  double Length(double p) const {
    const int n = 200000;
    double sum = 0;
    for (int i = 0; i < n; ++i) sum += 0.5 * (Speed(p * i / n) + Speed(p * (i + 1) / n)) * (p / n);
    return sum;
  }
  double ParamAt(double s, double p_max) const {  // bisection on Length
    double lo = 0, hi = p_max;
    for (int i = 0; i < 50; ++i) ((Length(0.5 * (lo + hi)) < s) ? lo : hi) = 0.5 * (lo + hi);
    return 0.5 * (lo + hi);
  }
  Eigen::Vector2d At(double p) const { return {bu * p + cu * p * p + du * p * p * p, bv * p + cv * p * p + dv * p * p * p}; }
};

std::string ParamPoly3Road(const std::string& id, double length, const Curve& c, const std::string& p_range) {
  char buf[1024];
  std::snprintf(buf, sizeof buf,
                "<road id=\"%s\" length=\"%.12f\" junction=\"-1\"><planView><geometry s=\"0\" x=\"10\" y=\"-5\" "
                "hdg=\"0.3\" length=\"%.12f\"><paramPoly3 aU=\"0\" bU=\"%.12g\" cU=\"%.12g\" dU=\"%.12g\" aV=\"0\" "
                "bV=\"%.12g\" cV=\"%.12g\" dV=\"%.12g\"%s/></geometry></planView><lanes><laneSection s=\"0\">"
                "<center><lane id=\"0\" type=\"none\"/></center><right><lane id=\"-1\" type=\"driving\">"
                "<width sOffset=\"0\" a=\"3.5\" b=\"0\" c=\"0\" d=\"0\"/></lane></right></laneSection></lanes></road>\n",
                id.c_str(), length, length, c.bu, c.cu, c.du, c.bv, c.cv, c.dv,
                p_range.empty() ? "" : (" pRange=\"" + p_range + "\"").c_str());
  return buf;
}

// The same curve (u = p, v = 0.01 p^2 - 1e-4 p^3 over p in [0, 40]) written with
// pRange="arcLength", "normalized" and no pRange (which means normalized). Points at
// arc length s must lie where the independent arc-length integral puts them.
TEST(map_param_poly3, ParameterisedByArcLength) {
  const Curve arc{1.0, 0, 0, 0, 0.01, -1e-4};
  const double p_max = 40;
  const Curve norm{arc.bu * p_max, 0, 0, 0, arc.cv * p_max * p_max, arc.dv * p_max * p_max * p_max};
  const double length = arc.Length(p_max);
  ASSERT_GT(length - p_max, 0.5);  // far enough from unit speed to matter
  const Map m = WriteAndLoad(Xodr(ParamPoly3Road("arc", length, arc, "arcLength") +
                                  ParamPoly3Road("norm", length, norm, "normalized") +
                                  ParamPoly3Road("default", length, norm, "")));
  const double c = std::cos(0.3), sn = std::sin(0.3);
  for (double s : {0.0, 5.0, 12.5, 20.0, 31.0, length - 1e-9}) {
    const double p = arc.ParamAt(s, p_max);
    const Eigen::Vector2d uv = arc.At(p);
    const Eigen::Vector2d want(10 + uv.x() * c - uv.y() * sn, -5 + uv.x() * sn + uv.y() * c);
    const double d1u = arc.bu, d1v = 2 * arc.cv * p + 3 * arc.dv * p * p;
    const double want_hdg = 0.3 + std::atan2(d1v, d1u);
    for (const char* road : {"arc", "norm", "default"}) {
      const Pose2 got = EvaluateReferenceLine(m.Data().roads[static_cast<std::size_t>(m.RoadIndex(road))].plan_view, s);
      EXPECT_NEAR(got.x, want.x(), 2e-3) << road << " s=" << s;
      EXPECT_NEAR(got.y, want.y(), 2e-3) << road << " s=" << s;
      EXPECT_NEAR(std::remainder(got.hdg - want_hdg, 2 * std::numbers::pi), 0.0, 1e-4) << road << " s=" << s;
    }
  }
  EXPECT_NE(ParseErrorOf(Xodr(ParamPoly3Road("bad", 10, arc, "metres"))).find("pRange must be 'arcLength' or 'normalized'"),
            std::string::npos);
}

// <border> gives the outer edge's t (from the reference line), so a lane's width is its
// border minus the inner neighbour's edge; the centre lane sits at the laneOffset.
// Width records, where a lane has them, win over borders; widths and borders mix.
TEST(map_border, OuterEdgeNotWidth) {
  auto poly = [](const char* tag, double a, double b) {
    return std::string("<") + tag + " sOffset=\"0\" a=\"" + std::to_string(a) + "\" b=\"" + std::to_string(b) +
           "\" c=\"0\" d=\"0\"/>";
  };
  const std::string road = StraightRoad(
      "B", 0, 40, "",
      "<laneSection s=\"0\"><left>"
      "<lane id=\"2\" type=\"sidewalk\">" + poly("border", 7.0, 0) + "</lane>"
      "<lane id=\"1\" type=\"driving\">" + poly("width", 3.0, 0) + poly("border", 99, 0) + "</lane></left>"
      "<center><lane id=\"0\" type=\"none\"/></center><right>"
      "<lane id=\"-1\" type=\"driving\">" + poly("border", -3.0, 0) + "</lane>"
      "<lane id=\"-2\" type=\"driving\">" + poly("border", -6.5, -0.02) + "</lane></right></laneSection>",
      "<laneOffset s=\"0\" a=\"0.5\" b=\"0.01\" c=\"0\" d=\"0\"/>");
  const Map m = WriteAndLoad(Xodr(road));
  for (double s : {0.0, 10.0, 25.0, 39.0}) {
    const double offset = 0.5 + 0.01 * s;
    struct Want { int lane; double inner, outer; };
    for (const Want& w : {Want{-1, offset, -3.0}, Want{-2, -3.0, -6.5 - 0.02 * s}, Want{1, offset, offset + 3.0},
                          Want{2, offset + 3.0, 7.0}}) {
      const Waypoint wp = m.MakeWaypoint(0, 0, w.lane, s);
      EXPECT_NEAR(wp.lane_width, std::fabs(w.outer - w.inner), 1e-9) << "lane " << w.lane << " s " << s;
      EXPECT_NEAR(wp.transform.location.y(), 0.5 * (w.inner + w.outer), 1e-9) << "lane " << w.lane << " s " << s;
    }
  }
  // The borders stay available as read.
  ASSERT_EQ(m.Data().roads[0].sections[0].Find(-2)->borders.size(), 1u);
  EXPECT_DOUBLE_EQ(m.Data().roads[0].sections[0].Find(-2)->borders[0].a, -6.5);
}

}  // namespace
}  // namespace lockstep::map
