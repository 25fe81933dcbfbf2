#pragma once
// Small test worlds for the sensor tests.
#include <map>
#include <string>
#include <vector>

#include "lockstep/map/mesh.h"
#include "lockstep/sensors/sensor_world.h"

namespace lockstep::sensors::test {

// A wall whose near face is the plane x = `x`, 200 m wide and 100 m high around z = 0.
inline map::Mesh Wall(double x, uint8_t tag = map::semantic::kBuilding, uint32_t instance = 7) {
  map::Mesh m;
  m.name = "wall";
  m.semantic_tag = tag;
  m.instance_id = instance;
  map::AddBox(m, Eigen::Vector3d(x + 0.5, 0, -50), 1.0, 200, 100, 0, true);
  return m;
}

// A closed room (inside faces everywhere) so that every ray hits something.
inline std::vector<map::Mesh> Room(double half) {
  std::vector<map::Mesh> out;
  for (int axis = 0; axis < 3; ++axis) {
    for (int sign : {-1, 1}) {
      map::Mesh m;
      m.semantic_tag = map::semantic::kWall;
      Eigen::Vector3d c = Eigen::Vector3d::Zero();
      c[axis] = sign * (half + 0.5);
      Eigen::Vector3d size = Eigen::Vector3d::Constant(2 * half + 2);
      size[axis] = 1.0;
      map::AddBox(m, Eigen::Vector3d(c.x(), c.y(), c.z() - size.z() / 2), size.x(), size.y(), size.z(), 0, true);
      out.push_back(m);
    }
  }
  return out;
}

inline Actor MakeActor(uint32_t id, ActorKind kind, const std::string& bp, const Pose& pose, const Vec3& half) {
  Actor a;
  a.id = id;
  a.kind = kind;
  a.blueprint = bp;
  a.pose = pose;
  a.half_extents = half;
  return a;
}

inline SensorSpawn Spawn(uint32_t id, const std::string& bp, std::map<std::string, std::string> attrs = {}, uint32_t parent = 0,
                         Pose transform = {}) {
  SensorSpawn s;
  s.id = id;
  s.blueprint = bp;
  s.attributes = std::move(attrs);
  s.parent = parent;
  s.transform = transform;
  return s;
}

inline WorldFrame Frame(uint64_t k, double dt, std::vector<Actor> actors = {}) {
  WorldFrame f;
  f.run = 1;
  f.frame = k;
  f.sim_time = static_cast<double>(k) * dt;
  f.actors = std::move(actors);
  return f;
}

}  // namespace lockstep::sensors::test
