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
