#include "lockstep/runtime/noop_core.h"

#include <cstring>

#include "lockstep/runtime/error.h"
#include "lockstep/runtime/hash.h"

namespace lockstep {

uint64_t CommandBodyDigest(const msg::CommandBody& b) {
  Fnv1a64 h;
  h.Add(static_cast<int32_t>(b._d()));
  switch (b._d()) {
    case msg::CommandKind::CMD_SET_WEATHER: {
      const auto& w = b.weather();
      for (float f : {w.cloudiness(), w.precipitation(), w.precipitation_deposits(), w.wind_intensity(),
                      w.sun_azimuth_angle(), w.sun_altitude_angle(), w.fog_density(), w.fog_distance(), w.fog_falloff(),
                      w.wetness(), w.scattering_intensity(), w.mie_scattering_scale(), w.rayleigh_scattering_scale(),
                      w.dust_storm()}) {
        h.Add(f);
      }
      break;
    }
    case msg::CommandKind::CMD_TRAFFIC_MANAGER:
      h.Add(static_cast<int32_t>(b.traffic_manager().parameter())).Add(b.traffic_manager().actor()).Add(b.traffic_manager().value());
      break;
    case msg::CommandKind::CMD_SPAWN_ACTOR:
      h.Add(std::string_view(b.spawn_actor().blueprint().c_str()))
          .Add(b.spawn_actor().actor())
          .Add(std::string_view(b.spawn_actor().owner().c_str()));
      break;
    case msg::CommandKind::CMD_DESTROY_ACTOR:
      h.Add(b.destroy_actor().actor());
      break;
    default:
      break;
  }
  return h.value();
}

uint64_t CommandHash(const msg::Command& c) {
  return Fnv1a64()
      .Add(std::string_view(c.client().c_str()))
      .Add(c.sequence_number())
      .Add(static_cast<int32_t>(c.body()._d()))
      .Add(CommandBodyDigest(c.body()))
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
