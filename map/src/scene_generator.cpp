#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <unordered_map>

#include "lockstep/map/buildings.h"
#include "lockstep/map/map.h"
#include "lockstep/map/scene.h"

namespace lockstep::map {
namespace {

// Portable draws from mt19937_64 (std distributions differ between standard libraries).
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : g_(seed) {}
  double Uniform(double lo, double hi) { return lo + (hi - lo) * static_cast<double>(g_() >> 11) * 0x1.0p-53; }
  int Int(int lo, int hi_inclusive) { return lo + static_cast<int>(g_() % static_cast<std::uint64_t>(hi_inclusive - lo + 1)); }
  bool Chance(double p) { return Uniform(0, 1) < p; }

 private:
  std::mt19937_64 g_;
};

struct Box2 {
  Eigen::Vector2d c;
  double hu, hv, yaw;  // half extents along local axes
};

bool Overlap(const Box2& a, const Box2& b) {
  const Eigen::Vector2d ax[4] = {{std::cos(a.yaw), std::sin(a.yaw)}, {-std::sin(a.yaw), std::cos(a.yaw)},
                                 {std::cos(b.yaw), std::sin(b.yaw)}, {-std::sin(b.yaw), std::cos(b.yaw)}};
  const Eigen::Vector2d d = b.c - a.c;
  for (const Eigen::Vector2d& n : ax) {
    const double ra = a.hu * std::fabs(ax[0].dot(n)) + a.hv * std::fabs(ax[1].dot(n));
    const double rb = b.hu * std::fabs(ax[2].dot(n)) + b.hv * std::fabs(ax[3].dot(n));
    if (std::fabs(d.dot(n)) > ra + rb) return false;
  }
  return true;
}

// Placed footprints, hashed on a coarse grid so collision checks stay local.
class Occupancy {
 public:
  bool Free(const Box2& b) const {
    const double r = std::hypot(b.hu, b.hv);
    for (long k : Cells(b.c, r)) {
      auto it = grid_.find(k);
      if (it == grid_.end()) continue;
      for (std::size_t i : it->second)
        if (Overlap(boxes_[i], b)) return false;
    }
    return true;
  }
  void Add(const Box2& b) {
    boxes_.push_back(b);
    for (long k : Cells(b.c, std::hypot(b.hu, b.hv))) grid_[k].push_back(boxes_.size() - 1);
  }

 private:
  static constexpr double kCell = 32.0;
  std::vector<long> Cells(const Eigen::Vector2d& c, double r) const {
    std::vector<long> out;
    const long x0 = static_cast<long>(std::floor((c.x() - r) / kCell)), x1 = static_cast<long>(std::floor((c.x() + r) / kCell));
    const long y0 = static_cast<long>(std::floor((c.y() - r) / kCell)), y1 = static_cast<long>(std::floor((c.y() + r) / kCell));
    for (long x = x0; x <= x1; ++x)
      for (long y = y0; y <= y1; ++y) out.push_back(x * 1000003L + y);
    return out;
  }
  std::vector<Box2> boxes_;
  std::unordered_map<long, std::vector<std::size_t>> grid_;
};

// True if no lane of any type covers a 5x5 sample of the box grown by `margin`.
bool ClearOfRoads(const Map& map, const Box2& b, double margin) {
  const Eigen::Vector2d u(std::cos(b.yaw), std::sin(b.yaw)), v(-std::sin(b.yaw), std::cos(b.yaw));
  for (int i = 0; i <= 4; ++i)
    for (int j = 0; j <= 4; ++j) {
      const Eigen::Vector2d p = b.c + (-1 + 0.5 * i) * (b.hu + margin) * u + (-1 + 0.5 * j) * (b.hv + margin) * v;
      if (!map.LanesAt(p.x(), p.y()).empty()) return false;
    }
  return true;
}

struct Edge {
  double t = 0;            // signed lateral position of the outermost border
  bool sidewalk = false;   // outermost lane is a sidewalk
  double sidewalk_width = 0;
};

Edge EdgeAt(const Road& road, double s, int side, std::vector<LaneSpan>* spans) {
  const std::size_t si = FindSection(road, s);
  LaneSpans(road, si, s, spans);
  Edge e;
  e.t = RoadLaneOffset(road, s);
  const LaneSection& sec = road.sections[si];
  for (std::size_t i = 0; i < sec.lanes.size(); ++i) {
    const Lane& l = sec.lanes[i];
    if (l.id == 0 || (l.id > 0) != (side > 0) || l.type == LaneType::None) continue;
    const double t = (*spans)[i].t_outer;
    if (side > 0 ? t >= e.t : t <= e.t) {
      e.t = t;
      e.sidewalk = l.type == LaneType::Sidewalk;
      e.sidewalk_width = (*spans)[i].Width();
    }
  }
  return e;
}

void AddSignalProps(const Map& map, Scene* scene) {
  // Traffic light heads face the traffic they control (robust to inverted orientation).
  std::unordered_map<std::string, double> light_yaw;
  for (const TrafficLightInfo& tl : map.TrafficLights()) light_yaw[tl.signal_id] = tl.pose.yaw;
  for (const Road& road : map.Data().roads) {
    for (const Signal& sig : road.signals) {
      PropInstance p;
      p.x = sig.x;
      p.y = sig.y;
      p.z = sig.z - sig.z_offset;
      p.yaw = sig.yaw;
      p.ref = sig.id;
      if (sig.dynamic || sig.type == "1000001") {
        p.kind = "traffic_light";
        if (auto it = light_yaw.find(sig.id); it != light_yaw.end()) p.yaw = it->second;
        p.height = 4.2;
      } else if (sig.type == "206") {
        p.kind = "stop_sign";
        p.height = 2.4;
      } else if (sig.type == "274") {
        p.kind = "speed_sign";
        p.height = 2.4;
      } else {
        p.kind = "sign";
        p.height = 2.4;
      }
      scene->props.push_back(p);
    }
    for (const RoadObject& o : road.objects) {
      if (o.name.rfind("Speed_", 0) != 0) continue;
      scene->props.push_back(PropInstance{"speed_sign", o.x, o.y, o.z - o.z_offset, o.yaw, 0, 2.4, o.id});
    }
  }
}

}  // namespace

Scene GenerateScene(const Map& map, std::uint64_t seed, const SceneOptions& opt) {
  Scene scene;
  scene.map = map.Name();
  scene.seed = seed;
  Rng rng(seed);
  Occupancy occ;
  std::vector<LaneSpan> spans;
  AddSignalProps(map, &scene);
  for (const PropInstance& p : scene.props) occ.Add(Box2{{p.x, p.y}, 0.5, 0.5, p.yaw});
  const OpenDrive& od = map.Data();
  for (const Road& road : od.roads) {
    if (road.junction_index >= 0 || road.length < 2 * opt.road_end_margin_m + 4) continue;
    for (int side : {-1, 1}) {
      // Street furniture first, on the sidewalk near its outer edge.
      const double lo = opt.road_end_margin_m, hi = road.length - opt.road_end_margin_m;
      for (double s = lo + rng.Uniform(0, opt.street_light_spacing_m * 0.5); s < hi; s += opt.street_light_spacing_m) {
        const Edge e = EdgeAt(road, s, side, &spans);
        const double t = e.sidewalk ? e.t - side * 0.5 : e.t + side * 0.8;
        double hdg = 0;
        const Eigen::Vector3d p = RoadToWorld(road, s, t, &hdg);
        const Box2 box{{p.x(), p.y()}, 0.4, 0.4, hdg};
        if (!occ.Free(box)) continue;
        occ.Add(box);
        // The arm points at the road: yaw towards decreasing |t|.
        scene.props.push_back(PropInstance{"street_light", p.x(), p.y(), p.z(), hdg - side * std::numbers::pi / 2, 0, 7.5, ""});
      }
      for (double s = lo + rng.Uniform(0, opt.tree_spacing_m); s < hi; s += opt.tree_spacing_m * rng.Uniform(0.8, 1.3)) {
        const Edge e = EdgeAt(road, s, side, &spans);
        const bool on_walk = e.sidewalk && e.sidewalk_width >= 2.0;
        const double t = on_walk ? e.t - side * 0.9 : e.t + side * 2.0;
        const Eigen::Vector3d p = RoadToWorld(road, s, t);
        const double radius = rng.Uniform(1.2, 2.6);
        const Box2 box{{p.x(), p.y()}, 0.6, 0.6, 0};
        if (!occ.Free(box)) continue;
        if (!on_walk && !map.LanesAt(p.x(), p.y()).empty()) continue;
        occ.Add(box);
        const int kind = rng.Int(0, 5);
        VegetationInstance v;
        v.kind = kind < 4 ? "tree" : kind == 4 ? "conifer" : "bush";
        v.x = p.x();
        v.y = p.y();
        v.z = p.z() + (e.sidewalk ? 0.15 : 0.0);
        v.height = v.kind == "bush" ? rng.Uniform(0.8, 1.6) : rng.Uniform(5.0, 10.0);
        v.radius = v.kind == "bush" ? 1.0 : radius;
        scene.vegetation.push_back(v);
      }
      // Lots: buildings set back from the edge, or a fence/wall/garden on the lot front.
      double s = lo;
      while (true) {
        const double lot = rng.Uniform(10.0, 26.0);
        const double depth = rng.Uniform(9.0, 22.0);
        const double setback = rng.Uniform(1.0, 4.0);
        if (s + lot > hi) break;
        const double sc = s + 0.5 * lot;
        const Edge e = EdgeAt(road, sc, side, &spans);
        double hdg = 0;
        const Eigen::Vector3d c = RoadToWorld(road, sc, e.t + side * (setback + 0.5 * depth), &hdg);
        // Building local +y points away from the street.
        const double yaw = side < 0 ? hdg : hdg + std::numbers::pi;
        const Box2 box{{c.x(), c.y()}, 0.5 * lot - 0.5, 0.5 * depth, yaw};
        const double roll = rng.Uniform(0, 1);
        const int design = rng.Int(0, kBuildingDesignCount - 1);
        const int storeys = rng.Int(1, 7);
        const double storey_h = rng.Uniform(2.9, 3.6);
        if (roll < opt.building_density) {
          if (occ.Free(box) && ClearOfRoads(map, box, 1.0)) {
            occ.Add(box);
            scene.buildings.push_back(BuildingInstance{design, c.x(), c.y(), c.z(), yaw, lot - 1.0, depth, storeys, storey_h});
          }
        } else {
          // Fence or wall along the front of an empty lot.
          const Eigen::Vector3d f = RoadToWorld(road, sc, e.t + side * (setback * 0.5 + 0.3));
          const Box2 fb{{f.x(), f.y()}, 0.5 * lot - 0.5, 0.2, hdg};
          if (occ.Free(fb) && ClearOfRoads(map, fb, 0.3)) {
            occ.Add(fb);
            const bool wall = roll > 0.5 * (1 + opt.building_density);
            scene.props.push_back(PropInstance{wall ? "wall" : "fence", f.x(), f.y(), f.z(), hdg, lot - 1.0,
                                               wall ? 2.2 : 1.4, ""});
          }
        }
        s += lot + rng.Uniform(0.5, 3.0);
      }
    }
  }
  for (const Transform& t : map.SpawnPoints(opt.vehicle_spawn_spacing_m))
    scene.vehicle_spawn_points.push_back(SpawnPoint{t.location.x(), t.location.y(), t.location.z(), t.yaw});
  for (const Transform& t : map.PedestrianSpawnPoints(opt.pedestrian_spawn_spacing_m))
    scene.pedestrian_spawn_points.push_back(SpawnPoint{t.location.x(), t.location.y(), t.location.z(), t.yaw});
  return scene;
}

}  // namespace lockstep::map
