// Whole-map enumerations: waypoints, topology, junction pairs, spawn points.
#include <algorithm>
#include <cmath>

#include "lockstep/map/map.h"

namespace lockstep::map {

std::vector<Waypoint> Map::GenerateWaypoints(double distance, LaneTypeMask types) const {
  std::vector<Waypoint> out;
  if (!(distance > 0)) return out;
  for (const LaneNode& n : nodes_) {
    if (!types.Has(n.type)) continue;
    // Along the travel direction, starting at the entry, like CARLA's GenerateWaypoints.
    const double sign = n.Forward() ? 1.0 : -1.0;
    for (double d = 0; d < n.Length() - 1e-6 || d == 0; d += distance) {
      out.push_back(MakeWaypoint(n.road, n.section, n.lane, n.EntryS() + sign * d));
      if (n.Length() <= 1e-6) break;
    }
  }
  return out;
}

std::vector<std::pair<Waypoint, Waypoint>> Map::Topology() const {
  std::vector<std::pair<Waypoint, Waypoint>> out;
  for (const LaneNode& n : nodes_) {
    if (n.type != LaneType::Driving || n.Length() <= 1e-6) continue;
    out.emplace_back(MakeWaypoint(n.road, n.section, n.lane, n.EntryS()),
                     MakeWaypoint(n.road, n.section, n.lane, n.ExitS()));
  }
  return out;
}

std::vector<std::pair<Waypoint, Waypoint>> Map::JunctionWaypoints(int junction, LaneTypeMask types) const {
  std::vector<std::pair<Waypoint, Waypoint>> out;
  for (std::size_t r = 0; r < data_.roads.size(); ++r) {
    const Road& road = data_.roads[r];
    if (road.junction_index != junction || road.sections.empty()) continue;
    // A lane through a junction may span several sections: entry of the first, exit of the last.
    const LaneSection& first = road.sections.front();
    for (const Lane& lane : first.lanes) {
      if (lane.id == 0 || !types.Has(lane.type)) continue;
      const int last = static_cast<int>(road.sections.size()) - 1;
      const bool fwd = lane.id < 0;
      const int in_sec = fwd ? 0 : last, out_sec = fwd ? last : 0;
      if (NodeOf(static_cast<int>(r), out_sec, lane.id) < 0) continue;
      out.emplace_back(MakeWaypoint(static_cast<int>(r), in_sec, lane.id, fwd ? 0.0 : road.length),
                       MakeWaypoint(static_cast<int>(r), out_sec, lane.id, fwd ? road.length : 0.0));
    }
  }
  return out;
}

namespace {
std::vector<Transform> SpawnAlong(const Map& map, LaneType type, double spacing, double lift, bool skip_junctions) {
  std::vector<Transform> out;
  if (!(spacing > 0)) return out;
  const double margin = 0.25 * spacing;
  for (const LaneNode& n : map.Nodes()) {
    if (n.type != type) continue;
    const Road& road = map.Data().roads[static_cast<std::size_t>(n.road)];
    if (skip_junctions && road.junction_index >= 0) continue;
    if (n.Length() < 2 * margin) continue;
    const double sign = n.Forward() ? 1.0 : -1.0;
    for (double d = margin; d <= n.Length() - margin; d += spacing) {
      Transform t = map.MakeWaypoint(n.road, n.section, n.lane, n.EntryS() + sign * d).transform;
      t.location.z() += lift;
      t.pitch = 0;
      out.push_back(t);
    }
  }
  return out;
}
}  // namespace

std::vector<Transform> Map::SpawnPoints(double spacing) const { return SpawnAlong(*this, LaneType::Driving, spacing, 0.5, true); }

std::vector<Transform> Map::PedestrianSpawnPoints(double spacing) const {
  return SpawnAlong(*this, LaneType::Sidewalk, spacing, 1.0, false);
}

}  // namespace lockstep::map
