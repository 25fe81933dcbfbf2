#pragma once
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "lockstep/map/opendrive.h"
#include "lockstep/map/road_profile.h"
#include "lockstep/map/waypoint.h"

namespace lockstep::map {

// One lane of one lane section: the node of the lane graph.
struct LaneNode {
  int road = -1, section = -1, lane = 0;
  double s_begin = 0, s_end = 0;   // section extent along the road (m)
  LaneType type = LaneType::None;
  std::vector<int> successors;     // nodes reached when driving off this node's exit
  std::vector<int> predecessors;
  double Length() const { return s_end - s_begin; }
  bool Forward() const { return lane < 0; }  // travels with increasing s
  double EntryS() const { return Forward() ? s_begin : s_end; }
  double ExitS() const { return Forward() ? s_end : s_begin; }
};

// Road point found by a lateral lookup (no projection onto a lane centre).
struct LanePoint {
  int node = -1;    // lane graph node
  double s = 0, t = 0;
};

// A box in the world frame, like carla.BoundingBox: centre, half sizes along its own
// axes, turned by `yaw` about z (0 for junction boxes, which are axis-aligned).
struct BoundingBox {
  Eigen::Vector3d location = Eigen::Vector3d::Zero();  // centre (m, ENU)
  Eigen::Vector3d extent = Eigen::Vector3d::Zero();    // half sizes along its x, y, z (m)
  double yaw = 0;                                      // (rad, CCW from +x)
  // Whether a world point lies inside (or on) the box.
  bool Contains(const Eigen::Vector3d& p) const;
};

// A traffic light (dynamic signal) with the lanes it controls, like CARLA's
// carla.TrafficLight get_stop_waypoints() / get_affected_lane_waypoints(). Stop and
// yield signs (Map::StopSigns) use the same record.
struct TrafficLightInfo {
  std::string signal_id;
  std::string type;              // OpenDRIVE signal type: "1000001", "206" (stop), "205" (yield), ...
  int road = -1;                 // road index the signal is placed on
  double s = 0, t = 0;           // its road coordinates (m)
  Transform pose;                // pole foot, yaw facing the traffic it controls
  int junction = -1;             // junction the controlled lanes drive into (-1: none)
  std::string controller_id;     // <controller> that groups it with others ("" if none)
  std::vector<Waypoint> stop_waypoints;  // one per controlled lane, at the lane's end (stop line)
  // Where an approaching vehicle must react (CARLA's trigger volume): 3 m of lane before
  // the stop line across all controlled lanes, 2 m high, turned along the first lane.
  BoundingBox trigger_volume;
};

// A junction, like carla.Junction. Its (entry, exit) waypoint pairs come from
// Map::JunctionWaypoints(index, lane_types) (carla.Junction.get_waypoints).
struct JunctionInfo {
  int index = -1;            // index into OpenDrive::junctions
  std::string id;            // OpenDRIVE <junction id> (carla.Junction.id)
  // Bounds of the lane centres of every lane (any type) of its connecting roads, as
  // CARLA computes carla.Junction.bounding_box.
  BoundingBox bounding_box;
};

// A signal (or a reference to one) found along a lane, like carla.Landmark from
// waypoint.get_landmarks(distance).
struct Landmark {
  std::string id;           // the signal's id (a <signalReference> gives its target's)
  std::string name, type, subtype, unit, text;  // the signal's attributes, as written
  double value = 0;         // the signal's value (NaN when absent)
  bool dynamic = false;     // traffic lights are dynamic
  int road = -1;            // road index where it was met (the reference's road for references)
  double s = 0, t = 0;      // its road coordinates there (m)
  Transform pose;           // the signal itself: pole foot, yaw facing its traffic
  double distance = 0;      // along the lane from the query waypoint (m)
  Waypoint waypoint;        // on the query's lane (or the branch taken) level with it
};

class SegmentIndex;  // spatial index over lane-centre segments (map_queries.cpp)

// An OpenDRIVE road network with CARLA-style queries. Immutable after construction.
class Map {
 public:
  explicit Map(OpenDrive data, std::string name = "");
  ~Map();
  Map(Map&&) noexcept;
  Map& operator=(Map&&) noexcept;

  static Map Load(const std::string& xodr_path);
  static Map FromString(const std::string& xodr_text, const std::string& name = "<memory>");

  const OpenDrive& Data() const { return data_; }
  const std::string& Name() const { return name_; }
  const std::vector<LaneNode>& Nodes() const { return nodes_; }
  int NodeOf(int road, int section, int lane) const;  // -1 if none
  int NodeOf(const Waypoint& wp) const { return NodeOf(wp.road, wp.section, wp.lane); }

  // Road index of an OpenDRIVE road id, -1 if there is none.
  int RoadIndex(const std::string& road_id) const;

  // Builds a waypoint from indices; s is clamped to the section. Section -1 picks it
  // from s. Does not check that the lane exists (then lane_type is None): use
  // WaypointXodr for input from outside.
  Waypoint MakeWaypoint(int road, int section, int lane, double s) const;

  // Waypoint from OpenDRIVE ids, like CARLA's map.get_waypoint_xodr(road_id, lane_id, s):
  // nothing when the road does not exist, s is outside [0, road length), or no lane
  // section at s has that lane (lane 0, the centre lane, gives nothing: it has no
  // centre line to drive). Where two sections meet, the one holding the lane is used.
  std::optional<Waypoint> WaypointXodr(const std::string& road_id, int lane_id, double s) const;
  std::optional<Waypoint> WaypointXodr(int road_id, int lane_id, double s) const;  // numeric id

  // Nearest lane-centre point whose lane type is in `types` (CARLA get_waypoint with
  // project_to_road=true). With project_to_road=false, the lane that contains the
  // point (if its type is in `types`), else nothing.
  std::optional<Waypoint> NearestWaypoint(const Eigen::Vector3d& p, bool project_to_road = true,
                                          LaneTypeMask types = LaneType::Driving) const;
  // All lanes whose area contains the point (x, y), any type (junction roads overlap).
  std::vector<LanePoint> LanesAt(double x, double y) const;

  // Waypoints `distance` metres ahead along the lane's travel direction, one per branch;
  // empty at a dead end. Previous() walks against the travel direction.
  std::vector<Waypoint> Next(const Waypoint& wp, double distance) const;
  std::vector<Waypoint> Previous(const Waypoint& wp, double distance) const;
  // CARLA's next_until_lane_end: waypoints every `distance` metres in the travel
  // direction while the lane continues on one branch of the same road, then the point
  // where it leaves the road (its last lane section's end). The start is not included.
  // Empty for an unknown lane or distance <= 0.
  std::vector<Waypoint> NextUntilLaneEnd(const Waypoint& wp, double distance) const;
  // CARLA's previous_until_lane_start: the same against the travel direction, ending
  // where the lane enters the road.
  std::vector<Waypoint> PreviousUntilLaneStart(const Waypoint& wp, double distance) const;

  // Neighbouring lanes relative to the travel direction (may travel the other way).
  std::optional<Waypoint> LeftLane(const Waypoint& wp) const;
  std::optional<Waypoint> RightLane(const Waypoint& wp) const;
  std::optional<LaneMarking> LeftMarking(const Waypoint& wp) const;
  std::optional<LaneMarking> RightMarking(const Waypoint& wp) const;
  LaneChange AllowedLaneChange(const Waypoint& wp) const;

  // Waypoints every `distance` metres on every lane of the given types.
  std::vector<Waypoint> GenerateWaypoints(double distance, LaneTypeMask types = LaneType::Driving) const;
  // (entry, exit) waypoint of every driving lane section, like CARLA get_topology().
  std::vector<std::pair<Waypoint, Waypoint>> Topology() const;
  // (entry, exit) of every lane of a junction's connecting roads, like carla.Junction.get_waypoints.
  // `junction` is the junction's index (JunctionInfo::index, Waypoint::junction).
  std::vector<std::pair<Waypoint, Waypoint>> JunctionWaypoints(int junction,
                                                               LaneTypeMask types = LaneType::Driving) const;
  // Every junction in file order (index i describes OpenDrive::junctions[i]).
  const std::vector<JunctionInfo>& Junctions() const { return junctions_; }
  // The junction a waypoint is in (carla.Waypoint.get_junction()), nothing outside junctions.
  std::optional<JunctionInfo> JunctionOf(const Waypoint& wp) const;
  // The junction with an OpenDRIVE id, if any.
  std::optional<JunctionInfo> JunctionById(const std::string& junction_id) const;
  // Vehicle spawn points on driving lanes outside junctions, every ~`spacing` metres,
  // 0.5 m above the road. Deterministic.
  std::vector<Transform> SpawnPoints(double spacing = 25.0) const;
  // Pedestrian spawn points on sidewalk lane centres.
  std::vector<Transform> PedestrianSpawnPoints(double spacing = 20.0) const;

  // Speed limit (m/s) for a waypoint: last speed-limit sign passed on its road in its
  // travel direction, else the lane's <speed>, else the road type's, else `fallback`.
  double SpeedLimit(const Waypoint& wp, double fallback = 30.0 / 3.6) const;
  // Speed limit (m/s) at a location: that of the nearest driving lane, heading-blind.
  double SpeedLimitAt(const Eigen::Vector3d& p, double fallback = 30.0 / 3.6) const;

  // Every dynamic signal with the driving lanes it controls. The controlled direction
  // comes from the side of the road the signal stands on (t < 0: lanes driving with s),
  // which also holds for RoadRunner exports whose `orientation` is inverted; `orientation`
  // decides only for t = 0. <validity> narrows the lanes.
  std::vector<TrafficLightInfo> TrafficLights() const;
  // Every stop (type 206) and yield (205) sign with the lanes it controls, found the
  // same way as for traffic lights; TrafficLightInfo::type tells them apart.
  std::vector<TrafficLightInfo> StopSigns() const;

  // Signals and signal references that apply to the lane ahead of `wp` within
  // `distance` metres along the lane graph (every branch), nearest first, each once
  // (waypoint.get_landmarks(distance, stop_at_junction)). A signal applies to a lane
  // its <validity> names, else to the lanes of its orientation ("+": lanes driving with
  // s, "-": against, other: both). With stop_at_junction the walk ends at a junction.
  std::vector<Landmark> LandmarksAhead(const Waypoint& wp, double distance, bool stop_at_junction = false) const;
  // Crosswalk zones (objects of type "crosswalk") as closed polygons in the world frame,
  // the first corner repeated last; CARLA's map.get_crosswalks() returns the same
  // polygons one after another in a single list. Objects without an outline give their
  // length x width rectangle.
  std::vector<std::vector<Eigen::Vector3d>> Crosswalks() const;

  // Axis-aligned bounds of all roads (m).
  Eigen::Vector2d BoundsMin() const { return bounds_min_; }
  Eigen::Vector2d BoundsMax() const { return bounds_max_; }

 private:
  void BuildGraph();
  void BuildJunctions();
  void LinkRoadEnd(int node_id, bool at_end);
  std::vector<Waypoint> UntilRoadEnd(const Waypoint& wp, double distance, bool forward) const;
  std::vector<TrafficLightInfo> ControlledSignals(bool (*selects)(const Signal&)) const;
  static constexpr int kWalkBudget = 20000;  // lane nodes visited by one Next/Previous at most
  std::vector<Waypoint> Walk(const Waypoint& wp, double distance, bool forward, int* budget) const;
  std::optional<Waypoint> Neighbour(const Waypoint& wp, int lane) const;
  std::optional<LaneMarking> MarkingBetween(const Waypoint& wp, int lane_a, int lane_b) const;

  OpenDrive data_;
  std::string name_;
  std::vector<LaneNode> nodes_;
  std::vector<std::vector<int>> node_lookup_;  // [road][section * stride + lane + offset]
  std::vector<int> lookup_offset_, lookup_stride_;
  std::unique_ptr<SegmentIndex> index_;
  std::vector<JunctionInfo> junctions_;
  Eigen::Vector2d bounds_min_ = Eigen::Vector2d::Zero(), bounds_max_ = Eigen::Vector2d::Zero();
};

}  // namespace lockstep::map
