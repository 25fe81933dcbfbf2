#include "frame_actors.h"

namespace lockstep::sensors {

Vec3 FromWire(const msg::Vector3& v) { return {v.x(), v.y(), v.z()}; }

Quat FromWire(const msg::Quaternion& q) {
  Quat out(q.w(), q.x(), q.y(), q.z());
  if (out.norm() < 1e-9) return Quat::Identity();
  return out.normalized();
}

Pose FromWire(const msg::Pose& p) { return Pose{FromWire(p.position()), FromWire(p.orientation())}; }

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
    a.half_extents = kDroneHalfExtents;
    a.velocity = FromWire(d.linear_velocity());
    a.angular_velocity = a.pose.orientation * FromWire(d.angular_velocity());  // body -> world
    out->push_back(std::move(a));
  }
}

}  // namespace lockstep::sensors
