#include "air_blueprints.h"

#include <map>
#include <sstream>
#include <stdexcept>

#include "lockstep/runtime/blueprint_builder.h"

namespace lockstep {
namespace {

// The frame a blueprint flies when the spawn does not set one.
std::string DefaultFrame(const std::string& blueprint) {
  if (blueprint == "drone.quad_plus") return "quad_plus";
  if (blueprint == "drone.hexa_x") return "hexa_x";
  return "quad_x";
}

std::string Format(double x) {
  std::ostringstream s;
  s.precision(17);
  s << x;
  return s.str();
}

std::vector<msg::AttributeDeclaration> DroneAttributes(const std::string& frame) {
  // api_control: AirSim's enableApiControl state at spawn (the airsim clients spawn their vehicles
  // without it, as AirSim's; Lockstep's own drone commands find it on).
  std::vector<msg::AttributeDeclaration> v{blueprint::String("role_name", ""), blueprint::Bool("api_control", true)};
  air::MultirotorParams p;
  struct Visitor {
    std::vector<msg::AttributeDeclaration>* out;
    std::string frame;
    void operator()(const char* key, double& x) const { out->push_back(blueprint::Float(key, x, 0, 1e9)); }
    // "x,y,z" in metres; ParamsFromAttributes checks it when the drone is built.
    void operator()(const char* key, air::Vec3& x) const {
      out->push_back(blueprint::String(key, Format(x.x()) + "," + Format(x.y()) + "," + Format(x.z())));
    }
    void operator()(const char*, air::FrameType&) const {
      out->push_back(blueprint::String("frame", frame, {"quad_x", "quad_plus", "hexa_x"}, true));
    }
    // Model choices: AirSim's by default, Lockstep's earlier models as options (docs/air.md).
    void operator()(const char* key, air::DragModel& m) const {
      out->push_back(blueprint::String(key, air::ToString(m), {"airsim", "faces"}, true));
    }
    void operator()(const char* key, air::GainModel& m) const {
      out->push_back(blueprint::String(key, air::ToString(m), {"airsim", "physical"}, true));
    }
    void operator()(const char* key, air::LandingModel& m) const {
      out->push_back(blueprint::String(key, air::ToString(m), {"ground_lock", "impulse"}, true));
    }
  };
  air::VisitParams(p, Visitor{&v, frame});
  return v;
}

}  // namespace

std::vector<msg::BlueprintDeclaration> AirBlueprints() {
  std::vector<msg::BlueprintDeclaration> out;
  for (const char* id : {"drone.generic_quad", "drone.quad_plus", "drone.hexa_x"}) {
    out.push_back(blueprint::Make(id, msg::ACTOR_DRONE, DroneAttributes(DefaultFrame(id))));
  }
  return out;
}

air::MultirotorParams AirSpawnParams(const msg::SpawnActor& spawn) {
  std::map<std::string, std::string> attrs;
  for (const auto& a : spawn.attributes()) {
    if (a.key().to_string() != "role_name" && a.key().to_string() != "api_control") {
      attrs[a.key().to_string()] = a.value().to_string();
    }
  }
  if (!attrs.count("frame")) attrs["frame"] = DefaultFrame(spawn.blueprint().to_string());
  return air::ParamsFromAttributes(attrs);
}

std::string CheckAirSpawn(const msg::SpawnActor& spawn) {
  try {
    const std::string why = air::ValidateParams(AirSpawnParams(spawn));
    return why.empty() ? why : "drone parameters: " + why;
  } catch (const std::exception& e) {
    return std::string("drone parameters: ") + e.what();
  }
}

}  // namespace lockstep
