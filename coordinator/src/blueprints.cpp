#include "lockstep/coordinator/blueprints.h"

#include <algorithm>

#include "lockstep/runtime/blueprint_builder.h"

namespace lockstep {

const char* ActorKindName(msg::ActorKind kind) {
  switch (kind) {
    case msg::ACTOR_VEHICLE: return "vehicle";
    case msg::ACTOR_WALKER: return "walker";
    case msg::ACTOR_DRONE: return "drone";
    case msg::ACTOR_SENSOR: return "sensor";
    case msg::ACTOR_TRAFFIC_LIGHT: return "traffic light";
    case msg::ACTOR_TRAFFIC_SIGN: return "traffic sign";
    case msg::ACTOR_CONTROLLER: return "controller";
    case msg::ACTOR_PROP: return "prop";
    case msg::ACTOR_OTHER: return "actor";
  }
  return "actor";
}

namespace {
const msg::BlueprintDeclaration* FindIn(const msg::BlueprintSet& set, const std::string& id) {
  for (const auto& bp : set.blueprints()) {
    if (bp.id() == id) return &bp;
  }
  return nullptr;
}
}  // namespace

void BlueprintLibrary::Declare(const msg::BlueprintSet& set) {
  Entry& e = sets_[set.service().to_string()];
  e.set = set;
}

void BlueprintLibrary::SetAlive(const std::string& service, bool alive) {
  auto it = sets_.find(service);
  if (it != sets_.end()) it->second.alive = alive;
}

void BlueprintLibrary::UpdateAlive(const std::function<bool(const std::string&)>& alive) {
  for (auto& [name, e] : sets_) e.alive = alive(name);
}

const msg::BlueprintDeclaration* BlueprintLibrary::Find(const std::string& id) const {
  for (const auto& [name, e] : sets_) {
    if (!e.alive) continue;
    if (const auto* bp = FindIn(e.set, id)) return bp;
  }
  return nullptr;
}

std::vector<std::string> BlueprintLibrary::Declarers(const std::string& id) const {
  std::vector<std::string> out;
  for (const auto& [name, e] : sets_) {
    if (e.alive && FindIn(e.set, id)) out.push_back(name);
  }
  return out;
}

std::string BlueprintLibrary::WhyUnknown(const std::string& id) const {
  std::string gone;
  for (const auto& [name, e] : sets_) {
    if (!e.alive && FindIn(e.set, id)) gone += (gone.empty() ? "" : ", ") + ("'" + name + "'");
  }
  std::string why = "unknown blueprint '" + id + "'";
  if (!gone.empty()) return why + ": declared only by " + gone + ", which is not alive";
  return why + ": no live service declares it";
}

bool BlueprintLibrary::ChecksSpawns(const std::string& service) const {
  auto it = sets_.find(service);
  return it != sets_.end() && it->second.set.checks_spawns();
}

long BlueprintLibrary::Declared(const std::string& service) const {
  auto it = sets_.find(service);
  return it == sets_.end() ? -1 : static_cast<long>(it->second.set.blueprints().size());
}

std::string BlueprintLibrary::Check(const msg::BlueprintDeclaration& bp, const std::vector<msg::BlueprintAttribute>& attributes) {
  const auto& decls = bp.attributes();
  for (size_t i = 0; i < attributes.size(); ++i) {
    const auto& a = attributes[i];
    auto def = std::find_if(decls.begin(), decls.end(), [&](const msg::AttributeDeclaration& d) { return d.id() == a.key(); });
    if (def == decls.end()) {
      std::string known;
      for (const auto& d : decls) known += (known.empty() ? "" : ", ") + d.id().to_string();
      return "blueprint '" + bp.id().to_string() + "' has no attribute '" + a.key().to_string() + "' (it has: " + known + ")";
    }
    for (size_t j = 0; j < i; ++j) {
      if (attributes[j].key() == a.key()) return "attribute '" + a.key().to_string() + "' given twice";
    }
    if (!def->modifiable()) {
      return "attribute '" + a.key().to_string() + "' of blueprint '" + bp.id().to_string() + "' cannot be set (not modifiable)";
    }
    if (std::string why = blueprint::CheckValue(*def, a.value().to_string()); !why.empty()) return why;
  }
  return {};
}

}  // namespace lockstep
