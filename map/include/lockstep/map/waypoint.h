#pragma once
#include <cstdint>
#include <string>

#include <Eigen/Core>

#include "lockstep/map/opendrive.h"

namespace lockstep::map {

// Pose in the world frame: ENU metres, yaw/pitch/roll in radians (yaw CCW from +x).
// CARLA's API shows the same pose with y negated and angles in degrees (left-handed).
struct Transform {
  Eigen::Vector3d location = Eigen::Vector3d::Zero();
  double yaw = 0, pitch = 0, roll = 0;
  Eigen::Vector3d Forward() const;
};

// CARLA's carla.LaneChange: which neighbour the road marks allow moving into.
enum class LaneChange : std::uint8_t { None = 0, Right = 1, Left = 2, Both = 3 };

struct LaneMarking {
  RoadMarkType type = RoadMarkType::None;
  RoadMarkColor color = RoadMarkColor::Standard;
  LaneChange lane_change = LaneChange::None;  // which side may cross it (CARLA semantics)
  double width = 0;                           // (m)
};

// A point on a lane centre, CARLA-style (carla.Waypoint). (road, section, lane, s)
// identify it; the rest is derived by Map::MakeWaypoint / Map::WaypointXodr.
//
// Indices vs OpenDRIVE ids: `road` and `junction` index OpenDrive::roads/junctions;
// `road_id` and `junction_id` are the ids written in the file (CARLA's
// waypoint.road_id / junction_id). `section` is the lane section's index within its
// road, which is also CARLA's section_id (OpenDRIVE sections have no ids). `lane` is
// the OpenDRIVE lane id (CARLA's lane_id).
struct Waypoint {
  int road = -1;      // index into OpenDrive::roads
  int section = -1;   // index into Road::sections (= CARLA section_id)
  int lane = 0;       // OpenDRIVE lane id; negative lanes travel with s, positive against
  double s = 0;       // road coordinate (m)
  // Derived:
  std::uint64_t id = 0;           // stable hash of (road, section, lane, s in mm)
  Transform transform;            // on the lane centre, yaw along the lane's travel direction
  double lane_width = 0;          // (m)
  LaneType lane_type = LaneType::None;
  int junction = -1;              // junction index, -1 if the road is not inside one
  std::string road_id;            // OpenDRIVE <road id>
  std::string junction_id = "-1"; // OpenDRIVE <junction id>, "-1" if the road is not inside one
  int SectionId() const { return section; }  // CARLA's section_id
  bool IsJunction() const { return junction >= 0; }
  bool Valid() const { return road >= 0; }
};

}  // namespace lockstep::map
