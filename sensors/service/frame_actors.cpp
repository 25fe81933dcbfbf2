#include "frame_actors.h"

namespace lockstep::sensors {

void AppendActors(const msg::GroundState& g, std::vector<Actor>* out) {
  for (const auto& v : g.vehicles()) {
    Actor a;
    a.id = v.actor();
    a.kind = ActorKind::kVehicle;
    a.blueprint = v.blueprint().to_string();
    a.pose = FromWire(v.transform());
    a.half_extents = FromWire(v.half_extents());
    a.velocity = FromWire(v.velocity());
    a.angular_velocity = FromWire(v.angular_velocity());
    a.light_state = v.light_state();
    out->push_back(std::move(a));
  }
  for (const auto& w : g.walkers()) {
    Actor a;
    a.id = w.actor();
    a.kind = ActorKind::kWalker;
    a.blueprint = w.blueprint().to_string();
    a.pose = FromWire(w.transform());
    a.half_extents = FromWire(w.half_extents());
    a.velocity = FromWire(w.velocity());
    out->push_back(std::move(a));
  }
}

void AppendActors(const msg::AirState& air, std::vector<Actor>* out) {
  for (const auto& d : air.drones()) {
    Actor a;
    a.id = d.actor();
    a.kind = ActorKind::kDrone;
    a.blueprint = d.blueprint().to_string();
    a.pose = FromWire(d.transform());
    a.half_extents = wire::DroneHalfExtents();
    a.velocity = FromWire(d.linear_velocity());
    a.angular_velocity = a.pose.orientation * FromWire(d.angular_velocity());  // body -> world
    out->push_back(std::move(a));
  }
}

CustomProp MakeCustomProp(const msg::BlueprintDeclaration& d, uint32_t id, uint32_t parent, const msg::Pose& transform) {
  CustomProp p;
  p.id = id;
  p.parent = parent;
  p.transform = FromWire(transform);
  p.half_extents = FromWire(d.half_extents());
  // Tags "custom,<name>,<Class>" (render/service): the class gives the semantic tag.
  const std::string tags = d.tags().to_string();
  const auto last = tags.rfind(',');
  const int tag = last == std::string::npos ? -1 : TagFromClassName(tags.substr(last + 1));
  p.tag = static_cast<uint8_t>(tag >= 0 ? tag : 20);  // Static when the class is not given
  return p;
}

void AppendProps(const std::vector<CustomProp>& props, std::vector<Actor>* actors) {
  for (const auto& p : props) {
    Actor a;
    a.id = p.id;
    a.kind = ActorKind::kOther;
    a.tag = p.tag;
    a.half_extents = p.half_extents;
    a.pose = p.transform;
    if (p.parent) {
      const Actor* parent = nullptr;
      for (const auto& c : *actors) {
        if (c.id == p.parent) parent = &c;
      }
      if (!parent) continue;  // the parent is not in this frame
      // Relative to the parent's mount, as the render service draws them (vehicles and
      // walkers: the bottom of their box).
      a.pose = MountPose(*parent).Compose(p.transform);
      a.velocity = parent->velocity;
    }
    actors->push_back(std::move(a));
  }
}

}  // namespace lockstep::sensors
