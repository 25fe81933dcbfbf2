#include "lockstep/ground/blueprints.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace lockstep::ground {
namespace {

// Engine and size classes; CARLA's physics defaults scaled to the vehicle.
VehiclePhysics Physics(double mass, double peak_torque, double max_rpm, double wheelbase, double track,
                       double wheel_radius, double steer_deg, double clearance = 0.25) {
  VehiclePhysics p;
  p.mass = mass;
  p.max_rpm = max_rpm;
  p.torque_curve = {{0, 0.8 * peak_torque}, {0.38 * max_rpm, peak_torque}, {max_rpm, 0.8 * peak_torque}};
  p.forward_gears = {{3.5, 0.15, 0.9}, {2.2, 0.5, 0.9}, {1.5, 0.6, 0.9}, {1.1, 0.6, 0.9}, {0.9, 0.6, 1.0}};
  p.final_ratio = 4.0;
  p.wheelbase = wheelbase;
  p.track = track;
  p.wheel_radius = wheel_radius;
  p.max_steer_angle = steer_deg * 3.14159265358979 / 180.0;
  p.ground_clearance = clearance;
  // Brakes and springs scale with mass: ~1 g of braking on dry asphalt, ~1.6 Hz ride.
  p.max_brake_torque = mass * 9.81 * 1.05 / 4.0 * wheel_radius;
  p.max_handbrake_torque = 2 * p.max_brake_torque;
  p.suspension_stiffness = mass / 4.0 * 100.0;
  p.suspension_damping = 2 * 0.5 * std::sqrt(p.suspension_stiffness * mass / 4.0);
  p.suspension_travel = 0.3;
  p.frontal_area = 2.2 * (mass > 2500 ? 2.0 : 1.0);
  return p;
}

const std::vector<std::string> kCarColors = {"17,37,103", "255,255,255", "0,0,0", "200,0,0", "80,80,80", "30,120,30"};

VehicleSpec Car(std::string id, Vec3 half, double mass, double torque, int gen, std::string special = "") {
  VehicleSpec s;
  s.id = std::move(id);
  s.base_type = BaseType::kCar;
  s.half_extents = half;
  s.generation = gen;
  s.colors = kCarColors;
  s.special_type = std::move(special);
  s.physics = Physics(mass, torque, 6000, 1.2 * half.x(), 1.7 * half.y(), 0.34, 36);
  return s;
}

VehicleSpec Big(std::string id, BaseType type, Vec3 half, double mass, double torque, int gen, std::string special = "") {
  VehicleSpec s;
  s.id = std::move(id);
  s.base_type = type;
  s.half_extents = half;
  s.generation = gen;
  s.colors = {"255,255,255", "200,0,0", "30,30,120"};
  s.special_type = std::move(special);
  s.physics = Physics(mass, torque, 4000, 1.25 * half.x(), 1.7 * half.y(), 0.45, 35, 0.35);
  return s;
}

VehicleSpec TwoWheel(std::string id, BaseType type, Vec3 half, double mass, double torque) {
  VehicleSpec s;
  s.id = std::move(id);
  s.base_type = type;
  s.wheels = 2;
  s.half_extents = half;
  s.generation = 2;
  s.colors = {"0,0,0", "200,0,0", "255,255,255"};
  s.has_lights = type == BaseType::kMotorcycle;
  // Two-wheelers ride on a narrow virtual track (no lean model; see docs/ground.md).
  s.physics = Physics(mass, torque, type == BaseType::kBicycle ? 1000 : 9000, 1.4 * half.x(), 0.5, 0.33, 40, 0.2);
  if (type == BaseType::kBicycle) s.physics.forward_gears = {{2.0, 0.1, 1.0}};
  return s;
}

VehicleSpec SixWheel(VehicleSpec s) {
  s.wheels = 6;  // declared as CARLA's; simulated on ground_sim's four-wheel model
  return s;
}

std::vector<VehicleSpec> BuildVehicles() {
  using B = BaseType;
  std::vector<VehicleSpec> v = {
      Car("vehicle.tesla.model3", {2.396, 1.082, 0.745}, 1845, 420, 2, "electric"),
      Car("vehicle.lincoln.mkz_2020", {2.445, 1.065, 0.757}, 1700, 380, 2),
      Car("vehicle.lincoln.mkz_2017", {2.45, 1.064, 0.755}, 1700, 360, 1),
      Car("vehicle.audi.tt", {2.091, 0.997, 0.693}, 1400, 360, 1),
      Car("vehicle.audi.a2", {1.853, 0.901, 0.771}, 1100, 220, 1),
      Car("vehicle.audi.etron", {2.428, 1.039, 0.827}, 2400, 540, 1, "electric"),
      Car("vehicle.bmw.grandtourer", {2.306, 1.12, 0.835}, 1600, 350, 1),
      Car("vehicle.chevrolet.impala", {2.679, 1.013, 0.703}, 1700, 380, 1),
      Car("vehicle.citroen.c3", {1.994, 0.927, 0.807}, 1100, 220, 1),
      Car("vehicle.dodge.charger_2020", {2.504, 1.047, 0.769}, 1900, 520, 2),
      Car("vehicle.dodge.charger_police_2020", {2.611, 1.045, 0.806}, 1900, 520, 2, "emergency"),
      Car("vehicle.ford.mustang", {2.358, 0.947, 0.650}, 1650, 550, 1),
      Car("vehicle.ford.crown", {2.679, 0.9, 0.787}, 1800, 400, 2, "taxi"),
      Car("vehicle.jeep.wrangler_rubicon", {1.934, 0.954, 0.941}, 2000, 400, 1),
      Car("vehicle.mercedes.coupe_2020", {2.337, 1.009, 0.719}, 1700, 400, 2),
      Car("vehicle.mini.cooper_s_2021", {2.268, 1.053, 0.892}, 1300, 300, 2),
      Car("vehicle.nissan.micra", {1.834, 0.904, 0.769}, 1000, 200, 1),
      Car("vehicle.nissan.patrol_2021", {2.782, 1.074, 1.044}, 2700, 560, 2),
      Car("vehicle.seat.leon", {2.096, 0.920, 0.738}, 1300, 300, 1),
      Car("vehicle.toyota.prius", {2.257, 1.007, 0.763}, 1400, 280, 1, "electric"),
      // The rest of CARLA 0.9.15's and 0.9.16's catalogue (their generation 1 twins and new models).
      Car("vehicle.dodge.charger_police", {2.487, 1.019, 0.777}, 1900, 500, 1, "emergency"),
      Car("vehicle.mercedes.coupe", {2.512, 1.076, 0.828}, 1700, 400, 1),
      Car("vehicle.mini.cooper_s", {1.905, 0.985, 0.737}, 1250, 280, 1),
      Car("vehicle.nissan.patrol", {2.305, 0.962, 0.928}, 2600, 540, 1),
      Car("vehicle.micro.microlino", {1.203, 0.742, 0.700}, 513, 90, 1, "electric"),
      Big("vehicle.tesla.cybertruck", B::kTruck, {3.136, 1.194, 1.049}, 3000, 900, 1, "electric"),
      Big("vehicle.carlamotors.carlacola", B::kTruck, {2.602, 1.308, 1.233}, 6000, 1200, 1),
      Big("vehicle.carlamotors.firetruck", B::kTruck, {4.234, 1.426, 1.916}, 12000, 2200, 2, "emergency"),
      Big("vehicle.ford.ambulance", B::kVan, {3.181, 1.186, 1.216}, 3500, 700, 2, "emergency"),
      Big("vehicle.mercedes.sprinter", B::kVan, {2.958, 0.990, 1.279}, 3000, 600, 2),
      Big("vehicle.volkswagen.t2", B::kVan, {2.240, 1.035, 1.021}, 1700, 300, 1),
      Big("vehicle.volkswagen.t2_2021", B::kVan, {2.204, 0.897, 1.020}, 1800, 350, 2),
      Big("vehicle.mitsubishi.fusorosa", B::kBus, {5.136, 1.921, 1.961}, 11000, 2000, 2),
      Big("vehicle.carlamotors.european_hgv", B::kTruck, {4.070, 1.490, 1.910}, 9000, 2000, 2),
      SixWheel(Big("vehicle.sixwheeltruck.sixwheeltruck", B::kTruck, {4.200, 1.300, 1.900}, 12000, 2200, 2)),
      TwoWheel("vehicle.harley-davidson.low_rider", B::kMotorcycle, {1.178, 0.382, 0.638}, 400, 130),
      TwoWheel("vehicle.kawasaki.ninja", B::kMotorcycle, {1.016, 0.402, 0.572}, 350, 110),
      TwoWheel("vehicle.yamaha.yzf", B::kMotorcycle, {1.104, 0.434, 0.625}, 350, 110),
      TwoWheel("vehicle.vespa.zx125", B::kMotorcycle, {0.904, 0.423, 0.617}, 250, 40),
      TwoWheel("vehicle.bh.crossbike", B::kBicycle, {0.744, 0.429, 0.546}, 100, 120),
      TwoWheel("vehicle.diamondback.century", B::kBicycle, {0.821, 0.186, 0.533}, 100, 120),
      TwoWheel("vehicle.gazelle.omafiets", B::kBicycle, {0.919, 0.164, 0.563}, 100, 120),
  };
  return v;
}

std::vector<WalkerSpec> BuildWalkers() {
  std::vector<WalkerSpec> w;
  for (int i = 1; i <= 52; ++i) {
    WalkerSpec s;
    char id[40];
    std::snprintf(id, sizeof id, "walker.pedestrian.%04d", i);
    s.id = id;
    // CARLA's pedestrians 0009-0014 and 0048-0049 are children.
    const bool child = (i >= 9 && i <= 14) || i == 48 || i == 49;
    s.age = child ? "child" : "adult";
    s.gender = (i % 2 == 0) ? "female" : "male";
    s.height = child ? 1.1 + 0.03 * (i % 5) : 1.6 + 0.02 * (i % 12);
    s.radius = child ? 0.25 : 0.34;
    s.walk_speed = child ? 1.2 : 1.4;
    s.run_speed = child ? 2.4 : 2.8;
    s.generation = i <= 26 ? 1 : 2;
    w.push_back(s);
  }
  return w;
}

bool ParseBool(const std::string& key, const std::string& v) {
  if (v == "true" || v == "True" || v == "1") return true;
  if (v == "false" || v == "False" || v == "0") return false;
  throw std::invalid_argument("attribute '" + key + "': '" + v + "' is not a bool");
}

}  // namespace

const char* ToString(BaseType t) {
  switch (t) {
    case BaseType::kCar: return "car";
    case BaseType::kTruck: return "truck";
    case BaseType::kVan: return "van";
    case BaseType::kBus: return "bus";
    case BaseType::kMotorcycle: return "motorcycle";
    case BaseType::kBicycle: return "bicycle";
  }
  return "car";
}

const std::vector<VehicleSpec>& VehicleCatalog() {
  static const std::vector<VehicleSpec> v = BuildVehicles();
  return v;
}
const std::vector<WalkerSpec>& WalkerCatalog() {
  static const std::vector<WalkerSpec> w = BuildWalkers();
  return w;
}
const VehicleSpec* FindVehicle(const std::string& id) {
  for (const auto& v : VehicleCatalog()) {
    if (v.id == id) return &v;
  }
  return nullptr;
}
const WalkerSpec* FindWalker(const std::string& id) {
  for (const auto& w : WalkerCatalog()) {
    if (w.id == id) return &w;
  }
  return nullptr;
}

SpawnAttributes ParseSpawnAttributes(const std::map<std::string, std::string>& attributes) {
  SpawnAttributes a;
  for (const auto& [k, v] : attributes) {
    if (k == "role_name") a.role_name = v;
    else if (k == "color") a.color = v;
    else if (k == "is_invincible") a.invincible = ParseBool(k, v);
    else if (k == "sticky_control") a.sticky_control = ParseBool(k, v);
    else if (k == "speed") {
      double x = 0;
      auto [p, ec] = std::from_chars(v.data(), v.data() + v.size(), x);
      if (ec != std::errc() || p != v.data() + v.size() || !(x >= 0 && x <= 10)) {
        throw std::invalid_argument("attribute 'speed': '" + v + "' is not a walking speed in 0..10 m/s");
      }
      a.walker_speed = x;
    }
  }
  return a;
}

}  // namespace lockstep::ground
