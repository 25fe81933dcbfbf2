// Save / restore of the whole ground state (a replacement ground_sim continues bit for
// bit) and the state hash (FNV-1a 64 over the same bytes).
#include <cstring>
#include <stdexcept>
#include <type_traits>

#include "internal.h"

namespace lockstep::ground {
namespace {

constexpr uint32_t kMagic = 0x47524E44;  // "GRND"
constexpr uint32_t kVersion = 1;

class Writer {
 public:
  template <class T>
  void Pod(const T& x) {
    static_assert(std::is_trivially_copyable_v<T>);
    const auto* p = reinterpret_cast<const uint8_t*>(&x);
    out.insert(out.end(), p, p + sizeof(T));
  }
  void Str(const std::string& s) {
    Pod<uint32_t>(static_cast<uint32_t>(s.size()));
    out.insert(out.end(), s.begin(), s.end());
  }
  void V(const Vec3& v) { Pod(v.x()), Pod(v.y()), Pod(v.z()); }
  void Q(const Quat& q) { Pod(q.w()), Pod(q.x()), Pod(q.y()), Pod(q.z()); }
  void P(const Pose& p) { V(p.position), Q(p.orientation); }
  void Wp(const map::Waypoint& w) { Pod(w.road), Pod(w.section), Pod(w.lane), Pod(w.s); }
  std::vector<uint8_t> out;
};

class Reader {
 public:
  explicit Reader(const std::vector<uint8_t>& b) : bytes(b) {}
  template <class T>
  T Pod() {
    static_assert(std::is_trivially_copyable_v<T>);
    if (at + sizeof(T) > bytes.size()) throw std::runtime_error("ground state: truncated");
    T x;
    std::memcpy(&x, bytes.data() + at, sizeof(T));
    at += sizeof(T);
    return x;
  }
  template <class T>
  void Get(T* x) { *x = Pod<T>(); }
  std::string Str() {
    const auto n = Pod<uint32_t>();
    if (at + n > bytes.size()) throw std::runtime_error("ground state: truncated string");
    std::string s(reinterpret_cast<const char*>(bytes.data() + at), n);
    at += n;
    return s;
  }
  Vec3 V() {
    const double x = Pod<double>(), y = Pod<double>(), z = Pod<double>();
    return Vec3(x, y, z);
  }
  Quat Q() {
    const double w = Pod<double>(), x = Pod<double>(), y = Pod<double>(), z = Pod<double>();
    return Quat(w, x, y, z);
  }
  Pose P() {
    Pose p;
    p.position = V();
    p.orientation = Q();
    return p;
  }
  map::Waypoint Wp(const map::Map& m) {
    const int road = Pod<int>(), section = Pod<int>(), lane = Pod<int>();
    const double s = Pod<double>();
    return m.MakeWaypoint(road, section, lane, s);
  }
  const std::vector<uint8_t>& bytes;
  size_t at = 0;
};

void PutPhysics(Writer& w, const VehiclePhysics& p) {
  w.Pod<uint32_t>(static_cast<uint32_t>(p.torque_curve.size()));
  for (auto [r, t] : p.torque_curve) w.Pod(r), w.Pod(t);
  w.Pod<uint32_t>(static_cast<uint32_t>(p.forward_gears.size()));
  for (const auto& g : p.forward_gears) w.Pod(g);
  for (double x : {p.max_rpm, p.moi, p.damping_rate_full_throttle, p.gear_switch_time, p.clutch_strength, p.final_ratio, p.mass,
                   p.drag_coefficient, p.frontal_area, p.tire_friction, p.wheel_radius, p.max_steer_angle, p.max_brake_torque,
                   p.max_handbrake_torque, p.suspension_stiffness, p.suspension_damping, p.suspension_travel, p.wheelbase,
                   p.track, p.ground_clearance})
    w.Pod(x);
  w.Pod(p.use_gear_autobox);
  w.V(p.center_of_mass);
}

VehiclePhysics GetPhysics(Reader& r) {
  VehiclePhysics p;
  p.torque_curve.resize(r.Pod<uint32_t>());
  for (auto& [a, b] : p.torque_curve) a = r.Pod<double>(), b = r.Pod<double>();
  p.forward_gears.resize(r.Pod<uint32_t>());
  for (auto& g : p.forward_gears) g = r.Pod<GearSpec>();
  for (double* x : {&p.max_rpm, &p.moi, &p.damping_rate_full_throttle, &p.gear_switch_time, &p.clutch_strength, &p.final_ratio,
                    &p.mass, &p.drag_coefficient, &p.frontal_area, &p.tire_friction, &p.wheel_radius, &p.max_steer_angle,
                    &p.max_brake_torque, &p.max_handbrake_torque, &p.suspension_stiffness, &p.suspension_damping,
                    &p.suspension_travel, &p.wheelbase, &p.track, &p.ground_clearance})
    *x = r.Pod<double>();
  p.use_gear_autobox = r.Pod<bool>();
  p.center_of_mass = r.V();
  return p;
}

void PutAttributes(Writer& w, const SpawnAttributes& a) {
  w.Str(a.role_name), w.Str(a.color), w.Pod(a.walker_speed), w.Pod(a.invincible), w.Pod(a.sticky_control);
}
SpawnAttributes GetAttributes(Reader& r) {
  SpawnAttributes a;
  a.role_name = r.Str();
  a.color = r.Str();
  r.Get(&a.walker_speed), r.Get(&a.invincible), r.Get(&a.sticky_control);
  return a;
}

void PutBody(Writer& w, dBodyID b) {
  w.P(BodyPose(b));
  w.V(ToVec(dBodyGetLinearVel(b)));
  w.V(ToVec(dBodyGetAngularVel(b)));
  w.Pod<bool>(dBodyIsKinematic(b) != 0);
}
void GetBody(Reader& r, dBodyID b) {
  SetBodyPose(b, r.P());
  const Vec3 v = r.V(), a = r.V();
  const bool kinematic = r.Pod<bool>();
  if (kinematic) dBodySetKinematic(b);
  else dBodySetDynamic(b);
  dBodySetLinearVel(b, v.x(), v.y(), v.z());
  dBodySetAngularVel(b, a.x(), a.y(), a.z());
}

void PutFootprint(Writer& w, const map::Footprint& f) {
  for (const auto& c : f) w.Pod(c.x()), w.Pod(c.y());
}
map::Footprint GetFootprint(Reader& r) {
  map::Footprint f;
  for (auto& c : f) {
    const double x = r.Pod<double>(), y = r.Pod<double>();
    c = Eigen::Vector2d(x, y);
  }
  return f;
}

void PutWaypoints(Writer& w, const std::deque<map::Waypoint>& d) {
  w.Pod<uint32_t>(static_cast<uint32_t>(d.size()));
  for (const auto& x : d) w.Wp(x);
}
std::deque<map::Waypoint> GetWaypoints(Reader& r, const map::Map& m) {
  std::deque<map::Waypoint> d(r.Pod<uint32_t>());
  for (auto& x : d) x = r.Wp(m);
  return d;
}

void PutTm(Writer& w, const TmState& s) {
  PutWaypoints(w, s.path);
  PutWaypoints(w, s.planned);
  w.Pod<uint32_t>(static_cast<uint32_t>(s.route.size()));
  for (int x : s.route) w.Pod(x);
  w.Pod(s.rng.s), w.Pod(s.speed), w.Pod(s.blocked), w.Pod(s.committed_junction), w.Pod(s.waiting), w.Pod(s.lane_change);
  w.Pod(s.lane_change_cooldown), w.Pod(s.random_draw_timer), w.Pod(s.ignore_draw_key), w.Pod(s.ignore_light);
  w.Pod(s.entry_key), w.Pod(s.front_to_line), w.P(s.kin_target), w.Pod(s.params), w.Pod(s.target_speed);
  w.Pod(s.steer_angle), w.Pod(s.light), w.Pod(s.light_distance);
}
void GetTm(Reader& r, const map::Map& m, TmState* s) {
  s->path = GetWaypoints(r, m);
  s->planned = GetWaypoints(r, m);
  s->route.resize(r.Pod<uint32_t>());
  for (int& x : s->route) x = r.Pod<int>();
  r.Get(&s->rng.s), r.Get(&s->speed), r.Get(&s->blocked), r.Get(&s->committed_junction), r.Get(&s->waiting), r.Get(&s->lane_change);
  r.Get(&s->lane_change_cooldown), r.Get(&s->random_draw_timer), r.Get(&s->ignore_draw_key), r.Get(&s->ignore_light);
  r.Get(&s->entry_key), r.Get(&s->front_to_line);
  s->kin_target = r.P();
  r.Get(&s->params), r.Get(&s->target_speed), r.Get(&s->steer_angle), r.Get(&s->light), r.Get(&s->light_distance);
}

}  // namespace

std::vector<uint8_t> World::Save() const {
  const Impl& I = *impl_;
  Writer w;
  w.Pod(kMagic), w.Pod(kVersion), w.Pod(I.town->Hash()), w.Pod(I.seed), w.Pod(I.frame), w.Pod(I.settings), w.Pod(I.tm);
  w.Pod(I.tm_rng.s);
  w.Pod<uint32_t>(static_cast<uint32_t>(I.lights.size()));
  for (const auto& l : I.lights) w.Pod(l);
  for (size_t g = 0; g < I.group_current.size(); ++g) w.Pod(I.group_current[g]), w.Pod<bool>(I.group_all_red[g]);
  w.Pod<uint32_t>(static_cast<uint32_t>(I.vehicles.size()));
  for (const auto& [id, vp] : I.vehicles) {
    const VehicleActor& v = *vp;
    w.Pod(v.id), w.Str(v.blueprint), PutAttributes(w, v.attributes), PutPhysics(w, v.physics), PutBody(w, v.body);
    w.Pod(v.control), w.Pod(v.use_ackermann), w.Pod(v.ackermann), w.Pod(v.ackermann_integral), w.Pod(v.steer_angle);
    w.Pod(v.simulate_physics), w.Pod(v.kinematic), w.Pod(v.gear), w.Pod(v.gear_timer), w.V(v.prev_velocity), w.V(v.acceleration);
    w.Pod(v.light_state), w.Pod(v.autopilot), PutTm(w, v.tm), PutFootprint(w, v.footprint), w.Pod(v.has_footprint), w.Pod(v.speed_limit);
    w.Pod(v.opposite_lane), w.Pod(v.sidewalk), w.Pod(v.infractions);
  }
  w.Pod<uint32_t>(static_cast<uint32_t>(I.walkers.size()));
  for (const auto& [id, wp] : I.walkers) {
    const WalkerActor& a = *wp;
    w.Pod(a.id), w.Str(a.blueprint), PutAttributes(w, a.attributes), PutBody(w, a.body);
    w.V(a.control.direction), w.Pod(a.control.speed), w.Pod(a.control.jump), w.Pod(a.vertical_speed), w.Pod(a.airborne);
    w.V(a.velocity), w.Pod(a.controller);
  }
  w.Pod<uint32_t>(static_cast<uint32_t>(I.controllers.size()));
  for (const auto& [id, c] : I.controllers) {
    w.Pod(c.id), w.Pod(c.walker), w.Pod(c.running), w.Pod(c.max_speed), w.Pod(c.has_goal), w.V(c.goal);
    PutWaypoints(w, c.path);
    w.Pod(c.rng.s);
  }
  return std::move(w.out);
}

std::unique_ptr<World> World::Restore(std::shared_ptr<const Town> town, const std::vector<uint8_t>& bytes) {
  Reader r(bytes);
  if (r.Pod<uint32_t>() != kMagic) throw std::runtime_error("ground state: not a ground_sim snapshot");
  if (r.Pod<uint32_t>() != kVersion) throw std::runtime_error("ground state: unsupported version");
  if (r.Pod<uint64_t>() != town->Hash()) throw std::runtime_error("ground state: saved on another town");
  const auto seed = r.Pod<uint64_t>();
  const auto frame = r.Pod<uint64_t>();
  const auto settings = r.Pod<PhysicsSettings>();
  auto world = std::make_unique<World>(town, seed, settings);
  Impl& I = *world->impl_;
  const map::Map& m = town->Map();
  I.frame = frame;
  r.Get(&I.tm);
  r.Get(&I.tm_rng.s);
  if (r.Pod<uint32_t>() != I.lights.size()) throw std::runtime_error("ground state: traffic light count differs");
  for (auto& l : I.lights) l = r.Pod<LightState>();
  for (size_t g = 0; g < I.group_current.size(); ++g) {
    I.group_current[g] = r.Pod<int>();
    I.group_all_red[g] = r.Pod<bool>();
  }
  const auto nv = r.Pod<uint32_t>();
  for (uint32_t k = 0; k < nv; ++k) {
    const auto id = r.Pod<uint32_t>();
    const std::string bp = r.Str();
    const SpawnAttributes attrs = GetAttributes(r);
    const std::string err = world->AddVehicle(id, bp, {}, Pose{});
    if (!err.empty()) throw std::runtime_error("ground state: " + err);
    VehicleActor& v = *I.vehicles.at(id);
    v.attributes = attrs;
    const VehiclePhysics phys = GetPhysics(r);
    world->SetVehiclePhysics(id, phys);
    GetBody(r, v.body);
    r.Get(&v.control), r.Get(&v.use_ackermann), r.Get(&v.ackermann), r.Get(&v.ackermann_integral), r.Get(&v.steer_angle);
    r.Get(&v.simulate_physics), r.Get(&v.kinematic), r.Get(&v.gear), r.Get(&v.gear_timer);
    v.prev_velocity = r.V();
    v.acceleration = r.V();
    r.Get(&v.light_state), r.Get(&v.autopilot);
    GetTm(r, m, &v.tm);
    v.footprint = GetFootprint(r), r.Get(&v.has_footprint), r.Get(&v.speed_limit), r.Get(&v.opposite_lane), r.Get(&v.sidewalk);
    r.Get(&v.infractions);
  }
  const auto nw = r.Pod<uint32_t>();
  for (uint32_t k = 0; k < nw; ++k) {
    const auto id = r.Pod<uint32_t>();
    const std::string bp = r.Str();
    const SpawnAttributes attrs = GetAttributes(r);
    const std::string err = world->AddWalker(id, bp, {}, Pose{});
    if (!err.empty()) throw std::runtime_error("ground state: " + err);
    WalkerActor& a = *I.walkers.at(id);
    a.attributes = attrs;
    GetBody(r, a.body);
    a.control.direction = r.V();
    r.Get(&a.control.speed), r.Get(&a.control.jump), r.Get(&a.vertical_speed), r.Get(&a.airborne);
    a.velocity = r.V();
    r.Get(&a.controller);
  }
  const auto nc = r.Pod<uint32_t>();
  for (uint32_t k = 0; k < nc; ++k) {
    ControllerActor c;
    r.Get(&c.id), r.Get(&c.walker), r.Get(&c.running), r.Get(&c.max_speed), r.Get(&c.has_goal);
    c.goal = r.V();
    c.path = GetWaypoints(r, m);
    r.Get(&c.rng.s);
    I.controllers.emplace(c.id, std::move(c));
  }
  if (r.at != bytes.size()) throw std::runtime_error("ground state: trailing bytes");
  return world;
}

uint64_t World::StateHash() const {
  const std::vector<uint8_t> bytes = Save();
  uint64_t h = 1469598103934665603ull;
  for (uint8_t b : bytes) h = (h ^ b) * 1099511628211ull;
  return h;
}

PopulationReport Populate(World* world, int n_vehicles, int n_walkers, uint64_t seed, uint32_t first_id,
                          const std::vector<std::string>& blueprints) {
  PopulationReport rep;
  Rng rng{MixSeed(seed, 0x90901)};
  std::vector<std::string> bps = blueprints;
  if (bps.empty()) {
    // generate_traffic.py's default filter: four-wheeled cars.
    for (const auto& v : VehicleCatalog()) {
      if (v.base_type == BaseType::kCar) bps.push_back(v.id);
    }
  }
  auto points = world->town().SpawnPoints();
  for (size_t i = points.size(); i > 1; --i) std::swap(points[i - 1], points[static_cast<size_t>(rng.Next() % i)]);
  uint32_t id = first_id;
  for (int k = 0; k < n_vehicles && k < static_cast<int>(points.size()); ++k) {
    const std::string& bp = bps[static_cast<size_t>(rng.Next() % bps.size())];
    const VehicleSpec* spec = FindVehicle(bp);
    const auto& sp = points[static_cast<size_t>(k)];
    // Spawn points are 0.5 m above the road; the box centre sits half its height up.
    const Pose pose = Pose::FromYaw(sp.location + Vec3(0, 0, spec->half_extents.z() - 0.5 + 0.02), sp.yaw);
    if (!world->CheckFree(pose, spec->half_extents).empty()) {
      ++rep.vehicle_failures;
      continue;
    }
    if (world->AddVehicle(id, bp, {{"role_name", "autopilot"}}, pose).empty()) {
      world->SetAutopilot(id, true);
      rep.vehicles.push_back(id++);
    }
  }
  auto wpoints = world->town().WalkerSpawnPoints();
  for (size_t i = wpoints.size(); i > 1; --i) std::swap(wpoints[i - 1], wpoints[static_cast<size_t>(rng.Next() % i)]);
  const auto& walkers = WalkerCatalog();
  for (int k = 0; k < n_walkers && k < static_cast<int>(wpoints.size()); ++k) {
    const WalkerSpec& spec = walkers[static_cast<size_t>(rng.Next() % walkers.size())];
    const auto& sp = wpoints[static_cast<size_t>(k)];
    const Pose pose = Pose::FromYaw(sp.location + Vec3(0, 0, spec.height / 2 + 0.2), sp.yaw);
    if (!world->AddWalker(id, spec.id, {}, pose).empty()) continue;
    rep.walkers.push_back(id);
    const uint32_t controller = id + 1;
    if (world->AddWalkerController(controller, id).empty()) {
      world->ControllerStart(controller);
      rep.controllers.push_back(controller);
    }
    id += 2;
  }
  return rep;
}

}  // namespace lockstep::ground
