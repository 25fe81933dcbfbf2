#include "lockstep/client/blueprint_library.h"

#include <fnmatch.h>

#include <algorithm>
#include <sstream>

namespace lockstep::client {

BlueprintLibrary::BlueprintLibrary(const std::map<std::string, std::vector<msg::BlueprintDeclaration>>& declarations) {
  std::map<std::string, msg::BlueprintDeclaration> by_id;
  for (const auto& [service, list] : declarations) {
    for (const auto& d : list) {
      const std::string id = d.id().to_string();
      by_id.emplace(id, d);  // the first declarer (services in name order) describes it
      owners_[id].push_back(service);
    }
  }
  for (auto& [id, d] : by_id) blueprints_.push_back(std::move(d));
}

bool WildcardMatch(const std::string& pattern, const std::string& text) {
  return fnmatch(pattern.c_str(), text.c_str(), 0) == 0;
}

std::vector<msg::BlueprintDeclaration> BlueprintLibrary::Filter(const std::string& pattern) const {
  std::vector<msg::BlueprintDeclaration> out;
  for (const auto& d : blueprints_) {
    bool match = WildcardMatch(pattern, d.id().to_string());
    std::stringstream tags(d.tags().to_string());
    for (std::string tag; !match && std::getline(tags, tag, ',');) match = WildcardMatch(pattern, tag);
    if (match) out.push_back(d);
  }
  return out;
}

std::optional<msg::BlueprintDeclaration> BlueprintLibrary::Find(const std::string& id) const {
  auto it = std::lower_bound(blueprints_.begin(), blueprints_.end(), id,
                             [](const msg::BlueprintDeclaration& d, const std::string& key) { return d.id().to_string() < key; });
  if (it == blueprints_.end() || it->id().to_string() != id) return std::nullopt;
  return *it;
}

std::vector<std::string> BlueprintLibrary::Owners(const std::string& id) const {
  auto it = owners_.find(id);
  return it == owners_.end() ? std::vector<std::string>{} : it->second;
}

const char* ActorKindName(msg::ActorKind kind) {
  switch (kind) {
    case msg::ActorKind::ACTOR_VEHICLE: return "vehicle";
    case msg::ActorKind::ACTOR_WALKER: return "walker";
    case msg::ActorKind::ACTOR_DRONE: return "drone";
    case msg::ActorKind::ACTOR_SENSOR: return "sensor";
    case msg::ActorKind::ACTOR_TRAFFIC_LIGHT: return "traffic_light";
    case msg::ActorKind::ACTOR_TRAFFIC_SIGN: return "traffic_sign";
    case msg::ActorKind::ACTOR_CONTROLLER: return "controller";
    case msg::ActorKind::ACTOR_PROP: return "prop";
    case msg::ActorKind::ACTOR_OTHER: return "other";
  }
  return "other";
}

}  // namespace lockstep::client
