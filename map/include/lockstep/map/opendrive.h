#pragma once
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "lockstep/map/reference_line.h"

// Plain data model of an OpenDRIVE 1.4-1.6 file, as read. Queries live in map.h.
namespace lockstep::map {

// Bit flags with CARLA's values (carla.LaneType), so masks mean the same thing.
enum class LaneType : std::uint32_t {
  None = 1u << 0, Driving = 1u << 1, Stop = 1u << 2, Shoulder = 1u << 3, Biking = 1u << 4,
  Sidewalk = 1u << 5, Border = 1u << 6, Restricted = 1u << 7, Parking = 1u << 8,
  Bidirectional = 1u << 9, Median = 1u << 10, Special1 = 1u << 11, Special2 = 1u << 12,
  Special3 = 1u << 13, RoadWorks = 1u << 14, Tram = 1u << 15, Rail = 1u << 16,
  Entry = 1u << 17, Exit = 1u << 18, OffRamp = 1u << 19, OnRamp = 1u << 20,
  Any = 0xFFFFFFFEu,
};

struct LaneTypeMask {
  std::uint32_t bits = 0;
  constexpr LaneTypeMask(LaneType t) : bits(static_cast<std::uint32_t>(t)) {}  // NOLINT implicit
  constexpr explicit LaneTypeMask(std::uint32_t b) : bits(b) {}
  constexpr bool Has(LaneType t) const { return (bits & static_cast<std::uint32_t>(t)) != 0; }
};
constexpr LaneTypeMask operator|(LaneTypeMask a, LaneTypeMask b) { return LaneTypeMask(a.bits | b.bits); }
constexpr LaneTypeMask operator|(LaneType a, LaneType b) { return LaneTypeMask(a) | LaneTypeMask(b); }

enum class RoadMarkType { None, Solid, Broken, SolidSolid, SolidBroken, BrokenSolid, BrokenBroken,
                          BottsDots, Grass, Curb, Custom, Edge };
enum class RoadMarkColor { Standard, White, Yellow, Blue, Green, Red, Orange, Black, Violet };
// Which crossings a marking allows, in OpenDRIVE terms: "increase" = towards lanes
// with a higher id (ids ascend from right to left in the road's s direction).
enum class MarkLaneChange { None, Increase, Decrease, Both };

struct Poly3 {
  double s = 0;  // start (m): road s for elevation/laneOffset, sOffset within the section for widths
  double a = 0, b = 0, c = 0, d = 0;
  double Eval(double ds) const { return a + ds * (b + ds * (c + ds * d)); }
  double Slope(double ds) const { return b + ds * (2 * c + ds * 3 * d); }
};

struct RoadMark {
  double s_offset = 0;  // from the start of the lane section (m)
  RoadMarkType type = RoadMarkType::None;
  RoadMarkColor color = RoadMarkColor::Standard;
  double width = 0.15;  // (m)
  MarkLaneChange lane_change = MarkLaneChange::Both;
  std::string material;
};

struct Lane {
  int id = 0;  // >0 left of the reference line, <0 right, 0 centre
  LaneType type = LaneType::None;
  bool level = false;
  // Width records, s = sOffset within the section. For a lane given by <border>
  // records instead, the reader derives these from the borders (see borders).
  std::vector<Poly3> widths;
  // <border> records as read: the t coordinate (m, from the road's reference line,
  // positive left) of the lane's outer edge, s = sOffset within the section. Used only
  // when the lane has no <width> (OpenDRIVE: width takes precedence).
  std::vector<Poly3> borders;
  std::vector<RoadMark> marks;      // outer border of this lane, sorted by s_offset
  std::vector<int> predecessors;    // lane ids in the previous section/road (s direction)
  std::vector<int> successors;
  double speed_max_mps = std::numeric_limits<double>::quiet_NaN();  // <speed> record, if any
};

struct LaneSection {
  double s = 0;            // start along the road (m)
  double length = 0;       // derived: up to the next section or road end (m)
  std::vector<Lane> lanes; // sorted by id descending: left n..1, centre 0, right -1..-m
  int left_count = 0;      // number of lanes with id > 0
  const Lane* Find(int id) const {
    const int idx = left_count - id;
    if (idx < 0 || idx >= static_cast<int>(lanes.size())) return nullptr;
    return &lanes[static_cast<std::size_t>(idx)];
  }
  Lane* Find(int id) { return const_cast<Lane*>(static_cast<const LaneSection*>(this)->Find(id)); }
};

enum class ContactPoint { None, Start, End };

struct RoadLink {
  enum class Kind { None, Road, Junction } kind = Kind::None;
  std::string element_id;
  ContactPoint contact = ContactPoint::None;
};

struct RoadTypeRecord {
  double s = 0;
  std::string type;  // "town", "rural", ...
  double speed_max_mps = std::numeric_limits<double>::quiet_NaN();
};

struct Signal {
  std::string id, name;
  double s = 0, t = 0, z_offset = 0, h_offset = 0;  // road coordinates (m, rad)
  double height = 0, width = 0;                     // (m)
  std::string orientation;                          // "+", "-" or "none"
  bool dynamic = false;
  std::string country, type, subtype, unit, text;
  double value = std::numeric_limits<double>::quiet_NaN();
  std::vector<std::pair<int, int>> validity;        // lane id ranges it applies to
  // Derived at load: world pose (ENU, m and rad).
  double x = 0, y = 0, z = 0, yaw = 0;
};

struct SignalReference {
  std::string id;
  double s = 0, t = 0;
  std::string orientation;
  std::vector<std::pair<int, int>> validity;  // lane id ranges it applies to
};

struct RoadObject {
  std::string id, name, type;
  double s = 0, t = 0, z_offset = 0, hdg = 0;       // road coordinates (m, rad)
  double length = 0, width = 0, height = 0, radius = 0;
  std::vector<std::pair<double, double>> outline_local;  // cornerLocal (u, v) in the object frame (m)
  std::vector<std::pair<double, double>> outline_road;   // cornerRoad (s, t) (m)
  // Derived at load: world pose of the object origin.
  double x = 0, y = 0, z = 0, yaw = 0;
};

struct Road {
  std::string id, name;
  double length = 0;            // (m)
  std::string junction = "-1";  // id of the junction this road belongs to, "-1" if none
  int junction_index = -1;      // derived
  RoadLink predecessor, successor;
  std::vector<RoadTypeRecord> types;
  std::vector<Geometry> plan_view;
  std::vector<Poly3> elevation;
  std::vector<Poly3> lane_offset;
  std::vector<LaneSection> sections;
  std::vector<Signal> signals;
  std::vector<SignalReference> signal_refs;
  std::vector<RoadObject> objects;
};

struct Connection {
  std::string id, incoming_road, connecting_road;
  ContactPoint contact = ContactPoint::Start;  // end of the connecting road that touches the incoming road
  std::vector<std::pair<int, int>> lane_links; // (from lane on incoming, to lane on connecting)
};

struct Junction {
  std::string id, name;
  std::vector<Connection> connections;
  std::vector<std::string> controllers;
};

struct Controller {
  std::string id, name;
  std::vector<std::string> signal_ids;
};

struct Header {
  int rev_major = 1, rev_minor = 4;
  std::string name, version, date, vendor;
  double north = 0, south = 0, east = 0, west = 0;
  std::string geo_reference;  // PROJ string, as written
};

struct OpenDrive {
  Header header;
  std::vector<Road> roads;
  std::vector<Junction> junctions;
  std::vector<Controller> controllers;
  std::unordered_map<std::string, int> road_index;      // road id -> index in roads
  std::unordered_map<std::string, int> junction_index;  // junction id -> index in junctions
};

const char* ToString(LaneType t);
const char* ToString(RoadMarkType t);
const char* ToString(RoadMarkColor c);

}  // namespace lockstep::map
