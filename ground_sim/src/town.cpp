#include "lockstep/ground/town.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>

#include "lockstep/map/scene_mesh.h"

namespace lockstep::ground {

Town::Town(map::Map map, std::vector<map::Mesh> meshes) : map_(std::move(map)), meshes_(std::move(meshes)) {
  // One group per signalled junction (CARLA's traffic light group); a light without a
  // junction forms its own group.
  std::map<int, int> junction_group;
  for (const auto& info : map_.TrafficLights()) {
    TownLight l;
    l.info = info;
    if (info.junction >= 0) {
      auto [it, fresh] = junction_group.emplace(info.junction, group_count_);
      if (fresh) ++group_count_;
      l.group = it->second;
    } else {
      l.group = group_count_++;
    }
    const int index = static_cast<int>(lights_.size());
    for (const auto& wp : info.stop_waypoints) lane_light_.emplace(std::make_tuple(wp.road, wp.section, wp.lane), index);
    lights_.push_back(std::move(l));
  }
  signs_ = map_.StopSigns();
  for (size_t i = 0; i < signs_.size(); ++i) {
    for (const auto& wp : signs_[i].stop_waypoints) lane_sign_.emplace(std::make_tuple(wp.road, wp.section, wp.lane), static_cast<int>(i));
  }
  std::vector<TownCrosswalk> crosswalks;
  for (const auto& poly : map_.Crosswalks()) {
    if (poly.size() < 3) continue;
    TownCrosswalk cw;
    const size_t n = poly.size() - 1;  // the first corner is repeated last
    for (size_t k = 0; k < n; ++k) cw.centre += poly[k] / static_cast<double>(n);
    const auto wp = map_.NearestWaypoint(cw.centre);
    if (!wp) continue;
    // Across the road: the polygon's extent along the lane's normal, half a metre more.
    const Eigen::Vector3d normal(-std::sin(wp->transform.yaw), std::cos(wp->transform.yaw), 0);
    double half = 0;
    for (size_t k = 0; k < n; ++k) half = std::max(half, std::abs((poly[k] - cw.centre).dot(normal)));
    cw.ends[0] = cw.centre - normal * (half + 0.5);
    cw.ends[1] = cw.centre + normal * (half + 0.5);
    // Lights at the ends of the lanes it crosses, if their stop line is near.
    std::vector<map::Waypoint> lanes{*wp};
    if (auto other = map_.LeftLane(*wp); other && other->lane_type == map::LaneType::Driving) lanes.push_back(*other);
    for (const auto& l : lanes) {
      const int light = LightOfLane(l.road, l.section, l.lane);
      if (light < 0) continue;
      for (const auto& stop : lights_[static_cast<size_t>(light)].info.stop_waypoints) {
        if ((stop.transform.location - cw.centre).head<2>().norm() < 20.0) {
          cw.lights.push_back(light);
          break;
        }
      }
    }
    crosswalks.push_back(std::move(cw));
  }
  // Lights of a lane whose stop line is near a crossing (not the road's other end).
  auto light_near = [this](int road, int section, int lane, const Eigen::Vector3d& at) {
    const int light = LightOfLane(road, section, lane);
    if (light < 0) return -1;
    for (const auto& stop : lights_[static_cast<size_t>(light)].info.stop_waypoints) {
      if ((stop.transform.location - at).head<2>().norm() < 20.0) return light;
    }
    return -1;
  };
  walker_graph_ = WalkerGraph(map_, std::move(crosswalks), light_near);
  spawn_points_ = map_.SpawnPoints();
  walker_spawn_points_ = map_.PedestrianSpawnPoints();
  uint64_t h = 1469598103934665603ull;
  auto mix = [&h](const void* p, size_t n) {
    const auto* b = static_cast<const unsigned char*>(p);
    for (size_t i = 0; i < n; ++i) h = (h ^ b[i]) * 1099511628211ull;
  };
  for (const auto& m : meshes_) {
    mix(m.vertices.data(), m.vertices.size() * sizeof(float));
    mix(&m.semantic_tag, 1);
  }
  mix(map_.Name().data(), map_.Name().size());
  hash_ = h;
}

std::shared_ptr<const Town> Town::Build(map::Map map, const map::Scene& scene) {
  std::vector<map::Mesh> keep;
  for (auto& m : map::BuildWorldMeshes(map, scene)) {
    // Road lines are paint (no collision); the ground quad under the map becomes an ODE
    // plane of the world (exact and cheaper than two huge triangles).
    if (m.semantic_tag == map::semantic::kRoadLine || m.semantic_tag == map::semantic::kGround || m.name == "ground") continue;
    keep.push_back(std::move(m));
  }
  return std::make_shared<Town>(std::move(map), std::move(keep));
}

std::shared_ptr<const Town> Town::Load(const std::string& xodr_path, uint64_t scene_seed) {
  map::Map m = map::Map::Load(xodr_path);
  const map::Scene scene = map::GenerateScene(m, scene_seed);
  return Build(std::move(m), scene);
}

double Town::SignSpeedLimit(const map::Waypoint& wp) const {
  double best = std::numeric_limits<double>::quiet_NaN(), best_behind = std::numeric_limits<double>::infinity();
  if (wp.road < 0) return best;
  const auto& road = map_.Data().roads[static_cast<size_t>(wp.road)];
  const bool forward = wp.lane < 0;
  auto consider = [&](double s, double t, const std::string& orientation, double mps) {
    // The sign's side of the road (or its orientation) says which direction it serves.
    const bool serves = orientation == "+" ? forward : orientation == "-" ? !forward : (t <= 0) == forward;
    const double behind = forward ? wp.s - s : s - wp.s;
    if (!serves || !std::isfinite(mps) || mps <= 0 || behind < -1e-6 || behind >= best_behind) return;
    best_behind = behind;
    best = mps;
  };
  for (const auto& sig : road.signals) {
    if (sig.type != "274") continue;  // OpenDRIVE's "maximum speed"
    consider(sig.s, sig.t, sig.orientation, sig.unit == "mph" ? sig.value * 0.44704 : sig.unit == "m/s" ? sig.value : sig.value / 3.6);
  }
  for (const auto& o : road.objects) {
    // RoadRunner exports (CARLA towns) place the signs as objects "Speed_<km/h>".
    if (o.name.rfind("Speed_", 0) == 0) consider(o.s, o.t, "", std::atof(o.name.c_str() + 6) / 3.6);
  }
  return best;
}

int Town::SignOfLane(int road, int section, int lane) const {
  auto it = lane_sign_.find(std::make_tuple(road, section, lane));
  return it == lane_sign_.end() ? -1 : it->second;
}

int Town::LightOfLane(int road, int section, int lane) const {
  auto it = lane_light_.find(std::make_tuple(road, section, lane));
  return it == lane_light_.end() ? -1 : it->second;
}

}  // namespace lockstep::ground
