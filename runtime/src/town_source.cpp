#include "lockstep/runtime/town_source.h"

#include "lockstep/runtime/error.h"

namespace lockstep {

TownSource::TownSource(Bus& bus)
    : reader_(bus, topics::kMap, [this](const msg::MapData& m, const SampleInfo&) {
        {
          std::lock_guard<std::mutex> lock(mu_);
          latest_ = m;
        }
        cv_.notify_all();
      }) {}

std::shared_ptr<const Town> TownSource::Load(const msg::WorldInfo& world, const std::string& who, std::chrono::seconds timeout) {
  if (world.map_name().to_string().empty()) return nullptr;
  std::optional<msg::MapData> data;
  {
    std::unique_lock<std::mutex> lock(mu_);
    auto arrived = [&] { return latest_ && latest_->content_hash() == world.map_hash(); };
    cv_.wait_for(lock, timeout, arrived);
    if (arrived()) data = latest_;
  }
  if (!data) {
    throw InputError(who + ": no map '" + world.map_name().to_string() + "' from the coordinator within " +
                     std::to_string(timeout.count()) + " s");
  }
  const std::string name = data->name().to_string();
  map::Map town = map::Map::FromString(data->opendrive(), name);
  map::Scene scene = data->scene().empty() ? map::GenerateScene(town, world.seed()) : map::SceneFromYaml(data->scene(), name + ".scene.yaml");
  const map::GeoReference geo = map::ParseGeoReference(town.Data().header.geo_reference);
  return std::make_shared<const Town>(Town{name, data->content_hash(), std::move(town), std::move(scene), geo});
}

}  // namespace lockstep
