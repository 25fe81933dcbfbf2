// Multirotor parameters: plain structs with in-class defaults (AirSim generic quad), one
// visitor (VisitParams) that names every field, a YAML loader and a blueprint-attribute
// loader built on that visitor. Bad input throws std::invalid_argument naming the key.
#pragma once

#include <map>
#include <string>
#include <type_traits>
#include <vector>

#include "lockstep/air/types.h"

namespace lockstep::air {

enum class FrameType { kQuadX, kQuadPlus, kHexaX };
const char* ToString(FrameType f);

// Model choices: AirSim's by default, Lockstep's earlier models as options (docs/air.md).
enum class DragModel {
  kAirSim,  // "airsim": six body faces with the rotors folded in (pi D^2 top/bottom, pi D h
            // sides per rotor), faces at +-body_box, combined face velocity v + w x r, one
            // coefficient (linear_drag_coefficient), no drag below 0.1 m/s face speed
  kFaces    // "faces": bare body faces at +-body_box/2 plus rotor discs (pi D^2 / 4), linear
            // and rotational parts squared separately with their own coefficients
};
enum class GainModel {
  kAirSim,   // "airsim": simple_flight's PIDs: each output clipped to [-1, 1] and scaled by the
             // child loop's limit; throttle (1 + u) / 2; no hover feed-forward
  kPhysical  // "physical": the gains are physical (1/s, rad per m/s, throttle per m/s) with a
             // hover-throttle feed-forward
};
enum class LandingModel {
  kGroundLock,  // "ground_lock": AirSim: a level, descending touchdown locks to the ground
                // (no bounce, levelled, zero velocity) until thrust exceeds weight
  kImpulse      // "impulse": contacts only (restitution above restitution_threshold)
};
const char* ToString(DragModel m);
const char* ToString(GainModel m);
const char* ToString(LandingModel m);

// One propeller + motor (AirSim RotorParams).
struct RotorParams {
  double thrust_coefficient = 0.109919;  // C_T, 1: T = C_T rho n^2 D^4 (n in rev/s)
  double power_coefficient = 0.040164;   // C_P, 1: Q = C_P rho n^2 D^5 / (2 pi)
  double max_rpm = 6396.667;             // rev/min at control signal 1
  double propeller_diameter = 0.2286;    // D, m
  double propeller_height = 0.01;        // m, disc thickness (side drag area pi D h)
  double time_constant = 0.005;          // s, first-order lag of the control signal
};

// Cascaded flight-controller gains (AirSim simple_flight defaults). Settable at run time.
struct ControllerGains {
  Vec3 angle_rate_p{0.25, 0.25, 0.25};   // 1 per rad/s: normalised torque per rate error (x,y,z body)
  Vec3 angle_rate_i{0, 0, 0};            // 1 per rad
  Vec3 angle_rate_d{0, 0, 0};            // 1 per rad/s^2
  double max_angle_rate = 2.5;           // rad/s, clamp of the rate goal from the angle loop
  Vec3 angle_level_p{2.5, 2.5, 2.5};     // 1/s: rate goal per angle error (roll, pitch, yaw)
  double max_tilt = 3.14159265358979323846 / 5.5;  // rad, clamp of roll and pitch goals
  double velocity_p_xy = 0.2;            // rad per m/s: tilt per horizontal speed error
  double velocity_i_xy = 0.0;            // rad per m
  double velocity_p_z = 2.0;             // throttle per m/s
  double velocity_i_z = 2.0;             // throttle per m
  double max_velocity = 6.0;             // m/s, clamp of horizontal and vertical speed goals
  double min_throttle = 0.3;             // 1, floor of the altitude loop's throttle while flying
  double position_p_xy = 0.25;           // 1/s: speed goal per position error
  double position_p_z = 0.25;            // 1/s
  double integrator_limit = 0.5;         // throttle units, clamp of the z integrator term
  double altitude_gain = 1.0;            // 1/s, z closing gain of commands with an absolute z
                                         // (velocity-z, rpy-z, rates-z); sqrt-limited by path_accel
};

// Sphere used for contact, in body FLU coordinates.
struct ContactSphere {
  Vec3 center = Vec3::Zero();  // m, body FLU
  double radius = 0.06;        // m
};

struct MultirotorParams {
  FrameType frame = FrameType::kQuadX;
  double mass = 1.0;                      // kg, total (body box + motors)
  double arm_length = 0.2275;             // m, centre to rotor hub
  double motor_mass = 0.055;              // kg per motor (point mass at the hub)
  Vec3 body_box{0.18, 0.11, 0.04};        // m, full extents of the central box (x, y, z FLU)
  double rotor_z = -0.025;                // m, hub height above the centre of mass (body FLU z);
                                          // AirSim generic quad: +2.5 cm in FRD = 2.5 cm below
  RotorParams rotor;
  DragModel drag_model = DragModel::kAirSim;
  GainModel gain_model = GainModel::kAirSim;
  LandingModel landing_model = LandingModel::kGroundLock;
  double linear_drag_coefficient = 1.3 / 4;   // 1, C_d of the drag faces (AirSim: the only one)
  double angular_drag_coefficient = 1.3 / 4;  // 1, drag_model faces only: C_d for w x r
  double restitution = 0.55;              // 1, contact restitution
  double friction = 0.5;                  // 1, Coulomb friction coefficient
  double contact_radius = 0.06;           // m, radius of the default contact spheres
  std::vector<ContactSphere> contact_spheres;  // empty = one at the centre and one per rotor hub
  ControllerGains gains;
  double takeoff_height = 2.0;            // m above the take-off point (AirSim: z = -2 NED)
  double takeoff_speed = 0.5;             // m/s (AirSim takeoff: moveToPosition at 0.5 m/s)
  double landing_speed = 0.2;             // m/s (AirSim landing_vel_)
  double path_accel = 2.0;                // m/s^2, accel/decel of move commands' reference
  double arrival_tolerance = 0.2;         // m, distance at which a move command completes
  double turbulence_scale = 1.0;          // 1, multiplies Environment::turbulence_sigma
};

// Derived quantities of a validated MultirotorParams (computed once per drone in the model).
struct RotorGeometry {
  Vec3 position = Vec3::Zero();  // m, hub in body FLU
  double spin = 1.0;             // +1 counter-clockwise seen from above (reaction torque -z), -1 CW
  double mix_roll = 0, mix_pitch = 0, mix_yaw = 0;  // mixer coefficients
};

struct DragFace {
  Vec3 position = Vec3::Zero();  // m, centre of the face, body FLU
  Vec3 normal = Vec3::UnitZ();   // outward unit normal, body FLU
  double area = 0;               // m^2
};

struct DerivedParams {
  std::vector<RotorGeometry> rotors;
  std::vector<DragFace> faces;
  std::vector<ContactSphere> spheres;
  Mat3 inertia = Mat3::Identity();      // kg m^2, body FLU about the centre of mass
  Mat3 inertia_inv = Mat3::Identity();  // 1/(kg m^2)
  double max_thrust_per_rotor = 0;      // N at sea-level density 1.225 and control 1
  double max_torque_per_rotor = 0;      // N m at density 1.225 and control 1
  double max_rev_per_s = 0;             // rev/s
  double hover_throttle = 0;            // 1, m g / (rotors * max thrust) at density 1.225
  double bounding_radius = 0;           // m, sphere around all contact spheres (body origin)
};

int RotorCount(FrameType f);
// Empty string when valid, else the first problem ("mass: must be > total motor mass ...").
std::string ValidateParams(const MultirotorParams& p);
// Throws std::invalid_argument when ValidateParams fails.
DerivedParams DeriveParams(const MultirotorParams& p);
// Height of the centre of mass above a flat surface the drone rests on level (m): spawn a
// drone at ground_height + RestHeight to start at rest.
double RestHeight(const DerivedParams& d);

// Visitor over every field with its dotted key ("rotor.max_rpm", "gains.velocity_p_xy").
// Visitor callables: v(key, double&), v(key, Vec3&), v(key, FrameType&), v(key, DragModel&),
// v(key, GainModel&), v(key, LandingModel&).
template <class V>
void VisitParams(MultirotorParams& p, V&& v) {
  v("frame", p.frame);
  v("mass", p.mass);
  v("arm_length", p.arm_length);
  v("motor_mass", p.motor_mass);
  v("body_box", p.body_box);
  v("rotor_z", p.rotor_z);
  // Model choices: visited only by visitors that take them (older visitors skip them).
  if constexpr (std::is_invocable_v<V, const char*, DragModel&>) v("drag_model", p.drag_model);
  if constexpr (std::is_invocable_v<V, const char*, GainModel&>) v("gain_model", p.gain_model);
  if constexpr (std::is_invocable_v<V, const char*, LandingModel&>) v("landing_model", p.landing_model);
  v("rotor.thrust_coefficient", p.rotor.thrust_coefficient);
  v("rotor.power_coefficient", p.rotor.power_coefficient);
  v("rotor.max_rpm", p.rotor.max_rpm);
  v("rotor.propeller_diameter", p.rotor.propeller_diameter);
  v("rotor.propeller_height", p.rotor.propeller_height);
  v("rotor.time_constant", p.rotor.time_constant);
  v("linear_drag_coefficient", p.linear_drag_coefficient);
  v("angular_drag_coefficient", p.angular_drag_coefficient);
  v("restitution", p.restitution);
  v("friction", p.friction);
  v("contact_radius", p.contact_radius);
  v("gains.angle_rate_p", p.gains.angle_rate_p);
  v("gains.angle_rate_i", p.gains.angle_rate_i);
  v("gains.angle_rate_d", p.gains.angle_rate_d);
  v("gains.max_angle_rate", p.gains.max_angle_rate);
  v("gains.angle_level_p", p.gains.angle_level_p);
  v("gains.max_tilt", p.gains.max_tilt);
  v("gains.velocity_p_xy", p.gains.velocity_p_xy);
  v("gains.velocity_i_xy", p.gains.velocity_i_xy);
  v("gains.velocity_p_z", p.gains.velocity_p_z);
  v("gains.velocity_i_z", p.gains.velocity_i_z);
  v("gains.max_velocity", p.gains.max_velocity);
  v("gains.min_throttle", p.gains.min_throttle);
  v("gains.position_p_xy", p.gains.position_p_xy);
  v("gains.position_p_z", p.gains.position_p_z);
  v("gains.integrator_limit", p.gains.integrator_limit);
  v("gains.altitude_gain", p.gains.altitude_gain);
  v("takeoff_height", p.takeoff_height);
  v("takeoff_speed", p.takeoff_speed);
  v("landing_speed", p.landing_speed);
  v("path_accel", p.path_accel);
  v("arrival_tolerance", p.arrival_tolerance);
  v("turbulence_scale", p.turbulence_scale);
}

// YAML: a mapping with the keys above, nested ("rotor: {max_rpm: 6000}") or dotted; vectors as
// [x, y, z]; "contact_spheres: [{center: [x,y,z], radius: r}, ...]". Errors name the key and
// its 1-based line: "line 3: unknown key 'masss'". Starts from `base` (defaults by default).
MultirotorParams LoadParamsYaml(const std::string& yaml_text, const MultirotorParams& base = {});
MultirotorParams LoadParamsYamlFile(const std::string& path, const MultirotorParams& base = {});

// Blueprint attributes: flat dotted keys -> strings ("mass" -> "1.2", "frame" -> "hexa_x",
// "body_box" -> "0.18,0.11,0.04", "gains.velocity_p_xy" -> "0.3"). Unknown keys and bad values
// throw std::invalid_argument naming the key and the value.
MultirotorParams ParamsFromAttributes(const std::map<std::string, std::string>& attributes,
                                      const MultirotorParams& base = {});
// The attribute keys ParamsFromAttributes accepts (for blueprint listings).
std::vector<std::string> ParamKeys();

}  // namespace lockstep::air
