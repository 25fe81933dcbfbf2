// A service finds others by what they declare: Declarations over the in-process bus.
#include <gtest/gtest.h>

#include "lockstep/runtime/blueprint_builder.h"
#include "lockstep/runtime/declarations.h"

namespace lockstep {
namespace {

using namespace std::chrono_literals;

void Publish(Writer<msg::BlueprintSet>& w, const std::string& service, msg::ActorKind kind) {
  msg::BlueprintSet s;
  s.service(service);
  s.blueprints({blueprint::Make(service + ".thing", kind, {})});
  w.Write(s);
}

void Announce(Writer<msg::ServiceAnnounce>& w, const std::string& service, msg::ServiceState state) {
  msg::ServiceAnnounce a;
  a.service(service);
  a.state(state);
  w.Write(a);
}

TEST(Declarations, FindsServicesByWhatTheySimulate) {
  auto bus = CreateInProcessBus();
  Writer<msg::BlueprintSet> sets(*bus, topics::kBlueprints);
  Writer<msg::ServiceAnnounce> announce(*bus, topics::kService);
  Declarations d(*bus);
  EXPECT_FALSE(d.WaitFor({"cars"}, 50ms)) << "nothing declared yet";
  Publish(sets, "cars", msg::ACTOR_VEHICLE);
  Publish(sets, "flyer", msg::ACTOR_DRONE);
  ASSERT_TRUE(d.WaitFor({"cars", "flyer"}, 5s));
  EXPECT_EQ(d.Declaring(msg::ACTOR_VEHICLE), std::vector<std::string>{"cars"});
  EXPECT_TRUE(d.AnyDeclares(msg::ACTOR_DRONE));
  EXPECT_FALSE(d.AnyDeclares(msg::ACTOR_VEHICLE, {"flyer"})) << "only among the services given";
  EXPECT_FALSE(d.AnyDeclares(msg::ACTOR_SENSOR));
  Announce(announce, "cars", msg::ServiceState::SERVICE_STOPPING);
  EXPECT_TRUE(d.WaitUntil([&] { return !d.AnyDeclares(msg::ACTOR_VEHICLE); }, 5s))
      << "a service that stops takes its declarations along";
  Announce(announce, "cars", msg::ServiceState::SERVICE_READY);
  EXPECT_TRUE(d.WaitUntil([&] { return d.AnyDeclares(msg::ACTOR_VEHICLE); }, 5s)) << "its replacement declares them again";
}

}  // namespace
}  // namespace lockstep
