#pragma once
// The blueprint library a client sees: the union of the blueprint declarations the live
// services publish on lockstep/blueprints (blueprint.idl). Never a copy in the client.
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "lockstep/msg/blueprint.h"

namespace lockstep::client {

class BlueprintLibrary {
 public:
  BlueprintLibrary() = default;
  // declarations[service] = what that service declares. A blueprint declared by
  // several services (several render processes) appears once; owners() lists them.
  explicit BlueprintLibrary(const std::map<std::string, std::vector<msg::BlueprintDeclaration>>& declarations);

  const std::vector<msg::BlueprintDeclaration>& all() const { return blueprints_; }
  size_t size() const { return blueprints_.size(); }
  // CARLA's filter: a wildcard pattern (fnmatch: *, ?, [..]) on the id or on any tag.
  std::vector<msg::BlueprintDeclaration> Filter(const std::string& pattern) const;
  // The blueprint with exactly this id; nullopt if none.
  std::optional<msg::BlueprintDeclaration> Find(const std::string& id) const;
  std::vector<std::string> Owners(const std::string& id) const;

 private:
  std::vector<msg::BlueprintDeclaration> blueprints_;  // sorted by id
  std::map<std::string, std::vector<std::string>> owners_;
};

// CARLA's wildcard match (fnmatch without flags).
bool WildcardMatch(const std::string& pattern, const std::string& text);
// "vehicle" / "walker" / ... for ActorKind.
const char* ActorKindName(msg::ActorKind kind);

}  // namespace lockstep::client
