#include "lockstep/runtime/command_builders.h"

#include <cmath>

namespace lockstep {

msg::Pose MakePose(double x, double y, double z, double yaw) {
  msg::Pose p;
  p.position().x(x);
  p.position().y(y);
  p.position().z(z);
  p.orientation().w(std::cos(yaw / 2));
  p.orientation().z(std::sin(yaw / 2));
  return p;
}

std::vector<msg::BlueprintAttribute> MakeAttributes(const AttributeList& attributes) {
  std::vector<msg::BlueprintAttribute> list;
  for (const auto& [k, v] : attributes) {
    msg::BlueprintAttribute a;
    a.key(k);
    a.value(v);
    list.push_back(a);
  }
  return list;
}

msg::CommandBody SpawnBody(const std::string& blueprint, const msg::Pose& pose, const AttributeList& attributes, uint32_t parent) {
  msg::SpawnActor s;
  s.blueprint(blueprint);
  s.transform(pose);
  s.attributes(MakeAttributes(attributes));
  s.parent(parent);
  msg::CommandBody b;
  b.spawn_actor(s);
  return b;
}

msg::CommandBody TransformBody(uint32_t actor, const msg::Pose& pose) {
  msg::SetTransform t;
  t.actor(actor);
  t.transform(pose);
  msg::CommandBody b;
  b.set_transform(t);
  return b;
}

namespace {
msg::CommandBody PhysicsBody(uint32_t actor, msg::ActorPhysicsKind kind, bool enabled, uint32_t light_state) {
  msg::ActorPhysicsCommand p;
  p.actor(actor);
  p.kind(kind);
  p.enabled(enabled);
  p.light_state(light_state);
  msg::CommandBody b;
  b.actor_physics(p);
  return b;
}
}  // namespace

msg::CommandBody SimulatePhysicsBody(uint32_t actor, bool on) {
  return PhysicsBody(actor, msg::ActorPhysicsKind::PHYSICS_SET_SIMULATE_PHYSICS, on, 0);
}

msg::CommandBody VehicleLightsBody(uint32_t actor, uint32_t light_state) {
  return PhysicsBody(actor, msg::ActorPhysicsKind::PHYSICS_SET_LIGHT_STATE, false, light_state);
}

msg::CommandBody AutopilotBody(uint32_t actor, bool on) {
  msg::TrafficManagerCommand t;
  t.parameter(msg::TrafficManagerParameter::TM_AUTOPILOT);
  t.actor(actor);
  t.value(on ? 1 : 0);
  msg::CommandBody b;
  b.traffic_manager(t);
  return b;
}

msg::CommandBody TrafficLightBody(uint32_t actor, msg::TrafficLightColor state, bool freeze) {
  msg::TrafficLightCommand l;
  l.actor(actor);
  l.action(msg::TrafficLightAction::LIGHT_SET);
  l.state(state);
  l.green_time(-1);
  l.yellow_time(-1);
  l.red_time(-1);
  l.freeze(freeze);
  msg::CommandBody b;
  b.traffic_light(l);
  return b;
}

msg::CommandBody RecorderBody(msg::RecorderAction action, const std::string& name, bool flag) {
  msg::RecorderCommand r;
  r.action(action);
  r.name(name);
  r.flag(flag);
  msg::CommandBody b;
  b.recorder(r);
  return b;
}

msg::SimEvent CommandFailedEvent(const std::string& service, uint32_t actor, const std::string& why, const msg::FrameStamp& stamp) {
  msg::SimEvent e;
  e.stamp(stamp);
  e.service(service);
  e.kind(msg::EventKind::EVENT_COMMAND_FAILED);
  e.actor(actor);
  e.message(why.substr(0, 511));
  return e;
}

const char* RunStateName(msg::RunState state) {
  switch (state) {
    case msg::RunState::RUN_WAITING_FOR_SERVICES: return "waiting for services";
    case msg::RunState::RUN_READY: return "ready";
    case msg::RunState::RUN_RUNNING: return "running";
    case msg::RunState::RUN_FAULTED: return "faulted";
    case msg::RunState::RUN_STOPPED: return "stopped";
  }
  return "?";
}

}  // namespace lockstep
