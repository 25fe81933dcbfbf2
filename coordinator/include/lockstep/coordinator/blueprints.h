#pragma once
// The blueprint library: the union of what the live members declare on
// lockstep/blueprints (blueprint.idl). Spawn requests are checked against it. The
// coordinator knows no blueprint of its own: a service that leaves takes its own away.
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "lockstep/msg/blueprint.h"
#include "lockstep/msg/common.h"

namespace lockstep {

const char* ActorKindName(msg::ActorKind kind);

class BlueprintLibrary {
 public:
  // Replaces what `set.service()` declared before.
  void Declare(const msg::BlueprintSet& set);
  // Only the declarations of live services count (the coordinator: alive members). A
  // service that declared is live until told otherwise.
  void SetAlive(const std::string& service, bool alive);
  void UpdateAlive(const std::function<bool(const std::string& service)>& alive);

  // The declaration of `id` by the first live declarer in name order; nullptr if none.
  const msg::BlueprintDeclaration* Find(const std::string& id) const;
  // Live services that declare `id`, in name order.
  std::vector<std::string> Declarers(const std::string& id) const;
  // Why `id` is not in the library, naming declarers that are no longer alive.
  std::string WhyUnknown(const std::string& id) const;
  // Whether `service` asks to check the spawns of its blueprints (SpawnCheck).
  bool ChecksSpawns(const std::string& service) const;
  // Blueprints `service` declared; -1 if no set has arrived from it.
  long Declared(const std::string& service) const;

  // Empty if every attribute is declared, settable by a client, given once, and valid for
  // its declaration (type, range, restricted values); otherwise the reason, naming it.
  static std::string Check(const msg::BlueprintDeclaration& bp, const std::vector<msg::BlueprintAttribute>& attributes);

 private:
  struct Entry {
    msg::BlueprintSet set;
    bool alive = true;
  };
  std::map<std::string, Entry> sets_;  // by service name
};

}  // namespace lockstep
