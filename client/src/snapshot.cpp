#include "lockstep/client/client.h"

namespace lockstep::client {

namespace {

ActorState FromVehicle(const msg::VehicleState& v) {
  ActorState a;
  a.id = v.actor();
  a.blueprint = v.blueprint().to_string();
  a.kind = msg::ActorKind::ACTOR_VEHICLE;
  a.transform = v.transform();
  a.velocity = v.velocity();
  a.angular_velocity = v.angular_velocity();
  a.acceleration = v.acceleration();
  a.half_extents = v.half_extents();
  return a;
}

ActorState FromWalker(const msg::WalkerState& w) {
  ActorState a;
  a.id = w.actor();
  a.blueprint = w.blueprint().to_string();
  a.kind = msg::ActorKind::ACTOR_WALKER;
  a.transform = w.transform();
  a.velocity = w.velocity();
  a.half_extents = w.half_extents();
  return a;
}

ActorState FromDrone(const msg::DroneState& d) {
  ActorState a;
  a.id = d.actor();
  a.blueprint = d.blueprint().to_string();
  a.kind = msg::ActorKind::ACTOR_DRONE;
  a.transform = d.transform();
  a.velocity = d.linear_velocity();
  a.angular_velocity = d.angular_velocity();
  a.acceleration = d.linear_acceleration();
  return a;
}

ActorState FromLight(const msg::TrafficLightState& l) {
  ActorState a;
  a.id = l.actor();
  a.blueprint = "traffic.traffic_light";
  a.kind = msg::ActorKind::ACTOR_TRAFFIC_LIGHT;
  a.transform = l.transform();
  return a;
}

template <class List>
auto FindIn(const List& list, uint32_t id) -> decltype(&list[0]) {
  for (const auto& x : list) {
    if (x.actor() == id) return &x;
  }
  return nullptr;
}

}  // namespace

std::vector<ActorState> Snapshot::Actors() const {
  std::vector<ActorState> out;
  if (ground) {
    for (const auto& v : ground->vehicles()) out.push_back(FromVehicle(v));
    for (const auto& w : ground->walkers()) out.push_back(FromWalker(w));
    for (const auto& l : ground->traffic_lights()) out.push_back(FromLight(l));
  }
  if (air) {
    for (const auto& d : air->drones()) out.push_back(FromDrone(d));
  }
  return out;
}

std::optional<ActorState> Snapshot::Find(uint32_t id) const {
  if (const auto* v = Vehicle(id)) return FromVehicle(*v);
  if (const auto* w = Walker(id)) return FromWalker(*w);
  if (const auto* d = Drone(id)) return FromDrone(*d);
  if (const auto* l = TrafficLight(id)) return FromLight(*l);
  return std::nullopt;
}

const msg::VehicleState* Snapshot::Vehicle(uint32_t id) const { return ground ? FindIn(ground->vehicles(), id) : nullptr; }
const msg::WalkerState* Snapshot::Walker(uint32_t id) const { return ground ? FindIn(ground->walkers(), id) : nullptr; }
const msg::DroneState* Snapshot::Drone(uint32_t id) const { return air ? FindIn(air->drones(), id) : nullptr; }
const msg::TrafficLightState* Snapshot::TrafficLight(uint32_t id) const {
  return ground ? FindIn(ground->traffic_lights(), id) : nullptr;
}

std::string ActorInfo::Attribute(const std::string& key, const std::string& fallback) const {
  for (const auto& [k, v] : attributes) {
    if (k == key) return v;
  }
  return fallback;
}

}  // namespace lockstep::client
