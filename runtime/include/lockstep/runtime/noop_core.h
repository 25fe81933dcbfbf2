#pragma once
// A service that simulates nothing: it folds every tick's commands into a hash chain.
// Used by the barrier benchmark and the tests, where equal hashes across services
// prove every service saw the same commands, in the same order, in the same frame.
#include <cstdint>
#include <utility>
#include <vector>

#include "lockstep/runtime/service.h"

namespace lockstep {

class NoopCore : public ServiceCore {
 public:
  // `blueprints`: what it declares, for tests of actors no real service is there for.
  explicit NoopCore(std::vector<msg::BlueprintDeclaration> blueprints = {}) : blueprints_(std::move(blueprints)) {}
  void BeginRun(const msg::WorldInfo& world) override;
  void Step(const msg::Tick& tick) override;
  uint64_t StateHash() const override { return hash_; }
  std::vector<uint8_t> SaveState() const override;
  void RestoreState(const std::vector<uint8_t>& state) override;
  bool StepNeverWaits() const override { return true; }
  std::vector<msg::BlueprintDeclaration> Blueprints() const override { return blueprints_; }

  uint64_t frames() const { return frames_; }

 private:
  std::vector<msg::BlueprintDeclaration> blueprints_;
  uint64_t hash_ = 0;
  uint64_t frames_ = 0;
};

// Hash of one command: client, sequence number, kind and CommandBodyDigest.
uint64_t CommandHash(const msg::Command& c);

// FNV-1a 64 of a command body: the kind (int32), then, by kind, in IDL order:
//   set_weather: its 14 floats; traffic_manager: parameter (int32), actor, value;
//   spawn_actor: blueprint, actor, owner; destroy_actor: actor.
// Other kinds: the kind only. Strings hash as their length (8 bytes) then their bytes,
// numbers as their little-endian bytes. client/cyclone_c/participant.c computes the same.
uint64_t CommandBodyDigest(const msg::CommandBody& body);

}  // namespace lockstep
