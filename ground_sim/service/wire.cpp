#include "wire.h"

#include <charconv>
#include <initializer_list>
#include <type_traits>

#include "lockstep/runtime/blueprint_builder.h"

namespace lockstep::ground_wire {
namespace {

// Numbers as the shortest text that reads back exactly, separated by spaces.
std::string Numbers(std::initializer_list<double> values) {
  std::string out;
  char buf[32];
  for (double v : values) {
    auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v);
    if (!out.empty()) out += ' ';
    out.append(buf, ec == std::errc() ? end : buf);
  }
  return out;
}

// The physics ground_sim simulates a vehicle blueprint with from its spawn on, as hidden
// attributes ('_physics.*', which the carla package does not list): a client answers
// get_physics_control() before the vehicle's first state, as CARLA does at once.
void DeclarePhysics(const ground::VehiclePhysics& p, std::vector<msg::AttributeDeclaration>* attrs) {
  namespace bp = blueprint;
  std::string curve, gears;
  auto append = [](std::string* out, const std::string& more) {
    if (!out->empty()) out->push_back(' ');
    out->append(more);
  };
  for (auto [rpm, nm] : p.torque_curve) append(&curve, Numbers({rpm, nm}));
  for (const auto& g : p.forward_gears) append(&gears, Numbers({g.ratio, g.down_ratio, g.up_ratio}));
  attrs->push_back(bp::String("_physics.engine",
                              Numbers({p.max_rpm, p.moi, p.damping_rate_full_throttle, p.use_gear_autobox ? 1.0 : 0.0,
                                       p.gear_switch_time, p.clutch_strength, p.final_ratio}),
                              {}, false, false));
  attrs->push_back(bp::String("_physics.torque_curve", curve, {}, false, false));
  attrs->push_back(bp::String("_physics.gears", gears, {}, false, false));
  attrs->push_back(bp::String("_physics.body",
                              Numbers({p.mass, p.drag_coefficient, p.center_of_mass.x(), p.center_of_mass.y(),
                                       p.center_of_mass.z()}),
                              {}, false, false));
  attrs->push_back(bp::String("_physics.wheels",
                              Numbers({p.tire_friction, p.wheel_radius, p.max_steer_angle, p.max_brake_torque,
                                       p.max_handbrake_torque, p.suspension_stiffness, p.suspension_damping, p.wheelbase,
                                       p.track}),
                              {}, false, false));
}

}  // namespace

msg::VehiclePhysicsControl ToWire(const ground::VehiclePhysics& p) {
  msg::VehiclePhysicsControl m;
  for (auto [rpm, nm] : p.torque_curve) {
    msg::CurvePoint c;
    c.x(rpm);
    c.y(nm);
    m.torque_curve().push_back(c);
  }
  m.max_rpm(p.max_rpm);
  m.moi(p.moi);
  m.damping_rate_full_throttle(p.damping_rate_full_throttle);
  m.use_gear_autobox(p.use_gear_autobox);
  m.gear_switch_time(p.gear_switch_time);
  m.clutch_strength(p.clutch_strength);
  m.final_ratio(p.final_ratio);
  for (const auto& g : p.forward_gears) {
    msg::GearPhysicsControl w;
    w.ratio(g.ratio);
    w.down_ratio(g.down_ratio);
    w.up_ratio(g.up_ratio);
    m.forward_gears().push_back(w);
  }
  m.mass(p.mass);
  m.drag_coefficient(p.drag_coefficient);
  m.center_of_mass(FromVec(p.center_of_mass));
  m.tire_friction(p.tire_friction);
  m.wheel_radius(p.wheel_radius);
  m.max_steer_angle(p.max_steer_angle);
  m.max_brake_torque(p.max_brake_torque);
  m.max_handbrake_torque(p.max_handbrake_torque);
  m.suspension_stiffness(p.suspension_stiffness);
  m.suspension_damping(p.suspension_damping);
  m.wheelbase(p.wheelbase);
  m.track(p.track);
  return m;
}

ground::VehiclePhysics FromWire(const msg::VehiclePhysicsControl& m) {
  ground::VehiclePhysics p;
  for (const auto& c : m.torque_curve()) p.torque_curve.emplace_back(c.x(), c.y());
  p.max_rpm = m.max_rpm();
  p.moi = m.moi();
  p.damping_rate_full_throttle = m.damping_rate_full_throttle();
  p.use_gear_autobox = m.use_gear_autobox();
  p.gear_switch_time = m.gear_switch_time();
  p.clutch_strength = m.clutch_strength();
  p.final_ratio = m.final_ratio();
  for (const auto& g : m.forward_gears()) p.forward_gears.push_back(ground::GearSpec{g.ratio(), g.down_ratio(), g.up_ratio()});
  p.mass = m.mass();
  p.drag_coefficient = m.drag_coefficient();
  p.center_of_mass = ToVec(m.center_of_mass());
  p.tire_friction = m.tire_friction();
  p.wheel_radius = m.wheel_radius();
  p.max_steer_angle = m.max_steer_angle();
  p.max_brake_torque = m.max_brake_torque();
  p.max_handbrake_torque = m.max_handbrake_torque();
  p.suspension_stiffness = m.suspension_stiffness();
  p.suspension_damping = m.suspension_damping();
  p.wheelbase = m.wheelbase();
  p.track = m.track();
  return p;
}

msg::LaneMarking ToWire(const map::LaneMarking& m) {
  using T = map::RoadMarkType;
  using W = msg::LaneMarkingType;
  msg::LaneMarking out;
  switch (m.type) {
    case T::None: out.type(W::MARKING_NONE); break;
    case T::Solid: out.type(W::MARKING_SOLID); break;
    case T::Broken: out.type(W::MARKING_BROKEN); break;
    case T::SolidSolid: out.type(W::MARKING_SOLID_SOLID); break;
    case T::SolidBroken: out.type(W::MARKING_SOLID_BROKEN); break;
    case T::BrokenSolid: out.type(W::MARKING_BROKEN_SOLID); break;
    case T::BrokenBroken: out.type(W::MARKING_BROKEN_BROKEN); break;
    case T::BottsDots: out.type(W::MARKING_BOTTS_DOTS); break;
    case T::Grass: out.type(W::MARKING_GRASS); break;
    case T::Curb: out.type(W::MARKING_CURB); break;
    default: out.type(W::MARKING_OTHER); break;
  }
  const char* color = "white";
  switch (m.color) {
    case map::RoadMarkColor::Yellow: color = "yellow"; break;
    case map::RoadMarkColor::Blue: color = "blue"; break;
    case map::RoadMarkColor::Green: color = "green"; break;
    case map::RoadMarkColor::Red: color = "red"; break;
    case map::RoadMarkColor::Orange: color = "orange"; break;
    default: break;
  }
  out.color(color);
  out.width(static_cast<float>(m.width));
  out.lane_change_left(m.lane_change == map::LaneChange::Left || m.lane_change == map::LaneChange::Both);
  out.lane_change_right(m.lane_change == map::LaneChange::Right || m.lane_change == map::LaneChange::Both);
  return out;
}

msg::ObjectKind ToWire(ground::ObjectKind k) { return wire::ObjectKindToWire(k); }

msg::TrafficLightColor ToWire(ground::LightColor c) {
  switch (c) {
    case ground::LightColor::kRed: return msg::TrafficLightColor::LIGHT_RED;
    case ground::LightColor::kYellow: return msg::TrafficLightColor::LIGHT_YELLOW;
    case ground::LightColor::kGreen: return msg::TrafficLightColor::LIGHT_GREEN;
    case ground::LightColor::kOff: return msg::TrafficLightColor::LIGHT_OFF;
    case ground::LightColor::kUnknown: return msg::TrafficLightColor::LIGHT_UNKNOWN;
  }
  return msg::TrafficLightColor::LIGHT_UNKNOWN;
}

std::optional<ground::LightColor> FromWire(msg::TrafficLightColor c) {
  switch (c) {
    case msg::TrafficLightColor::LIGHT_RED: return ground::LightColor::kRed;
    case msg::TrafficLightColor::LIGHT_YELLOW: return ground::LightColor::kYellow;
    case msg::TrafficLightColor::LIGHT_GREEN: return ground::LightColor::kGreen;
    case msg::TrafficLightColor::LIGHT_OFF: return ground::LightColor::kOff;
    case msg::TrafficLightColor::LIGHT_UNKNOWN: return std::nullopt;  // unchanged
  }
  return std::nullopt;
}

std::optional<ground::TmParam> FromWire(msg::TrafficManagerParameter p) {
  using P = msg::TrafficManagerParameter;
  using G = ground::TmParam;
  switch (p) {
    case P::TM_DISTANCE_TO_LEADING_VEHICLE: return G::kDistanceToLeadingVehicle;
    case P::TM_PERCENTAGE_SPEED_DIFFERENCE: return G::kPercentageSpeedDifference;
    case P::TM_IGNORE_LIGHTS_PERCENTAGE: return G::kIgnoreLightsPercentage;
    case P::TM_IGNORE_SIGNS_PERCENTAGE: return G::kIgnoreSignsPercentage;
    case P::TM_IGNORE_VEHICLES_PERCENTAGE: return G::kIgnoreVehiclesPercentage;
    case P::TM_IGNORE_WALKERS_PERCENTAGE: return G::kIgnoreWalkersPercentage;
    case P::TM_AUTO_LANE_CHANGE: return G::kAutoLaneChange;
    case P::TM_HYBRID_PHYSICS_RADIUS: return G::kHybridPhysicsRadius;
    case P::TM_RANDOM_SEED: return G::kRandomSeed;
    case P::TM_DESIRED_SPEED: return G::kDesiredSpeed;
    case P::TM_KEEP_RIGHT_RULE_PERCENTAGE: return G::kKeepRightPercentage;
    case P::TM_RANDOM_LEFT_LANECHANGE_PERCENTAGE: return G::kRandomLeftLaneChangePercentage;
    case P::TM_RANDOM_RIGHT_LANECHANGE_PERCENTAGE: return G::kRandomRightLaneChangePercentage;
    case P::TM_HYBRID_PHYSICS_MODE: return G::kHybridPhysicsMode;
    case P::TM_SYNCHRONOUS_MODE: return G::kSynchronousMode;
    case P::TM_RESPAWN_DORMANT_VEHICLES: return G::kRespawnDormantVehicles;
    case P::TM_LANE_OFFSET: return G::kLaneOffset;
    default: return std::nullopt;  // autopilot, set_path, set_route, force_lane_change, collision_detection,
                                   // respawn boundaries, vehicle lights: own calls
  }
}

msg::VehicleState ToWire(const ground::VehicleView& v) {
  msg::VehicleState m;
  m.actor(v.id);
  m.blueprint(v.blueprint);
  m.transform(FromPose(v.pose));
  m.half_extents(FromVec(v.half_extents));
  m.velocity(FromVec(v.velocity));
  m.angular_velocity(FromVec(v.angular_velocity));
  m.acceleration(FromVec(v.acceleration));
  msg::VehicleControl c;
  c.actor(v.id);
  c.throttle(static_cast<float>(v.control.throttle));
  c.steer(static_cast<float>(v.control.steer));
  c.brake(static_cast<float>(v.control.brake));
  c.hand_brake(v.control.hand_brake);
  c.reverse(v.control.reverse);
  c.manual_gear_shift(v.control.manual_gear_shift);
  c.gear(v.gear);
  m.control(c);
  m.autopilot(v.autopilot);
  m.speed_limit(static_cast<float>(v.speed_limit));
  m.traffic_light(v.traffic_light);
  m.stop_line_distance(v.stop_line_distance);
  m.opposite_lane_fraction(v.opposite_lane);
  m.sidewalk_fraction(v.sidewalk);
  m.light_state(v.light_state);
  m.kinematic(v.kinematic);
  m.gear(v.gear);
  m.role_name(v.role_name);
  m.red_light_infractions(static_cast<uint32_t>(v.infractions.red_lights));
  const ground::Infractions& f = v.infractions;
  m.collision_infractions(static_cast<uint32_t>(f.vehicle_collisions + f.walker_collisions + f.static_collisions));
  m.stop_sign_infractions(static_cast<uint32_t>(f.stop_signs));
  m.lane_invasions(static_cast<uint32_t>(f.lane_invasions));
  m.vehicle_collisions(static_cast<uint32_t>(f.vehicle_collisions));
  m.walker_collisions(static_cast<uint32_t>(f.walker_collisions));
  m.other_collisions(static_cast<uint32_t>(f.static_collisions));
  m.opposite_lane_infractions(static_cast<uint32_t>(f.opposite_lane));
  m.offroad_infractions(static_cast<uint32_t>(f.offroad));
  m.offroad_fraction(v.offroad);
  m.distance_driven(f.distance);
  return m;
}

std::vector<msg::BlueprintDeclaration> Blueprints() {
  namespace bp = blueprint;
  std::vector<msg::BlueprintDeclaration> out;
  for (const auto& v : ground::VehicleCatalog()) {
    std::vector<msg::AttributeDeclaration> attrs = {
        bp::String("role_name", "autopilot", {"autopilot", "scenario", "ego_vehicle", "hero"}),
        bp::Bool("sticky_control", true),
        bp::Bool("terramechanics", false),
        bp::Int("number_of_wheels", v.wheels, v.wheels, v.wheels, false),
        bp::String("base_type", ground::ToString(v.base_type), {}, false, false),
        bp::Int("generation", v.generation, v.generation, v.generation, false),
        bp::String("object_type", "", {}, false, false),
        bp::String("special_type", v.special_type, {}, false, false),
        bp::Bool("has_dynamic_doors", false, false),
        bp::Bool("has_lights", v.has_lights, false),
        bp::Rgb("color", v.colors.front(), v.colors),
    };
    if (v.base_type == ground::BaseType::kBicycle || v.base_type == ground::BaseType::kMotorcycle) {
      attrs.push_back(bp::String("driver_id", "0", {"0", "1", "2"}));
    }
    DeclarePhysics(v.physics, &attrs);
    out.push_back(bp::Make(v.id, msg::ActorKind::ACTOR_VEHICLE, std::move(attrs), {}, v.half_extents.x(),
                           v.half_extents.y(), v.half_extents.z()));
  }
  for (const auto& w : ground::WalkerCatalog()) {
    char walk[32], run[32];
    std::snprintf(walk, sizeof walk, "%.2f", w.walk_speed);
    std::snprintf(run, sizeof run, "%.2f", w.run_speed);
    // CARLA's walker speed: a float whose recommended values are standing, walking and
    // running; the first is the default (0 = the AI controller's walking speed here).
    msg::AttributeDeclaration speed = bp::Float("speed", 0.0, 0.0, 10.0);
    speed.default_value("0.0");
    {
      std::remove_cvref_t<decltype(speed.recommended_values())> rec;
      for (const char* r : {"0.0", static_cast<const char*>(walk), static_cast<const char*>(run)}) rec.emplace_back(r);
      speed.recommended_values(rec);
    }
    std::vector<msg::AttributeDeclaration> attrs = {
        bp::String("role_name", "walker"),
        bp::Bool("is_invincible", true),
        speed,
        bp::String("gender", w.gender, {"male", "female"}, false, false),
        bp::String("age", w.age, {"adult", "child"}, false, false),
        bp::Int("generation", w.generation, w.generation, w.generation, false),
        bp::Bool("can_use_wheelchair", false, false),
        bp::Bool("use_wheelchair", false),
        bp::Float("height", w.height, w.height, w.height, false),
        bp::Float("width", 2 * w.radius, 2 * w.radius, 2 * w.radius, false),
    };
    out.push_back(bp::Make(w.id, msg::ActorKind::ACTOR_WALKER, std::move(attrs), {}, w.radius, w.radius, w.height / 2));
  }
  out.push_back(bp::Make(ground::kWalkerControllerBlueprint, msg::ActorKind::ACTOR_CONTROLLER,
                         {bp::String("role_name", "")}));
  return out;
}

}  // namespace lockstep::ground_wire
