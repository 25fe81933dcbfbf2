#pragma once
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "lockstep/map/map.h"

namespace lockstep::map {

// High-level command at each waypoint, as CARLA's RoadOption (CIL agents use the
// first four at junctions).
enum class RoadOption { Void = -1, Left = 1, Right = 2, Straight = 3, LaneFollow = 4, ChangeLaneLeft = 5, ChangeLaneRight = 6 };
const char* ToString(RoadOption o);

struct RouteStep {
  Waypoint waypoint;
  RoadOption option = RoadOption::LaneFollow;
};

struct Route {
  std::vector<RouteStep> steps;
  double length_m = 0;  // along the lanes
};

struct RoutePlannerOptions {
  double resolution_m = 2.0;        // spacing of the returned waypoints
  bool allow_lane_changes = true;   // where road marks permit, between same-direction driving lanes
  double lane_change_cost_m = 10.0; // penalty added per lane change
  double straight_threshold_rad = 0.5236;  // |turn| below 30 degrees is STRAIGHT
};

// A* over the lane graph (driving lanes) from the lane nearest to `from` to the lane
// nearest to `to`. Returns nothing when no route exists.
std::optional<Route> PlanRoute(const Map& map, const Eigen::Vector3d& from, const Eigen::Vector3d& to,
                               const RoutePlannerOptions& options = {});
std::optional<Route> PlanRoute(const Map& map, const Waypoint& from, const Waypoint& to,
                               const RoutePlannerOptions& options = {});

}  // namespace lockstep::map
