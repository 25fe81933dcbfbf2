#include "lockstep/coordinator/blueprints.h"

#include "lockstep/air/params.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <sstream>

namespace lockstep {

const char* ActorKindName(ActorKind kind) {
  switch (kind) {
    case ActorKind::kVehicle: return "vehicle";
    case ActorKind::kWalker: return "walker";
    case ActorKind::kDrone: return "drone";
    case ActorKind::kSensor: return "sensor";
    case ActorKind::kTrafficLight: return "traffic light";
  }
  return "actor";
}

namespace {

using T = AttributeType;
constexpr double kInf = std::numeric_limits<double>::infinity();

AttributeDef Attr(std::string name, AttributeType type, std::string def, double min = -kInf, double max = kInf) {
  return AttributeDef{std::move(name), type, std::move(def), min, max, {}};
}
AttributeDef Choice(std::string name, std::string def, std::vector<std::string> options) {
  return AttributeDef{std::move(name), T::kString, std::move(def), -kInf, kInf, std::move(options)};
}

std::vector<AttributeDef> Common() {
  return {Attr("role_name", T::kString, "")};
}

std::vector<AttributeDef> With(std::vector<AttributeDef> base, std::vector<AttributeDef> more) {
  base.insert(base.end(), more.begin(), more.end());
  return base;
}

std::vector<AttributeDef> CameraAttributes() {
  return With(Common(), {Attr("image_size_x", T::kInt, "800", 1, 3840), Attr("image_size_y", T::kInt, "600", 1, 2160),
                         Attr("fov", T::kFloat, "90", 1, 179), Attr("sensor_tick", T::kFloat, "0", 0, 3600)});
}

// Every multirotor parameter air_sim accepts (air::VisitParams), so a spawn request is
// checked here against exactly what the service will build.
std::vector<AttributeDef> DroneAttributes(const std::string& frame) {
  std::vector<AttributeDef> v = Common();
  air::MultirotorParams p;
  struct Visitor {
    std::vector<AttributeDef>* out;
    std::string frame;
    void operator()(const char* key, double& x) const { out->push_back(Attr(key, T::kFloat, std::to_string(x), 0, 1e9)); }
    void operator()(const char* key, air::Vec3&) const { out->push_back(Attr(key, T::kString, "")); }
    void operator()(const char*, air::FrameType&) const { out->push_back(Choice("frame", frame, {"quad_x", "quad_plus", "hexa_x"})); }
  };
  air::VisitParams(p, Visitor{&v, frame});
  return v;
}

bool ParseNumber(const std::string& s, double* out) {
  if (s.empty()) return false;
  const char* b = s.data();
  const char* e = b + s.size();
  auto [p, ec] = std::from_chars(b, e, *out);
  return ec == std::errc() && p == e && std::isfinite(*out);
}

std::string TypeName(AttributeType t) {
  switch (t) {
    case T::kBool: return "bool";
    case T::kInt: return "int";
    case T::kFloat: return "float";
    case T::kString: return "string";
    case T::kRgb: return "rgb";
  }
  return "?";
}

// Empty if `value` is a valid `def`, else why not.
std::string CheckValue(const AttributeDef& def, const std::string& value) {
  auto bad = [&](const std::string& why) {
    return "attribute '" + def.name + "' (" + TypeName(def.type) + "): " + why + ", got '" + value + "'";
  };
  double x = 0;
  switch (def.type) {
    case T::kBool:
      if (value != "true" && value != "false" && value != "True" && value != "False") return bad("expected true or false");
      return {};
    case T::kInt:
      if (!ParseNumber(value, &x) || x != std::floor(x)) return bad("expected an integer");
      break;
    case T::kFloat:
      if (!ParseNumber(value, &x)) return bad("expected a finite number");
      break;
    case T::kRgb: {
      std::stringstream ss(value);
      std::string part;
      int n = 0;
      while (std::getline(ss, part, ',')) {
        double c;
        if (!ParseNumber(part, &c) || c < 0 || c > 255 || c != std::floor(c)) return bad("expected 'r,g,b' with 0..255 integers");
        ++n;
      }
      if (n != 3) return bad("expected 'r,g,b'");
      return {};
    }
    case T::kString:
      if (!def.options.empty() && std::find(def.options.begin(), def.options.end(), value) == def.options.end()) {
        std::string opts;
        for (const auto& o : def.options) opts += (opts.empty() ? "" : ", ") + o;
        return bad("expected one of " + opts);
      }
      return {};
  }
  if (x < def.min || x > def.max) {
    std::ostringstream r;
    r << "out of range [" << def.min << ", " << def.max << "]";
    return bad(r.str());
  }
  return {};
}

}  // namespace

void BlueprintLibrary::Add(Blueprint bp) { blueprints_.push_back(std::move(bp)); }

const Blueprint* BlueprintLibrary::Find(const std::string& id) const {
  for (const auto& bp : blueprints_) {
    if (bp.id == id) return &bp;
  }
  return nullptr;
}

std::string BlueprintLibrary::Check(const Blueprint& bp, const std::vector<msg::BlueprintAttribute>& attributes) const {
  for (size_t i = 0; i < attributes.size(); ++i) {
    const auto& a = attributes[i];
    auto def = std::find_if(bp.attributes.begin(), bp.attributes.end(), [&](const AttributeDef& d) { return d.name == a.key(); });
    if (def == bp.attributes.end()) {
      std::string known;
      for (const auto& d : bp.attributes) known += (known.empty() ? "" : ", ") + d.name;
      return "blueprint '" + bp.id + "' has no attribute '" + a.key().to_string() + "' (it has: " + known + ")";
    }
    for (size_t j = 0; j < i; ++j) {
      if (attributes[j].key() == a.key()) return "attribute '" + a.key().to_string() + "' given twice";
    }
    std::string why = CheckValue(*def, a.value().to_string());
    if (!why.empty()) return why;
  }
  return {};
}

BlueprintLibrary BlueprintLibrary::Default() {
  BlueprintLibrary lib;
  const std::vector<AttributeDef> vehicle = With(Common(), {Attr("color", T::kRgb, "128,128,128"), Attr("sticky_control", T::kBool, "true"),
                                                            Attr("number_of_wheels", T::kInt, "4", 2, 18)});
  for (const char* id : {"vehicle.lockstep.sedan", "vehicle.lockstep.hatchback", "vehicle.lockstep.suv", "vehicle.lockstep.van",
                         "vehicle.lockstep.truck", "vehicle.lockstep.bus", "vehicle.lockstep.motorbike"}) {
    lib.Add({id, ActorKind::kVehicle, vehicle});
  }
  const std::vector<AttributeDef> walker = With(Common(), {Attr("speed", T::kFloat, "1.4", 0, 10), Attr("is_invincible", T::kBool, "false")});
  for (int i = 1; i <= 10; ++i) {
    char id[40];
    std::snprintf(id, sizeof id, "walker.pedestrian.%04d", i);
    lib.Add({id, ActorKind::kWalker, walker});
  }
  lib.Add({"drone.generic_quad", ActorKind::kDrone, DroneAttributes("quad_x")});
  lib.Add({"drone.quad_plus", ActorKind::kDrone, DroneAttributes("quad_plus")});
  lib.Add({"drone.hexa_x", ActorKind::kDrone, DroneAttributes("hexa_x")});
  for (const char* cam : {"sensor.camera.rgb", "sensor.camera.depth", "sensor.camera.semantic_segmentation",
                          "sensor.camera.instance_segmentation", "sensor.camera.normals"}) {
    lib.Add({cam, ActorKind::kSensor, CameraAttributes()});
  }
  const auto lidar = With(Common(), {Attr("channels", T::kInt, "32", 1, 256), Attr("range", T::kFloat, "10", 0.1, 1000),
                                     Attr("points_per_second", T::kInt, "56000", 1, 10000000), Attr("rotation_frequency", T::kFloat, "10", 0.1, 1000),
                                     Attr("upper_fov", T::kFloat, "10", -90, 90), Attr("lower_fov", T::kFloat, "-30", -90, 90),
                                     Attr("horizontal_fov", T::kFloat, "360", 1, 360), Attr("atmosphere_attenuation_rate", T::kFloat, "0.004", 0, 1),
                                     Attr("dropoff_general_rate", T::kFloat, "0.45", 0, 1), Attr("dropoff_intensity_limit", T::kFloat, "0.8", 0, 1),
                                     Attr("dropoff_zero_intensity", T::kFloat, "0.4", 0, 1), Attr("noise_stddev", T::kFloat, "0", 0, 10),
                                     Attr("sensor_tick", T::kFloat, "0", 0, 3600)});
  lib.Add({"sensor.lidar.ray_cast", ActorKind::kSensor, lidar});
  lib.Add({"sensor.lidar.ray_cast_semantic", ActorKind::kSensor, lidar});
  lib.Add({"sensor.other.radar", ActorKind::kSensor,
           With(Common(), {Attr("horizontal_fov", T::kFloat, "30", 1, 180), Attr("vertical_fov", T::kFloat, "30", 1, 180),
                           Attr("points_per_second", T::kInt, "1500", 1, 1000000), Attr("range", T::kFloat, "100", 0.1, 1000),
                           Attr("sensor_tick", T::kFloat, "0", 0, 3600)})});
  const auto noisy = [](std::vector<std::string> names) {
    std::vector<AttributeDef> v = Common();
    for (auto& n : names) v.push_back(Attr(n, T::kFloat, "0", 0, 1e6));
    v.push_back(Attr("noise_seed", T::kInt, "0", 0, 4294967295.0));
    v.push_back(Attr("sensor_tick", T::kFloat, "0", 0, 3600));
    return v;
  };
  lib.Add({"sensor.other.gnss", ActorKind::kSensor,
           noisy({"noise_lat_bias", "noise_lat_stddev", "noise_lon_bias", "noise_lon_stddev", "noise_alt_bias", "noise_alt_stddev"})});
  lib.Add({"sensor.other.imu", ActorKind::kSensor,
           noisy({"noise_accel_stddev_x", "noise_accel_stddev_y", "noise_accel_stddev_z", "noise_gyro_bias_x", "noise_gyro_bias_y",
                  "noise_gyro_bias_z", "noise_gyro_stddev_x", "noise_gyro_stddev_y", "noise_gyro_stddev_z"})});
  lib.Add({"sensor.other.barometer", ActorKind::kSensor, noisy({"noise_pressure_stddev"})});
  lib.Add({"sensor.other.magnetometer", ActorKind::kSensor, noisy({"noise_stddev"})});
  lib.Add({"sensor.other.collision", ActorKind::kSensor, Common()});
  lib.Add({"sensor.other.lane_invasion", ActorKind::kSensor, Common()});
  lib.Add({"sensor.other.obstacle", ActorKind::kSensor,
           With(Common(), {Attr("distance", T::kFloat, "5", 0, 1000), Attr("hit_radius", T::kFloat, "0.5", 0, 100),
                           Attr("only_dynamics", T::kBool, "false"), Attr("sensor_tick", T::kFloat, "0", 0, 3600)})});
  return lib;
}

}  // namespace lockstep
