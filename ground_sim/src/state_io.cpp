// Save / restore of the whole ground state (a replacement ground_sim continues bit for
// bit) and the state hash (FNV-1a 64 over the same bytes). Every field is written one by
// one as a number: a struct written whole would carry its padding bytes (whatever the
// memory held), and the same state would give different bytes and hashes.
#include <cstring>
#include <stdexcept>
#include <type_traits>

#include "internal.h"

namespace lockstep::ground {
namespace {

constexpr uint32_t kMagic = 0x47524E44;  // "GRND"
constexpr uint32_t kVersion = 7;  // 2: every field written explicitly (no struct padding); 3: stop signs, contacts of the last step, crosswalks;
                                   // 4: benchmark onsets, distance, off-road fraction, props; 5: pedestrians seed, walker graph routes;
                                   // 6: the weather the TM's vehicle lights follow; 7: lane offsets, collision
                                   // detection, respawn boundaries

class Writer {
 public:
  template <class T>
  void Pod(const T& x) {
    static_assert(std::is_arithmetic_v<T>, "write structs field by field (padding bytes are not state)");
    if constexpr (std::is_same_v<T, bool>) {
      out.push_back(x ? 1 : 0);
    } else {
      const auto* p = reinterpret_cast<const uint8_t*>(&x);
      out.insert(out.end(), p, p + sizeof(T));
    }
  }
  void Str(const std::string& s) {
    Pod<uint32_t>(static_cast<uint32_t>(s.size()));
    out.insert(out.end(), s.begin(), s.end());
  }
  void V(const Vec3& v) { Pod(v.x()), Pod(v.y()), Pod(v.z()); }
  void Q(const Quat& q) { Pod(q.w()), Pod(q.x()), Pod(q.y()), Pod(q.z()); }
  void P(const Pose& p) { V(p.position), Q(p.orientation); }
  void Wp(const map::Waypoint& w) { Pod<int32_t>(w.road), Pod<int32_t>(w.section), Pod<int32_t>(w.lane), Pod(w.s); }
  std::vector<uint8_t> out;
};

class Reader {
 public:
  explicit Reader(const std::vector<uint8_t>& b) : bytes(b) {}
  template <class T>
  T Pod() {
    static_assert(std::is_arithmetic_v<T>, "read structs field by field");
    if (at + sizeof(T) > bytes.size()) throw std::runtime_error("ground state: truncated");
    if constexpr (std::is_same_v<T, bool>) {
      const uint8_t b = bytes[at++];
      if (b > 1) throw std::runtime_error("ground state: corrupt flag");
      return b == 1;
    } else {
      T x;
      std::memcpy(&x, bytes.data() + at, sizeof(T));
      at += sizeof(T);
      return x;
    }
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
    const int road = Pod<int32_t>(), section = Pod<int32_t>(), lane = Pod<int32_t>();
    const double s = Pod<double>();
    return m.MakeWaypoint(road, section, lane, s);
  }
  const std::vector<uint8_t>& bytes;
  size_t at = 0;
};

void PutSettings(Writer& w, const PhysicsSettings& s) {
  w.Pod(s.substepping), w.Pod(s.max_substep_delta_time), w.Pod<int32_t>(s.max_substeps);
}
PhysicsSettings GetSettings(Reader& r) {
  PhysicsSettings s;
  r.Get(&s.substepping), r.Get(&s.max_substep_delta_time);
  s.max_substeps = r.Pod<int32_t>();
  return s;
}

void PutTmGlobal(Writer& w, const TmGlobal& t) {
  for (double x : {t.distance_to_leading_vehicle, t.percentage_speed_difference, t.ignore_lights_percentage,
                   t.ignore_signs_percentage, t.ignore_vehicles_percentage, t.ignore_walkers_percentage, t.keep_right_percentage,
                   t.random_left_lanechange_percentage, t.random_right_lanechange_percentage, t.hybrid_physics_radius,
                   t.blocked_time_threshold, t.red_light_blocked_time_threshold, t.lane_offset, t.respawn_lower_bound,
                   t.respawn_upper_bound, t.actor_active_distance})
    w.Pod(x);
  for (bool b : {t.auto_lane_change, t.hybrid_physics_mode, t.synchronous_mode, t.respawn_dormant_vehicles}) w.Pod(b);
  w.Pod(t.random_seed);
}
void GetTmGlobal(Reader& r, TmGlobal* t) {
  for (double* x : {&t->distance_to_leading_vehicle, &t->percentage_speed_difference, &t->ignore_lights_percentage,
                    &t->ignore_signs_percentage, &t->ignore_vehicles_percentage, &t->ignore_walkers_percentage,
                    &t->keep_right_percentage, &t->random_left_lanechange_percentage, &t->random_right_lanechange_percentage,
                    &t->hybrid_physics_radius, &t->blocked_time_threshold, &t->red_light_blocked_time_threshold,
                    &t->lane_offset, &t->respawn_lower_bound, &t->respawn_upper_bound, &t->actor_active_distance})
    *x = r.Pod<double>();
  for (bool* b : {&t->auto_lane_change, &t->hybrid_physics_mode, &t->synchronous_mode, &t->respawn_dormant_vehicles})
    *b = r.Pod<bool>();
  r.Get(&t->random_seed);
}

void PutTmParams(Writer& w, const TmVehicleParams& p) {
  for (double x : {p.distance_to_leading_vehicle, p.percentage_speed_difference, p.desired_speed, p.ignore_lights_percentage,
                   p.ignore_signs_percentage, p.ignore_vehicles_percentage, p.ignore_walkers_percentage, p.auto_lane_change,
                   p.keep_right_percentage, p.random_left_lanechange_percentage, p.random_right_lanechange_percentage,
                   p.lane_offset})
    w.Pod(x);
  w.Pod(p.update_lights);
}
void GetTmParams(Reader& r, TmVehicleParams* p) {
  for (double* x : {&p->distance_to_leading_vehicle, &p->percentage_speed_difference, &p->desired_speed,
                    &p->ignore_lights_percentage, &p->ignore_signs_percentage, &p->ignore_vehicles_percentage,
                    &p->ignore_walkers_percentage, &p->auto_lane_change, &p->keep_right_percentage,
                    &p->random_left_lanechange_percentage, &p->random_right_lanechange_percentage, &p->lane_offset})
    *x = r.Pod<double>();
  r.Get(&p->update_lights);
}

void PutLight(Writer& w, const LightState& l) {
  w.Pod<int32_t>(static_cast<int32_t>(l.color)), w.Pod(l.elapsed), w.Pod(l.green_time), w.Pod(l.yellow_time), w.Pod(l.red_time);
  w.Pod(l.frozen), w.Pod<int32_t>(l.group);
}
LightState GetLight(Reader& r) {
  LightState l;
  const auto color = r.Pod<int32_t>();
  if (color < 0 || color > static_cast<int32_t>(LightColor::kUnknown)) throw std::runtime_error("ground state: bad light colour");
  l.color = static_cast<LightColor>(color);
  r.Get(&l.elapsed), r.Get(&l.green_time), r.Get(&l.yellow_time), r.Get(&l.red_time), r.Get(&l.frozen);
  l.group = r.Pod<int32_t>();
  return l;
}

void PutControl(Writer& w, const VehicleControl& c) {
  w.Pod(c.throttle), w.Pod(c.steer), w.Pod(c.brake), w.Pod(c.hand_brake), w.Pod(c.reverse), w.Pod(c.manual_gear_shift);
  w.Pod<int32_t>(c.gear);
}
VehicleControl GetControl(Reader& r) {
  VehicleControl c;
  r.Get(&c.throttle), r.Get(&c.steer), r.Get(&c.brake), r.Get(&c.hand_brake), r.Get(&c.reverse), r.Get(&c.manual_gear_shift);
  c.gear = r.Pod<int32_t>();
  return c;
}

void PutAckermann(Writer& w, const AckermannControl& a) {
  w.Pod(a.steer), w.Pod(a.steer_speed), w.Pod(a.speed), w.Pod(a.acceleration), w.Pod(a.jerk);
}
AckermannControl GetAckermann(Reader& r) {
  AckermannControl a;
  r.Get(&a.steer), r.Get(&a.steer_speed), r.Get(&a.speed), r.Get(&a.acceleration), r.Get(&a.jerk);
  return a;
}

void PutInfractions(Writer& w, const Infractions& f) {
  for (int x : {f.red_lights, f.vehicle_collisions, f.walker_collisions, f.static_collisions, f.lane_invasions, f.stop_signs,
                f.opposite_lane, f.offroad})
    w.Pod<int32_t>(x);
  w.Pod(f.distance);
}
Infractions GetInfractions(Reader& r) {
  Infractions f;
  for (int* x : {&f.red_lights, &f.vehicle_collisions, &f.walker_collisions, &f.static_collisions, &f.lane_invasions,
                 &f.stop_signs, &f.opposite_lane, &f.offroad})
    *x = r.Pod<int32_t>();
  r.Get(&f.distance);
  return f;
}

void PutPhysics(Writer& w, const VehiclePhysics& p) {
  w.Pod<uint32_t>(static_cast<uint32_t>(p.torque_curve.size()));
  for (auto [r, t] : p.torque_curve) w.Pod(r), w.Pod(t);
  w.Pod<uint32_t>(static_cast<uint32_t>(p.forward_gears.size()));
  for (const auto& g : p.forward_gears) w.Pod(g.ratio), w.Pod(g.down_ratio), w.Pod(g.up_ratio);
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
  for (auto& g : p.forward_gears) r.Get(&g.ratio), r.Get(&g.down_ratio), r.Get(&g.up_ratio);
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
// The saved orientation exactly: dBodySetQuaternion normalises again, which can move the
// last bit, and the restored world would then drift from the one that was saved.
void SetExactPose(dBodyID b, const Pose& p) {
  SetBodyPose(b, p);  // position, geoms marked moved
  auto* q = const_cast<dReal*>(dBodyGetQuaternion(b));  // ODE's own storage (documented as such)
  q[0] = p.orientation.w(), q[1] = p.orientation.x(), q[2] = p.orientation.y(), q[3] = p.orientation.z();
  dQtoR(q, const_cast<dReal*>(dBodyGetRotation(b)));  // what each ODE step does after normalising
}

void GetBody(Reader& r, dBodyID b) {
  SetExactPose(b, r.P());
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
  for (int x : s.route) w.Pod<int32_t>(x);
  w.Pod(s.rng.s), w.Pod(s.speed), w.Pod(s.blocked), w.Pod<int32_t>(s.committed_junction), w.Pod(s.waiting), w.Pod<int32_t>(s.lane_change);
  w.Pod(s.lane_change_cooldown), w.Pod(s.random_draw_timer), w.Pod(s.ignore_draw_key), w.Pod(s.ignore_light);
  w.Pod(s.ignore_sign), w.Pod(s.sign_wait), w.Pod(s.sign_done_key);
  w.Pod(s.entry_key), w.Pod(s.front_to_line), w.P(s.kin_target), PutTmParams(w, s.params), w.Pod(s.target_speed);
  w.Pod(s.steer_angle), w.Pod<int32_t>(s.light), w.Pod(s.light_distance);
  w.Pod<uint32_t>(static_cast<uint32_t>(s.ignore_collision.size()));
  for (uint32_t id : s.ignore_collision) w.Pod(id);
}
void GetTm(Reader& r, const map::Map& m, TmState* s) {
  s->path = GetWaypoints(r, m);
  s->planned = GetWaypoints(r, m);
  s->route.resize(r.Pod<uint32_t>());
  for (int& x : s->route) x = r.Pod<int32_t>();
  r.Get(&s->rng.s), r.Get(&s->speed), r.Get(&s->blocked), s->committed_junction = r.Pod<int32_t>();
  r.Get(&s->waiting);
  s->lane_change = r.Pod<int32_t>();
  r.Get(&s->lane_change_cooldown), r.Get(&s->random_draw_timer), r.Get(&s->ignore_draw_key), r.Get(&s->ignore_light);
  r.Get(&s->ignore_sign), r.Get(&s->sign_wait), r.Get(&s->sign_done_key);
  r.Get(&s->entry_key), r.Get(&s->front_to_line);
  s->kin_target = r.P();
  GetTmParams(r, &s->params), r.Get(&s->target_speed), r.Get(&s->steer_angle);
  s->light = r.Pod<int32_t>();
  r.Get(&s->light_distance);
  const auto ignored = r.Pod<uint32_t>();
  for (uint32_t k = 0; k < ignored; ++k) s->ignore_collision.insert(r.Pod<uint32_t>());
}

}  // namespace

std::vector<uint8_t> World::Save() const {
  const Impl& I = *impl_;
  Writer w;
  w.Pod(kMagic), w.Pod(kVersion), w.Pod(I.town->Hash()), w.Pod(I.seed), w.Pod(I.frame);
  PutSettings(w, I.settings), PutTmGlobal(w, I.tm);
  w.Pod(I.tm_rng.s);
  w.Pod<uint32_t>(static_cast<uint32_t>(I.lights.size()));
  for (const auto& l : I.lights) PutLight(w, l);
  for (size_t g = 0; g < I.group_current.size(); ++g) w.Pod<int32_t>(I.group_current[g]), w.Pod<bool>(I.group_all_red[g]);
  w.Pod<uint32_t>(static_cast<uint32_t>(I.vehicles.size()));
  for (const auto& [id, vp] : I.vehicles) {
    const VehicleActor& v = *vp;
    w.Pod(v.id), w.Str(v.blueprint), PutAttributes(w, v.attributes), PutPhysics(w, v.physics), PutBody(w, v.body);
    PutControl(w, v.control), w.Pod(v.use_ackermann), PutAckermann(w, v.ackermann), w.Pod(v.ackermann_integral), w.Pod(v.steer_angle);
    w.Pod(v.simulate_physics), w.Pod(v.kinematic), w.Pod<int32_t>(v.gear), w.Pod(v.gear_timer), w.V(v.prev_velocity), w.V(v.acceleration);
    w.Pod(v.light_state), w.Pod(v.autopilot), PutTm(w, v.tm), PutFootprint(w, v.footprint), w.Pod(v.has_footprint), w.Pod(v.speed_limit);
    w.Pod(v.opposite_lane), w.Pod(v.sidewalk), w.Pod(v.offroad), PutInfractions(w, v.infractions);
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
    w.Pod(c.planned), w.V(c.goal_point);
    w.Pod<uint32_t>(static_cast<uint32_t>(c.route.size()));
    for (const auto& [node, crossing] : c.route) w.Pod<int32_t>(node), w.Pod<int32_t>(crossing);
    w.Pod(c.rng.s);
    w.Pod<int32_t>(c.at_node), w.Pod<int32_t>(c.came_from), w.Pod<int32_t>(c.drawn_node);
    w.Pod<int32_t>(c.crossing), w.Pod<int32_t>(c.cross_end), w.Pod(c.cross_wait);
  }
  w.Pod(I.cross_factor), w.Pod(I.has_pedestrians_seed), w.Pod(I.pedestrians_seed);
  w.Pod<uint32_t>(static_cast<uint32_t>(I.last_contacts.size()));
  for (const auto& [a, b] : I.last_contacts) w.Pod(a), w.Pod(b);
  w.Pod<uint32_t>(static_cast<uint32_t>(I.props.size()));
  for (const auto& [id, p] : I.props) w.Pod(p->id), w.V(p->pose.position), w.Q(p->pose.orientation), w.V(p->half_extents);
  w.Pod(I.weather.sun_altitude_angle), w.Pod(I.weather.precipitation), w.Pod(I.weather.fog_density);
  return std::move(w.out);
}

std::unique_ptr<World> World::Restore(std::shared_ptr<const Town> town, const std::vector<uint8_t>& bytes) {
  Reader r(bytes);
  if (r.Pod<uint32_t>() != kMagic) throw std::runtime_error("ground state: not a ground_sim snapshot");
  if (r.Pod<uint32_t>() != kVersion) throw std::runtime_error("ground state: unsupported version");
  if (r.Pod<uint64_t>() != town->Hash()) throw std::runtime_error("ground state: saved on another town");
  const auto seed = r.Pod<uint64_t>();
  const auto frame = r.Pod<uint64_t>();
  const PhysicsSettings settings = GetSettings(r);
  auto world = std::make_unique<World>(town, seed, settings);
  Impl& I = *world->impl_;
  const map::Map& m = town->Map();
  I.frame = frame;
  GetTmGlobal(r, &I.tm);
  r.Get(&I.tm_rng.s);
  if (r.Pod<uint32_t>() != I.lights.size()) throw std::runtime_error("ground state: traffic light count differs");
  for (auto& l : I.lights) l = GetLight(r);
  for (size_t g = 0; g < I.group_current.size(); ++g) {
    I.group_current[g] = r.Pod<int32_t>();
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
    v.control = GetControl(r);
    r.Get(&v.use_ackermann);
    v.ackermann = GetAckermann(r);
    r.Get(&v.ackermann_integral), r.Get(&v.steer_angle);
    r.Get(&v.simulate_physics), r.Get(&v.kinematic);
    v.gear = r.Pod<int32_t>();
    r.Get(&v.gear_timer);
    v.prev_velocity = r.V();
    v.acceleration = r.V();
    r.Get(&v.light_state), r.Get(&v.autopilot);
    GetTm(r, m, &v.tm);
    v.footprint = GetFootprint(r), r.Get(&v.has_footprint), r.Get(&v.speed_limit), r.Get(&v.opposite_lane), r.Get(&v.sidewalk),
        r.Get(&v.offroad);
    v.infractions = GetInfractions(r);
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
    r.Get(&c.planned);
    c.goal_point = r.V();
    const int nodes = static_cast<int>(town->WalkerNav().NodeCount());
    const int crossings = static_cast<int>(town->Crosswalks().size());
    auto node_ok = [nodes](int n) { return n >= -1 && n < nodes; };
    auto crossing_ok = [crossings](int x) { return x >= -1 && x < crossings; };
    const auto nroute = r.Pod<uint32_t>();
    for (uint32_t q = 0; q < nroute; ++q) {
      const int node = r.Pod<int32_t>();
      const int crossing = r.Pod<int32_t>();
      if (node < 0 || !node_ok(node) || !crossing_ok(crossing)) throw std::runtime_error("ground state: bad route of a walker controller");
      c.route.emplace_back(node, crossing);
    }
    r.Get(&c.rng.s);
    c.at_node = r.Pod<int32_t>();
    c.came_from = r.Pod<int32_t>();
    c.drawn_node = r.Pod<int32_t>();
    c.crossing = r.Pod<int32_t>();
    c.cross_end = r.Pod<int32_t>();
    r.Get(&c.cross_wait);
    if (!node_ok(c.at_node) || !node_ok(c.came_from) || !node_ok(c.drawn_node) || !crossing_ok(c.crossing) || c.cross_end < 0 ||
        c.cross_end > 1)
      throw std::runtime_error("ground state: bad graph position of a walker controller");
    I.controllers.emplace(c.id, std::move(c));
  }
  r.Get(&I.cross_factor), r.Get(&I.has_pedestrians_seed), r.Get(&I.pedestrians_seed);
  const auto ncontacts = r.Pod<uint32_t>();
  for (uint32_t k = 0; k < ncontacts; ++k) {
    const auto a = r.Pod<uint32_t>();
    I.last_contacts.emplace(a, r.Pod<uint32_t>());
  }
  const auto nprops = r.Pod<uint32_t>();
  for (uint32_t k = 0; k < nprops; ++k) {
    const auto id = r.Pod<uint32_t>();
    Pose p;
    p.position = r.V();
    p.orientation = r.Q();
    const Vec3 half = r.V();
    const std::string err = world->AddProp(id, p, half);
    if (!err.empty()) throw std::runtime_error("ground state: " + err);
  }
  r.Get(&I.weather.sun_altitude_angle), r.Get(&I.weather.precipitation), r.Get(&I.weather.fog_density);
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
