#include "lockstep/runtime/noop_core.h"

#include <cstring>

#include "lockstep/runtime/error.h"
#include "lockstep/runtime/hash.h"

namespace lockstep {

uint64_t CommandHash(const msg::Command& c) {
  return Fnv1a64()
      .Add(std::string_view(c.client().c_str()))
      .Add(c.sequence_number())
      .Add(static_cast<int32_t>(c.body()._d()))
      .value();
}

void NoopCore::BeginRun(const msg::WorldInfo& world) {
  hash_ = Fnv1a64().Add(world.run()).Add(world.seed()).value();
  frames_ = 0;
}

void NoopCore::Step(const msg::Tick& tick) {
  Fnv1a64 h;
  h.Add(hash_).Add(tick.frame());
  for (const auto& c : tick.commands()) h.Add(CommandHash(c));
  hash_ = h.value();
  ++frames_;
}

std::vector<uint8_t> NoopCore::SaveState() const {
  std::vector<uint8_t> out(16);
  std::memcpy(out.data(), &hash_, 8);
  std::memcpy(out.data() + 8, &frames_, 8);
  return out;
}

void NoopCore::RestoreState(const std::vector<uint8_t>& state) {
  if (state.size() != 16) throw InputError("noop snapshot must be 16 bytes, got " + std::to_string(state.size()));
  std::memcpy(&hash_, state.data(), 8);
  std::memcpy(&frames_, state.data() + 8, 8);
}

}  // namespace lockstep
