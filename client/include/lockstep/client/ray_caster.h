#pragma once
// CARLA's World.cast_ray and World.project_point, answered in the client's process: the
// town's meshes built from the map the world uses (the same meshes, semantic tags and
// Embree scene as the sensors service's LiDAR) plus the boxes of the actors of the latest
// frame (built from the state messages by the sensors service's own functions).
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "lockstep/runtime/messages.h"

namespace lockstep::client {

class Client;

// A point on a surface, world ENU (m), and the CARLA semantic tag (carla.CityObjectLabel) of
// what is there.
struct LabelledPoint {
  msg::Vector3 location;
  uint8_t label = 0;
};

class RayCaster {
 public:
  explicit RayCaster(Client& client);
  ~RayCaster();
  RayCaster(const RayCaster&) = delete;
  RayCaster& operator=(const RayCaster&) = delete;

  // Every object the segment crosses, nearest first, each object once (CARLA's
  // LineTraceMultiByChannel on its overlap channel).
  std::vector<LabelledPoint> CastRay(const msg::Vector3& from, const msg::Vector3& to);
  // The first surface along `direction` (normalised; a zero direction finds nothing) within
  // `search_distance` m of `location`, or nullopt (CARLA's LineTraceSingleByChannel).
  std::optional<LabelledPoint> ProjectPoint(const msg::Vector3& location, const msg::Vector3& direction, double search_distance);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace lockstep::client
