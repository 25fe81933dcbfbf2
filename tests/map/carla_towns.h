#pragma once
// CARLA's Town01/Town02 from ../shared/maps/carla, parsed once per test process.
#include <map>
#include <string>

#include "lockstep/map/map.h"

namespace lockstep::map {

inline const Map& Town(const std::string& name) {
  static std::map<std::string, Map> cache;
  auto it = cache.find(name);
  if (it == cache.end()) it = cache.emplace(name, Map::Load(std::string(LOCKSTEP_CARLA_MAPS_DIR) + "/" + name + ".xodr")).first;
  return it->second;
}

}  // namespace lockstep::map
