// A custom prop declared by another service (as the render service declares `custom.<name>`
// with the asset's bounding box) is part of ground_sim's physics: a car driven into it
// stops with a collision event naming the prop's actor id. In-process bus, real coordinator,
// CARLA's Town01.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <mutex>
#include <optional>
#include <thread>

#include "ground_service.h"
#include "lockstep/coordinator/coordinator.h"
#include "lockstep/map/map.h"
#include "lockstep/runtime/blueprint_builder.h"
#include "lockstep/runtime/command_builders.h"
#include "observer.h"

namespace lockstep {
namespace {

using namespace std::chrono_literals;

const std::string kTown01 = std::string(LOCKSTEP_CARLA_MAPS_DIR) + "/Town01.xodr";

// Stands in for the render service: declares one custom prop with a 1 x 3 x 1.2 m box.
class PropDeclarer final : public ServiceCore {
 public:
  void BeginRun(const msg::WorldInfo&) override {}
  std::vector<msg::BlueprintDeclaration> Blueprints() const override {
    return {blueprint::Make("custom.crate", msg::ActorKind::ACTOR_PROP, {blueprint::String("role_name", "")}, {}, 0.5, 1.5, 0.6)};
  }
  void Step(const msg::Tick&) override {}
};

TEST(GroundProp, ACarDrivenIntoACustomPropCollidesWithItsBoundingBox) {
  LaunchConfig c;
  c.world = DefaultWorldSettings();
  c.world.synchronous_mode(true);
  c.world.service_timeout(30);
  c.map = kTown01;
  c.services.push_back({"ground_sim", "ground_sim", "", {}, true, false, "never"});
  c.services.push_back({"render", "props", "", {}, true, false, "never"});
  auto bus = CreateInProcessBus();
  std::mutex mu;
  std::map<uint64_t, msg::PhysicsEvents> events;
  std::map<uint64_t, msg::GroundState> states;
  Reader<msg::PhysicsEvents> er(*bus, topics::kPhysicsEvents, [&](const msg::PhysicsEvents& e, const SampleInfo&) {
    std::lock_guard<std::mutex> lock(mu);
    events[e.stamp().frame()] = e;
  });
  Reader<msg::GroundState> sr(*bus, topics::kGroundState, [&](const msg::GroundState& s, const SampleInfo&) {
    std::lock_guard<std::mutex> lock(mu);
    states[s.stamp().frame()] = s;
  });
  testing::Observer obs(*bus);
  Coordinator coordinator(*bus, c);
  GroundService ground(*bus);
  PropDeclarer props;
  ServiceRunner rg(*bus, ServiceOptions{"ground_sim", "ground_sim", false}, ground);
  ServiceRunner rp(*bus, ServiceOptions{"render", "props", false}, props);
  std::atomic<bool> stop{false};
  std::thread tg([&] { rg.Run(stop); });
  std::thread tp([&] { rp.Run(stop); });
  std::thread tc([&] { coordinator.Run(stop); });
  struct Join {
    std::atomic<bool>& stop;
    std::vector<std::thread*> threads;
    ~Join() {
      stop = true;
      for (auto* t : threads) t->join();
    }
  } join{stop, {&tg, &tp, &tc}};
  ASSERT_TRUE(obs.WaitUntil([&] { return obs.status() && obs.status()->state() == msg::RunState::RUN_READY; }, 60s));
  auto send = [&](msg::CommandBody b) {
    auto r = obs.WaitReply(obs.Send(std::move(b)), 20s);
    EXPECT_TRUE(r && r->accepted()) << (r ? r->reason().to_string() : "no reply");
    return r.value_or(msg::CommandReply{});
  };
  auto tick = [&](uint32_t n) {
    msg::TickRequest t;
    t.count(n);
    msg::CommandBody b;
    b.tick_request(t);
    const uint64_t want = send(b).frame();
    EXPECT_TRUE(obs.WaitUntil([&] {
      std::lock_guard<std::mutex> lock(mu);
      return events.count(want) > 0 && states.count(want) > 0;
    }, 60s));
    return want;
  };

  // A car at a Town01 spawn point, the crate 25 m ahead of it on its lane.
  // (the first spawn point with 40 m of straight lane ahead).
  const map::Map town = map::Map::Load(kTown01);
  std::optional<map::Transform> pick;
  for (const auto& p : town.SpawnPoints()) {
    auto wp = town.NearestWaypoint(p.location);
    bool straight = wp.has_value();
    for (int k = 0; straight && k < 20; ++k) {
      auto next = town.Next(*wp, 2.0);
      straight = !next.empty() && !next.front().IsJunction() && std::abs(std::remainder(next.front().transform.yaw - p.yaw, 2 * M_PI)) < 0.05;
      if (straight) wp = next.front();
    }
    if (straight) {
      pick = p;
      break;
    }
  }
  ASSERT_TRUE(pick);
  const map::Transform sp = *pick;
  const double cy = std::cos(sp.yaw), sy = std::sin(sp.yaw);
  const uint32_t car = send(SpawnBody("vehicle.tesla.model3", MakePose(sp.location.x(), sp.location.y(), sp.location.z() - 0.5 + 0.765, sp.yaw))).actor();
  const auto road = town.NearestWaypoint(sp.location + Eigen::Vector3d(25 * cy, 25 * sy, 0));
  ASSERT_TRUE(road);
  const uint32_t crate = send(SpawnBody("custom.crate", MakePose(sp.location.x() + 25 * cy, sp.location.y() + 25 * sy,
                                                                 road->transform.location.z() + 0.6, sp.yaw))).actor();
  ASSERT_NE(crate, 0u);
  msg::VehicleControl vc;
  vc.actor(car);
  vc.throttle(0.5);
  msg::CommandBody b;
  b.vehicle_control(vc);
  send(b);
  uint64_t hit_frame = 0;
  msg::ActorCollision hit;
  for (int i = 0; i < 300 && hit_frame == 0; ++i) {
    const uint64_t f = tick(1);
    std::lock_guard<std::mutex> lock(mu);
    for (const auto& col : events.at(f).collisions()) {
      if (col.actor() == car && col.other_actor() == crate) {
        hit_frame = f;
        hit = col;
      }
    }
  }
  ASSERT_NE(hit_frame, 0u) << "no collision of the car with the crate";
  EXPECT_EQ(hit.other_kind(), msg::ObjectKind::OBJECT_STATIC);
  EXPECT_EQ(hit.other_semantic_tag(), 20) << "CARLA's Static class";
  vc.throttle(0);
  vc.brake(1);
  b.vehicle_control(vc);
  send(b);
  const uint64_t last = tick(40);
  std::lock_guard<std::mutex> lock(mu);
  const auto& v = states.at(last).vehicles().at(0);
  const double along = (v.transform().position().x() - sp.location.x()) * cy + (v.transform().position().y() - sp.location.y()) * sy;
  EXPECT_LT(along + v.half_extents().x(), 25.0 - 0.5 + 0.3) << "the car stopped at the crate's box";
  EXPECT_GE(v.other_collisions(), 1u) << "counted as a collision with a static object";
  EXPECT_EQ(v.vehicle_collisions(), 0u);
}

}  // namespace
}  // namespace lockstep
