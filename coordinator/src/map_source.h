#pragma once
// Where the coordinator's map comes from: the launch config's `map` (an .xodr file, its
// scene <stem>.scene.yaml beside it) or a CMD_LOAD_MAP (a path, or inline OpenDRIVE and
// scene). A map is parsed before it is accepted, so a malformed one is refused naming the
// element and line; what the coordinator then publishes as MapData is the checked text.
#include <cstdint>
#include <optional>
#include <string>

#include "lockstep/runtime/messages.h"

namespace lockstep {

// A map as the coordinator publishes it, checked by parsing it once.
struct MapContent {
  std::string name;
  std::string opendrive;
  std::string scene;
  size_t traffic_lights = 0;  // they become actors 1..n of every run, in signal order

  // FNV-1a 64 of the OpenDRIVE and scene text: WorldInfo.map_hash, MapData.content_hash.
  uint64_t Hash() const;
};

// Parses OpenDRIVE and scene; a malformed map throws InputError naming element and line.
MapContent ParseMap(std::string name, std::string opendrive, std::string scene);

// `path` to an .xodr file; its scene is <stem>.scene.yaml beside it, if present.
MapContent ReadMap(const std::string& path);

// The map a CMD_LOAD_MAP asks for: inline OpenDRIVE, or a path other than the current map's
// name. nullopt when it names the current map (a reload of the same map: a new run only).
// Throws InputError with the reason the command is refused (unknown path, malformed map).
std::optional<MapContent> MapToLoad(const msg::LoadMap& request, const std::string& current_name);

}  // namespace lockstep
