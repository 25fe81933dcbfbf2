#pragma once
// The pedestrian navigation graph of a town (what CARLA's walkers get from their
// navigation mesh): nodes every ~2 m along every sidewalk lane, walkable both ways,
// joined where sidewalks continue (lane sections, roads, junction corners), and crossing
// edges over the driving lanes: the map's crosswalk objects and a crossing derived at
// every junction mouth (kerb to kerb across the road end, just inside the junction, past
// the stop line). Built once per town, immutable, shared by worlds.
#include <functional>
#include <vector>

#include <Eigen/Core>

#include "lockstep/map/map.h"

namespace lockstep::ground {

// A crossing of the driving lanes: where it meets the kerb on both sides of the road, and
// the traffic lights of the lanes it crosses (walkers may cross when all of them are red
// for the vehicles). A crosswalk object of the map, or derived at a junction mouth.
struct TownCrosswalk {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  Eigen::Vector3d ends[2] = {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  std::vector<int> lights;
  int nodes[2] = {-1, -1};  // the graph nodes at ends[0] and ends[1]
  bool derived = false;     // at a junction mouth (else a crosswalk object of the map)
};

struct WalkerEdge {
  int to = -1;
  double length = 0;  // m
  int crossing = -1;  // index into Crossings(), -1 on the sidewalks
};

class WalkerGraph {
 public:
  WalkerGraph() = default;
  // crosswalks: the map's crosswalk objects (ends and lights known); light_of_lane: the
  // light governing a driving lane (road, section, lane) at its exit when its stop line is
  // near the point, else -1.
  WalkerGraph(const map::Map& m, std::vector<TownCrosswalk> crosswalks,
              const std::function<int(int, int, int, const Eigen::Vector3d&)>& light_of_lane);

  size_t NodeCount() const { return pos_.size(); }
  const Eigen::Vector3d& Position(int node) const { return pos_[static_cast<size_t>(node)]; }
  const std::vector<WalkerEdge>& Edges(int node) const { return edges_[static_cast<size_t>(node)]; }
  // The map's crosswalk objects first (in map order), then the derived junction-mouth ones.
  const std::vector<TownCrosswalk>& Crossings() const { return crossings_; }
  // Nearest node to p (horizontal distance), -1 if the graph is empty.
  int Nearest(const Eigen::Vector3d& p) const;
  // Nearest point to p on a sidewalk edge (or a lone node), with the node nearest to it.
  Eigen::Vector3d NearestPoint(const Eigen::Vector3d& p, int* node) const;
  // A* from `from` to `to`: the nodes after `from` up to `to`, each with the crossing of the
  // edge that reaches it (-1: sidewalk). Unreachable: the route to the reachable node
  // nearest to `to`. Crossing edges cost kCrossingPenalty metres more than their length.
  std::vector<std::pair<int, int>> Route(int from, int to) const;
  // Whether p (horizontal) stands on a driving lane of the map.
  static bool OnDrivingLane(const map::Map& m, const Eigen::Vector3d& p);

  static constexpr double kSpacing = 2.0;          // m between nodes along a sidewalk
  static constexpr double kMouthSetback = 2.0;     // m into the junction past the road end
  static constexpr double kCrossingPenalty = 10.0;  // m added to a crossing edge in A*

 private:
  int AddNode(const Eigen::Vector3d& p);
  void Connect(int a, int b, int crossing);
  void BuildGrid();
  std::vector<int> Near(const Eigen::Vector3d& p, double radius) const;

  std::vector<Eigen::Vector3d> pos_;
  std::vector<std::vector<WalkerEdge>> edges_;
  std::vector<TownCrosswalk> crossings_;
  // Uniform grid over the nodes (kCell m), row-major from grid_min_.
  static constexpr double kCell = 4.0;
  Eigen::Vector2d grid_min_ = Eigen::Vector2d::Zero();
  int grid_w_ = 0, grid_h_ = 0;
  std::vector<std::vector<int>> grid_;
};

}  // namespace lockstep::ground
