// The walker AI (controller.ai.walker) on the pedestrian graph of CARLA's Town01:
// go_to_location crosses roads at crossings on the walk light and goes round block
// corners along the sidewalks; wandering keeps to the sidewalks at cross factor 0; the
// random choices come from the run seed and world.set_pedestrians_seed.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "lockstep/ground/world.h"
#include "test_towns.h"
#include "walker_test_helpers.h"

namespace lockstep::ground {
namespace {

using testing::AwayFrom;
using testing::Flat;

constexpr double kDt = 0.05;

double SegmentDistance(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Eigen::Vector2d ab = (b - a).head<2>();
  const double t = std::clamp((p - a).head<2>().dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  return ((a + (b - a) * t) - p).head<2>().norm();
}

// A junction-mouth crossing of Town01 with a traffic light, sidewalk reaching both kerbs.
int LitCrossing(const Town& town) {
  const auto& g = town.WalkerNav();
  for (size_t k = 0; k < town.Crosswalks().size(); ++k) {
    const auto& cw = town.Crosswalks()[k];
    if (!cw.derived || cw.lights.empty() || Flat(cw.ends[0], cw.ends[1]) < 6) continue;
    if (Flat(g.Position(AwayFrom(g, cw.nodes[0], cw.centre, 4)), cw.centre) < 8) continue;
    if (Flat(g.Position(AwayFrom(g, cw.nodes[1], cw.centre, 4)), cw.centre) < 8) continue;
    return static_cast<int>(k);
  }
  return -1;
}

bool AllRed(const World& w, const TownCrosswalk& cw) {
  const auto lights = w.Lights();
  for (int l : cw.lights) {
    if (lights[static_cast<size_t>(l)].state.color != LightColor::kRed) return false;
  }
  return true;
}

// No node on a driving lane (crossing ends are kerbs, off the road), every crossing end
// joins the sidewalks, and with the crossings the sidewalks form one network.
void CheckGraph(const Town& town) {
  const auto& g = town.WalkerNav();
  for (size_t n = 0; n < g.NodeCount(); ++n) {
    ASSERT_FALSE(WalkerGraph::OnDrivingLane(town.Map(), g.Position(static_cast<int>(n)))) << "node " << n;
  }
  for (const auto& cw : town.Crosswalks()) {
    for (int node : cw.nodes) {
      int sidewalk = 0;
      for (const auto& e : g.Edges(node)) sidewalk += e.crossing < 0;
      EXPECT_GT(sidewalk, 0) << "a kerb of the crossing at (" << cw.centre.x() << ", " << cw.centre.y() << ") joins no sidewalk";
    }
  }
  std::vector<bool> seen(g.NodeCount(), false);
  std::vector<int> todo{0};
  size_t reached = 0;
  seen[0] = true;
  while (!todo.empty()) {
    const int n = todo.back();
    todo.pop_back();
    ++reached;
    for (const auto& e : g.Edges(n)) {
      if (!seen[static_cast<size_t>(e.to)]) seen[static_cast<size_t>(e.to)] = true, todo.push_back(e.to);
    }
  }
  std::printf("%s walker graph: %zu nodes, %zu crossings, %zu nodes reached from node 0\n", town.Map().Name().c_str(), g.NodeCount(),
              town.Crosswalks().size(), reached);
  EXPECT_GT(reached, g.NodeCount() * 95 / 100);
}

TEST(GroundWalkerNav, TownOneHasASidewalkGraphWithCrossingsAtEveryJunctionMouth) {
  const auto town = testing::Town01();
  EXPECT_GT(town->WalkerNav().NodeCount(), 1000u);
  int derived = 0, lit = 0;
  for (const auto& cw : town->Crosswalks()) derived += cw.derived, lit += !cw.lights.empty();
  // 12 T junctions, three mouths each, every one with a light.
  EXPECT_EQ(derived, 36);
  EXPECT_EQ(lit, 36);
  CheckGraph(*town);
}

TEST(GroundWalkerNav, TownTwoHasASidewalkGraphWithCrossings) {
  const auto town = Town::Load(std::string(LOCKSTEP_CARLA_MAPS_DIR) + "/Town02.xodr", 42);
  EXPECT_GT(town->WalkerNav().NodeCount(), 500u);
  EXPECT_GT(town->Crosswalks().size(), 10u);
  CheckGraph(*town);
}

// go_to_location to a sidewalk point across the road: the walker walks to the crossing,
// waits at the kerb while the light is green for the cars (frozen green for 30 s), steps
// off only on red, crosses on the crossing and reaches the goal within 0.5 m; it never
// stands on a driving lane off the crossing.
TEST(GroundWalkerNav, GoToLocationCrossesTheRoadAtTheCrossingOnTheWalkLight) {
  const auto town = testing::Town01();
  const auto& g = town->WalkerNav();
  const int k = LitCrossing(*town);
  ASSERT_GE(k, 0);
  const TownCrosswalk& cw = town->Crosswalks()[static_cast<size_t>(k)];
  const Vec3 start = g.Position(AwayFrom(g, cw.nodes[0], cw.centre, 4));
  const Vec3 goal = g.Position(AwayFrom(g, cw.nodes[1], cw.centre, 4));
  World w(town, 5);
  const uint32_t light = static_cast<uint32_t>(cw.lights[0] + 1);
  ASSERT_EQ(w.SetTrafficLight(light, LightColor::kGreen, -1, -1, -1, true), "");
  ASSERT_EQ(w.AddWalker(9, "walker.pedestrian.0001", {}, Pose::FromYaw(start + Vec3(0, 0, 1.0), 0)), "");
  ASSERT_EQ(w.AddWalkerController(10, 9), "");
  ASSERT_EQ(w.ControllerStart(10), "");
  ASSERT_EQ(w.ControllerGoTo(10, goal), "");
  for (int i = 0; i < 600; ++i) {  // 30 s of green: it walks to the kerb and waits there
    w.Step(kDt);
    ASSERT_FALSE(WalkerGraph::OnDrivingLane(town->Map(), w.Walker(9)->pose.position)) << "on the road during green, step " << i;
  }
  EXPECT_LT(Flat(w.Walker(9)->pose.position, cw.ends[0]), 0.2) << "not waiting at the kerb";
  EXPECT_LT(w.Walker(9)->velocity.head<2>().norm(), 1e-6);
  ASSERT_EQ(w.SetTrafficLight(light, std::nullopt, -1, -1, -1, false), "");
  Vec3 prev = w.Walker(9)->pose.position;
  int on_crossing = 0, departures = 0;
  double closest = 1e9;
  for (int i = 0; i < 2400 && closest > 0.1; ++i) {
    w.Step(kDt);
    const Vec3 p = w.Walker(9)->pose.position;
    const bool at_kerb = Flat(prev, cw.ends[0]) < 0.2;
    const bool steps_off = at_kerb && Flat(p, cw.ends[1]) < Flat(prev, cw.ends[1]) - 1e-6;
    if (steps_off) {
      ASSERT_TRUE(AllRed(w, cw)) << "left the kerb while a light of the crossing is not red, step " << i;
      ++departures;
    }
    if (WalkerGraph::OnDrivingLane(town->Map(), p)) {
      ASSERT_LT(SegmentDistance(p, cw.ends[0], cw.ends[1]), 0.5) << "on a driving lane off the crossing, step " << i;
      ++on_crossing;
    }
    closest = std::min(closest, Flat(p, goal));
    prev = p;
  }
  std::printf("crossing %d: %d steps on the crossing, reached the goal within %.3f m\n", k, on_crossing, closest);
  EXPECT_GT(on_crossing, 10) << "never crossed on the crossing";
  EXPECT_GE(departures, 1);
  EXPECT_LT(closest, 0.5);
}

// Clearance (a pedestrian signal's flashing don't-walk): the walker starts crossing only
// if the cars' red lasts its crossing time plus 1 s more. With short red phases (the other
// lights of the group at 1 s green, 0.5 s yellow, 0.5 s all-red: the crossing's light is
// red for under 5 s, the crossing takes over 4 s at 1.4 m/s) it stays at the kerb; when
// the red is frozen (the cycle stands still) it crosses.
TEST(GroundWalkerNav, AWalkerStartsCrossingOnlyWhenTheRedLastsItsCrossingTime) {
  const auto town = testing::Town01();
  const auto& g = town->WalkerNav();
  const int k = LitCrossing(*town);
  ASSERT_GE(k, 0);
  const TownCrosswalk& cw = town->Crosswalks()[static_cast<size_t>(k)];
  World w(town, 5);
  std::vector<int> groups;
  for (int l : cw.lights) groups.push_back(w.Lights()[static_cast<size_t>(l)].state.group);
  for (const auto& lv : w.Lights()) {
    if (std::find(groups.begin(), groups.end(), lv.state.group) != groups.end()) {
      ASSERT_EQ(w.SetTrafficLight(lv.id, std::nullopt, 1.0, 0.5, 0.5, std::nullopt), "");
    }
  }
  ASSERT_EQ(w.AddWalker(9, "walker.pedestrian.0001", {}, Pose::FromYaw(g.Position(AwayFrom(g, cw.nodes[0], cw.centre, 3)) + Vec3(0, 0, 1.0), 0)), "");
  ASSERT_EQ(w.AddWalkerController(10, 9), "");
  ASSERT_EQ(w.ControllerStart(10), "");
  ASSERT_EQ(w.ControllerGoTo(10, g.Position(AwayFrom(g, cw.nodes[1], cw.centre, 3))), "");
  int red_phases = 0;
  bool was_red = AllRed(w, cw);
  for (int i = 0; i < 1200; ++i) {  // 60 s of short red phases
    w.Step(kDt);
    ASSERT_FALSE(WalkerGraph::OnDrivingLane(town->Map(), w.Walker(9)->pose.position)) << "stepped off on a short red, step " << i;
    red_phases += AllRed(w, cw) && !was_red;
    was_red = AllRed(w, cw);
  }
  EXPECT_LT(Flat(w.Walker(9)->pose.position, cw.ends[0]), 0.2) << "not waiting at the kerb";
  EXPECT_GE(red_phases, 5);
  // The red frozen: it crosses.
  for (int l : cw.lights) ASSERT_EQ(w.SetTrafficLight(static_cast<uint32_t>(l + 1), LightColor::kRed, -1, -1, -1, true), "");
  int on_road = 0;
  double far = 1e9;
  for (int i = 0; i < 400; ++i) {
    w.Step(kDt);
    on_road += WalkerGraph::OnDrivingLane(town->Map(), w.Walker(9)->pose.position);
    far = std::min(far, Flat(w.Walker(9)->pose.position, cw.ends[1]));
  }
  EXPECT_GT(on_road, 10) << "did not cross on a frozen red";
  EXPECT_LT(far, 0.2);
}

// A walker saved on its way (route, kerb wait, crossing) continues bit for bit after a
// restore: the snapshot of a replacement ground_sim.
TEST(GroundWalkerNav, ASavedWalkerOnItsRouteContinuesBitForBit) {
  const auto town = testing::Town01();
  const auto& g = town->WalkerNav();
  const int k = LitCrossing(*town);
  ASSERT_GE(k, 0);
  const TownCrosswalk& cw = town->Crosswalks()[static_cast<size_t>(k)];
  World a(town, 5);
  const uint32_t light = static_cast<uint32_t>(cw.lights[0] + 1);
  ASSERT_EQ(a.SetTrafficLight(light, LightColor::kGreen, -1, -1, -1, true), "");
  ASSERT_EQ(a.AddWalker(9, "walker.pedestrian.0001", {}, Pose::FromYaw(g.Position(AwayFrom(g, cw.nodes[0], cw.centre, 4)) + Vec3(0, 0, 1.0), 0)), "");
  ASSERT_EQ(a.AddWalkerController(10, 9), "");
  ASSERT_EQ(a.ControllerStart(10), "");
  ASSERT_EQ(a.ControllerGoTo(10, g.Position(AwayFrom(g, cw.nodes[1], cw.centre, 4))), "");
  int on_road = 0;
  for (const int save_at : {60, 400}) {  // on the way to the kerb; waiting at it (then the light runs)
    while (a.frame() < static_cast<uint64_t>(save_at)) a.Step(kDt);
    auto r = World::Restore(town, a.Save());
    ASSERT_EQ(r->StateHash(), a.StateHash());
    if (save_at == 400) {
      for (World* w : {&a, r.get()}) ASSERT_EQ(w->SetTrafficLight(light, std::nullopt, -1, -1, -1, false), "");
    }
    for (int i = 0; i < (save_at == 400 ? 900 : 300); ++i) {
      a.Step(kDt);
      r->Step(kDt);
      ASSERT_EQ(a.StateHash(), r->StateHash()) << "diverged " << i << " steps after a restore at " << save_at;
      on_road += WalkerGraph::OnDrivingLane(town->Map(), a.Walker(9)->pose.position);
    }
  }
  EXPECT_GT(on_road, 10) << "the restored walker never crossed";
}

// A goal round a block corner: the route follows the sidewalks (never farther than 1 m
// from a sidewalk edge, never on the road) although the straight line cuts the corner.
TEST(GroundWalkerNav, GoToLocationGoesRoundABlockCornerAlongTheSidewalks) {
  const auto town = testing::Town01();
  const auto& g = town->WalkerNav();
  int s = -1, goal_node = -1;
  for (size_t k = 0; k < town->Crosswalks().size() && goal_node < 0; ++k) {
    const auto& cw = town->Crosswalks()[k];
    for (int e = 0; e < 2 && goal_node < 0; ++e) {
      const int cand = AwayFrom(g, cw.nodes[e], cw.centre, 8);
      for (size_t n = 0; n < g.NodeCount() && goal_node < 0; ++n) {
        const Vec3& p = g.Position(cand);
        const Vec3& q = g.Position(static_cast<int>(n));
        const double d = Flat(p, q);
        if (d < 25 || d > 40) continue;
        if (Flat(g.NearestPoint((p + q) / 2, nullptr), (p + q) / 2) < 4) continue;  // the straight line keeps near a sidewalk
        const auto route = g.Route(cand, static_cast<int>(n));
        if (route.empty() || route.back().first != static_cast<int>(n)) continue;
        double len = 0;
        bool crosses = false;
        Vec3 at = p;
        for (const auto& [node, crossing] : route) crosses |= crossing >= 0, len += Flat(at, g.Position(node)), at = g.Position(node);
        if (crosses || len < 1.2 * d || len > 2.5 * d) continue;
        s = cand;
        goal_node = static_cast<int>(n);
      }
    }
  }
  ASSERT_GE(goal_node, 0) << "no block corner found";
  const Vec3 start = g.Position(s), goal = g.Position(goal_node);
  std::printf("corner: from (%.1f, %.1f) to (%.1f, %.1f), %.1f m apart\n", start.x(), start.y(), goal.x(), goal.y(), Flat(start, goal));
  World w(town, 5);
  ASSERT_EQ(w.AddWalker(9, "walker.pedestrian.0002", {}, Pose::FromYaw(start + Vec3(0, 0, 1.0), 0)), "");
  ASSERT_EQ(w.AddWalkerController(10, 9), "");
  ASSERT_EQ(w.ControllerStart(10), "");
  ASSERT_EQ(w.ControllerGoTo(10, goal), "");
  double closest = 1e9;
  for (int i = 0; i < 2000 && closest > 0.1; ++i) {
    w.Step(kDt);
    const Vec3 p = w.Walker(9)->pose.position;
    ASSERT_FALSE(WalkerGraph::OnDrivingLane(town->Map(), p)) << "on the road, step " << i;
    ASSERT_LT(Flat(g.NearestPoint(p, nullptr), p), 1.0) << "off the sidewalks, step " << i;
    closest = std::min(closest, Flat(p, goal));
  }
  EXPECT_LT(closest, 0.5);
}

// A goal off the graph (the middle of a road) takes the walker to the nearest sidewalk
// point, not onto the road.
TEST(GroundWalkerNav, AGoalOnTheRoadLeadsToTheNearestSidewalkPoint) {
  const auto town = testing::Town01();
  const auto& g = town->WalkerNav();
  const int k = LitCrossing(*town);
  ASSERT_GE(k, 0);
  const TownCrosswalk& cw = town->Crosswalks()[static_cast<size_t>(k)];
  const int n = AwayFrom(g, cw.nodes[0], cw.centre, 6);
  const Vec3 start = g.Position(n);
  const auto road = town->Map().NearestWaypoint(g.Position(AwayFrom(g, cw.nodes[0], cw.centre, 10)));
  ASSERT_TRUE(road.has_value());
  const Vec3 goal = road->transform.location;
  ASSERT_TRUE(WalkerGraph::OnDrivingLane(town->Map(), goal));
  const Vec3 expected = g.NearestPoint(goal, nullptr);
  World w(town, 5);
  ASSERT_EQ(w.AddWalker(9, "walker.pedestrian.0003", {}, Pose::FromYaw(start + Vec3(0, 0, 1.0), 0)), "");
  ASSERT_EQ(w.AddWalkerController(10, 9), "");
  ASSERT_EQ(w.ControllerStart(10), "");
  ASSERT_EQ(w.ControllerGoTo(10, goal), "");
  double closest = 1e9;
  for (int i = 0; i < 600 && closest > 0.1; ++i) {
    w.Step(kDt);
    ASSERT_FALSE(WalkerGraph::OnDrivingLane(town->Map(), w.Walker(9)->pose.position)) << "step " << i;
    closest = std::min(closest, Flat(w.Walker(9)->pose.position, expected));
  }
  EXPECT_LT(closest, 0.5);
}

// Ten AI walkers of Populate(seed 9) after 30 s; pedestrians_seed 0 = none sent.
std::vector<Vec3> WanderedPositions(uint64_t pedestrians_seed, uint64_t* hash = nullptr) {
  World w(testing::Town01(), 9);
  const auto rep = Populate(&w, 0, 10, 9, 10);
  EXPECT_EQ(rep.controllers.size(), 10u);
  if (pedestrians_seed) w.SetPedestriansSeed(pedestrians_seed);
  for (int i = 0; i < 600; ++i) w.Step(kDt);
  std::vector<Vec3> out;
  for (const auto& v : w.Walkers()) out.push_back(v.pose.position);
  if (hash) *hash = w.StateHash();
  return out;
}

TEST(GroundWalkerNav, ThePedestriansSeedDecidesTheWanderChoices) {
  uint64_t h1 = 0, h2 = 0, h3 = 0, h4 = 0;
  const auto base = WanderedPositions(0, &h1), again = WanderedPositions(0, &h2);
  const auto seeded = WanderedPositions(77, &h3), seeded_again = WanderedPositions(77, &h4), other = WanderedPositions(78);
  ASSERT_EQ(base.size(), 10u);
  EXPECT_EQ(base, again);
  EXPECT_EQ(h1, h2);
  EXPECT_EQ(seeded, seeded_again);
  EXPECT_EQ(h3, h4);
  EXPECT_NE(h1, h3);
  auto moved_apart = [](const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
    int n = 0;
    for (size_t k = 0; k < a.size(); ++k) n += (a[k] - b[k]).norm() > 1.0;
    return n;
  };
  EXPECT_GE(moved_apart(base, seeded), 3) << "set_pedestrians_seed did not change the walkers' choices";
  EXPECT_GE(moved_apart(seeded, other), 3) << "another pedestrians seed made the same choices";
}

// Wandering walkers (20, 3 minutes): at cross factor 0 none ever stands on a driving
// lane; at 1 they cross roads.
TEST(GroundWalkerNav, AtCrossFactorZeroWanderingWalkersStayOnTheSidewalks) {
  for (const double factor : {0.0, 1.0}) {
    World w(testing::Town01(), 4);
    ASSERT_EQ(w.SetPedestriansCrossFactor(factor), "");
    const auto rep = Populate(&w, 0, 20, 4, 10);
    ASSERT_EQ(rep.controllers.size(), 20u);
    int on_road = 0;
    for (int i = 0; i < 3600; ++i) {
      w.Step(kDt);
      if (i % 5) continue;
      for (const auto& v : w.Walkers()) on_road += WalkerGraph::OnDrivingLane(w.town().Map(), v.pose.position);
    }
    if (factor == 0) {
      EXPECT_EQ(on_road, 0);
    } else {
      EXPECT_GT(on_road, 0) << "no walker crossed at cross factor 1";
    }
  }
}

}  // namespace
}  // namespace lockstep::ground
