#pragma once
// Helpers of the walker tests (navigation and crowd).
#include <Eigen/Core>

#include "lockstep/ground/walker_graph.h"

namespace lockstep::ground::testing {

// Horizontal distance.
inline double Flat(const Eigen::Vector3d& a, const Eigen::Vector3d& b) { return (a - b).head<2>().norm(); }

// `hops` sidewalk edges from `node`, each to the neighbour farthest from `from`.
inline int AwayFrom(const WalkerGraph& g, int node, const Eigen::Vector3d& from, int hops) {
  for (int h = 0; h < hops; ++h) {
    int best = -1;
    double best_d = Flat(g.Position(node), from);
    for (const auto& e : g.Edges(node)) {
      if (e.crossing < 0 && Flat(g.Position(e.to), from) > best_d) best = e.to, best_d = Flat(g.Position(e.to), from);
    }
    if (best < 0) break;
    node = best;
  }
  return node;
}

}  // namespace lockstep::ground::testing
