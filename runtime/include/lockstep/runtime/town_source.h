#pragma once
// The town of a run as the coordinator publishes it on lockstep/map (MapData: OpenDRIVE,
// scene, content hash), parsed once for every service that needs its geometry: air_sim
// (the drones' static collision mesh, GPS) and the sensors (ray casting, GNSS). No shared
// disk: the map comes over the bus. Thread safe.
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "lockstep/map/geo.h"
#include "lockstep/map/map.h"
#include "lockstep/map/scene.h"
#include "lockstep/runtime/bus.h"
#include "lockstep/runtime/messages.h"

namespace lockstep {

struct Town {
  std::string name;
  uint64_t hash = 0;        // MapData.content_hash (= WorldInfo.map_hash)
  map::Map map;
  map::Scene scene;         // the map's scene file, or the one generated from WorldInfo.seed
  map::GeoReference geo;    // the OpenDRIVE header's geo reference
};

class TownSource {
 public:
  explicit TownSource(Bus& bus);

  // The town `world` names (nullptr when it names none): waits up to `timeout` for the
  // coordinator's MapData whose content hash is world.map_hash(), then parses it. Throws
  // InputError "<who>: no map '<name>' from the coordinator within N s" when it does not come.
  std::shared_ptr<const Town> Load(const msg::WorldInfo& world, const std::string& who,
                                   std::chrono::seconds timeout = std::chrono::seconds(30));

 private:
  std::mutex mu_;
  std::condition_variable cv_;
  std::optional<msg::MapData> latest_;
  Reader<msg::MapData> reader_;  // last: its callback uses the members above
};

}  // namespace lockstep
