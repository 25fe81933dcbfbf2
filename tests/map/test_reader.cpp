#include <gtest/gtest.h>

#include <string>

#include "lockstep/map/map.h"
#include "lockstep/map/opendrive_reader.h"

namespace lockstep::map {
namespace {

const std::string kDir = LOCKSTEP_CARLA_MAPS_DIR;

TEST(map_reader, LoadsTown01) {
  const OpenDrive od = LoadOpenDriveFile(kDir + "/Town01.xodr");
  EXPECT_EQ(od.roads.size(), 122u);
  EXPECT_EQ(od.junctions.size(), 12u);
  EXPECT_EQ(od.header.rev_major, 1);
  EXPECT_EQ(od.header.rev_minor, 4);
  EXPECT_EQ(od.header.vendor, "VectorZero");
  EXPECT_NE(od.header.geo_reference.find("+proj=tmerc"), std::string::npos);
  std::size_t arcs = 0, signals = 0, refs = 0, objects = 0, marks = 0, lanes = 0;
  for (const Road& r : od.roads) {
    for (const Geometry& g : r.plan_view) arcs += g.kind == GeometryKind::Arc;
    signals += r.signals.size();
    refs += r.signal_refs.size();
    objects += r.objects.size();
    for (const LaneSection& s : r.sections)
      for (const Lane& l : s.lanes) {
        marks += l.marks.size();
        lanes += 1;
      }
  }
  // Counts of the elements in the file (grep -c).
  EXPECT_EQ(arcs, 160u);
  EXPECT_EQ(signals, 36u);
  EXPECT_EQ(refs, 72u);
  EXPECT_EQ(objects, 22u);
  EXPECT_EQ(marks, 1120u);
  EXPECT_EQ(lanes, 422u);
  const Road& r0 = od.roads[static_cast<std::size_t>(od.road_index.at("0"))];
  EXPECT_NEAR(r0.length, 36.36, 1e-9);
  EXPECT_EQ(r0.successor.kind, RoadLink::Kind::Junction);
  EXPECT_EQ(r0.successor.element_id, "26");
  EXPECT_EQ(r0.predecessor.contact, ContactPoint::Start);
  ASSERT_FALSE(r0.types.empty());
  EXPECT_NEAR(r0.types[0].speed_max_mps, 25 * 0.44704, 1e-9);
  std::size_t links = 0;
  for (const Junction& j : od.junctions)
    for (const Connection& c : j.connections) links += c.lane_links.size();
  EXPECT_EQ(links, 144u);
}

TEST(map_reader, LoadsTown02) {
  const OpenDrive od = LoadOpenDriveFile(kDir + "/Town02.xodr");
  EXPECT_EQ(od.roads.size(), 84u);
  EXPECT_EQ(od.junctions.size(), 8u);
}

std::string Wrap(const std::string& road_body) {
  return "<?xml version=\"1.0\"?>\n<OpenDRIVE>\n<header revMajor=\"1\" revMinor=\"6\"/>\n" + road_body + "</OpenDRIVE>\n";
}

const char* kGoodRoad =
    "<road id=\"1\" length=\"10\" junction=\"-1\">\n"
    "  <planView>\n"
    "    <geometry s=\"0\" x=\"0\" y=\"0\" hdg=\"0\" length=\"10\"><line/></geometry>\n"
    "  </planView>\n"
    "  <lanes><laneSection s=\"0\"><center><lane id=\"0\" type=\"none\"/></center>\n"
    "    <right><lane id=\"-1\" type=\"driving\"><width sOffset=\"0\" a=\"3.5\" b=\"0\" c=\"0\" d=\"0\"/></lane></right>\n"
    "  </laneSection></lanes>\n"
    "</road>\n";

std::string ErrorOf(const std::string& xml) {
  try {
    ParseOpenDrive(xml, "t.xodr");
  } catch (const MapError& e) {
    return e.what();
  }
  return "";
}

TEST(map_reader, MinimalRoadParses) {
  const OpenDrive od = ParseOpenDrive(Wrap(kGoodRoad));
  ASSERT_EQ(od.roads.size(), 1u);
  EXPECT_EQ(od.roads[0].sections[0].lanes.size(), 2u);
}

TEST(map_reader, MalformedXmlNamesLine) {
  std::string xml = Wrap(kGoodRoad);
  xml.replace(xml.find("</planView>"), 11, "</planVeiw>");
  const std::string err = ErrorOf(xml);
  EXPECT_NE(err.find("t.xodr:7:"), std::string::npos) << err;
  EXPECT_NE(err.find("XML error"), std::string::npos) << err;
}

TEST(map_reader, MissingAttributeNamesElementAndLine) {
  std::string xml = Wrap(kGoodRoad);
  xml.replace(xml.find(" hdg=\"0\""), 8, "");
  const std::string err = ErrorOf(xml);
  EXPECT_NE(err.find("t.xodr:6: <geometry>: missing attribute 'hdg'"), std::string::npos) << err;
}

TEST(map_reader, BadNumberNamesElementAndLine) {
  std::string xml = Wrap(kGoodRoad);
  xml.replace(xml.find("a=\"3.5\""), 7, "a=\"wide\"");
  const std::string err = ErrorOf(xml);
  EXPECT_NE(err.find("t.xodr:9: <width>: attribute 'a' is not a number"), std::string::npos) << err;
}

TEST(map_reader, StructuralErrors) {
  EXPECT_NE(ErrorOf("<?xml version=\"1.0\"?>\n<foo/>").find("<foo>: document has no <OpenDRIVE>"), std::string::npos);
  std::string no_lanes = Wrap(kGoodRoad);
  no_lanes.replace(no_lanes.find("<lanes>"), 7, "<lanez>").replace(no_lanes.find("</lanes>"), 8, "</lanez>");
  EXPECT_NE(ErrorOf(no_lanes).find("t.xodr:4: <road>: road '1' has no <lanes>"), std::string::npos) << ErrorOf(no_lanes);
  std::string bad_shape = Wrap(kGoodRoad);
  bad_shape.replace(bad_shape.find("<line/>"), 7, "<circle/>");
  EXPECT_NE(ErrorOf(bad_shape).find("<circle>: unknown geometry shape"), std::string::npos);
  std::string dup = Wrap(std::string(kGoodRoad) + kGoodRoad);
  EXPECT_NE(ErrorOf(dup).find("t.xodr:12: <road>: duplicate road id '1'"), std::string::npos) << ErrorOf(dup);
  std::string bad_junction = Wrap(kGoodRoad);
  bad_junction.replace(bad_junction.find("junction=\"-1\""), 13, "junction=\"7\"");
  EXPECT_NE(ErrorOf(bad_junction).find("unknown junction '7'"), std::string::npos);
  EXPECT_NE(ErrorOf("").find("XML error"), std::string::npos);
  EXPECT_NE(ErrorOf(Wrap("")).find(""), std::string::npos);
}

TEST(map_reader, MissingFile) {
  EXPECT_THROW(LoadOpenDriveFile("/nonexistent/x.xodr"), MapError);
}

}  // namespace
}  // namespace lockstep::map

namespace lockstep::map {
namespace {

// The fuzzer's seeds are real inputs too: all but the truncated one must load.
TEST(map_reader, FuzzSeedCorpusLoads) {
  const std::string dir = LOCKSTEP_MAP_FUZZ_CORPUS;
  for (const char* name : {"straight.xodr", "curves.xodr", "junction.xodr", "minimal.xodr"}) {
    const OpenDrive od = LoadOpenDriveFile(dir + "/" + name);
    EXPECT_FALSE(od.roads.empty()) << name;
  }
  EXPECT_THROW(LoadOpenDriveFile(dir + "/truncated.xodr"), MapError);
}

}  // namespace
}  // namespace lockstep::map

#include "lockstep/map/map_info.h"

namespace lockstep::map {
namespace {

// Reference numbers computed independently from the XML (Python ElementTree: sum of
// road lengths, junction roads, driving lanes x section lengths).
TEST(map_info, CarlaTownStatistics) {
  struct Expect { const char* town; int roads, junctions; double length, junction_length, driving; };
  for (const Expect& e : {Expect{"Town01", 122, 12, 4216.062, 1736.247, 6402.159},
                          Expect{"Town02", 84, 8, 1999.518, 943.299, 2919.390}}) {
    const MapStats s = ComputeStats(Map::Load(kDir + "/" + e.town + ".xodr"));
    EXPECT_EQ(s.name, e.town);
    EXPECT_EQ(s.roads, e.roads);
    EXPECT_EQ(s.junctions, e.junctions);
    EXPECT_NEAR(s.road_length_m, e.length, 1e-3);
    EXPECT_NEAR(s.junction_road_length_m, e.junction_length, 1e-3);
    EXPECT_NEAR(s.driving_lane_length_m, e.driving, 1e-3);
    EXPECT_GT(s.spawn_points, 50);
    const std::string text = StatsToText(s);
    EXPECT_NE(text.find("junctions:"), std::string::npos);
  }
}

}  // namespace
}  // namespace lockstep::map
