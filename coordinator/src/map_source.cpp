#include "map_source.h"

#include <filesystem>
#include <fstream>
#include <sstream>

#include "lockstep/map/map.h"
#include "lockstep/map/scene.h"
#include "lockstep/runtime/error.h"
#include "lockstep/runtime/hash.h"

namespace lockstep {
namespace {

std::string ReadFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError("cannot read map file '" + path + "'");
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace

uint64_t MapContent::Hash() const { return Fnv1a64().Add(std::string_view(opendrive)).Add(std::string_view(scene)).value(); }

MapContent ParseMap(std::string name, std::string opendrive, std::string scene) {
  MapContent m{std::move(name), std::move(opendrive), std::move(scene), 0};
  try {
    const map::Map parsed = map::Map::FromString(m.opendrive, m.name + ".xodr");
    if (!m.scene.empty()) map::SceneFromYaml(m.scene, m.name + ".scene.yaml");
    m.traffic_lights = parsed.TrafficLights().size();
  } catch (const std::exception& e) {
    throw InputError(std::string("map '") + m.name + "': " + e.what());
  }
  return m;
}

MapContent ReadMap(const std::string& path) {
  std::filesystem::path p(path);
  std::filesystem::path scene = p.parent_path() / (p.stem().string() + ".scene.yaml");
  return ParseMap(p.stem().string(), ReadFile(path), std::filesystem::exists(scene) ? ReadFile(scene.string()) : std::string());
}

std::optional<MapContent> MapToLoad(const msg::LoadMap& request, const std::string& current_name) {
  const std::string name = request.name().to_string();
  if (!request.opendrive().empty()) return ParseMap(name.empty() ? "inline" : name, request.opendrive(), request.scene());
  if (name == current_name) return std::nullopt;
  if (!std::filesystem::exists(name)) {
    throw InputError("unknown map '" + name + "': give a path to an .xodr file or inline OpenDRIVE");
  }
  return ReadMap(name);
}

}  // namespace lockstep
