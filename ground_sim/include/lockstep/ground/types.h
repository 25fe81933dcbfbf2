#pragma once
// Plain types of the ground simulation core: poses, controls, physics parameters.
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace lockstep::ground {

using Vec3 = Eigen::Vector3d;
using Quat = Eigen::Quaterniond;

// World ENU (x east, y north, z up), metres; body x forward, y left, z up.
struct Pose {
  Vec3 position = Vec3::Zero();
  Quat orientation = Quat::Identity();
  double Yaw() const;
  static Pose FromYaw(const Vec3& p, double yaw);
};

// CARLA's carla.VehicleControl.
struct VehicleControl {
  double throttle = 0;        // 0..1
  double steer = 0;           // -1 (left) .. 1 (right), CARLA's sign
  double brake = 0;           // 0..1
  bool hand_brake = false;
  bool reverse = false;
  bool manual_gear_shift = false;
  int gear = 0;               // used with manual_gear_shift; -1 reverse, 0 neutral
};

// CARLA's carla.VehicleAckermannControl: the vehicle's own controller tracks these.
struct AckermannControl {
  double steer = 0;           // rad, front wheel (bicycle) angle, positive = left (ENU)
  double steer_speed = 0;     // rad/s, 0 = instant
  double speed = 0;           // m/s, negative = reverse
  double acceleration = 0;    // m/s^2, magnitude limit, 0 = the vehicle's maximum
  double jerk = 0;            // m/s^3, accepted and ignored (documented)
};

// CARLA's carla.WalkerControl.
struct WalkerControl {
  Vec3 direction = Vec3::UnitX();  // world ENU, normalised on use
  double speed = 0;                // m/s
  bool jump = false;
};

struct GearSpec {
  double ratio = 1;
  double down_ratio = 0.5;  // share of max rpm below which it shifts down
  double up_ratio = 0.65;   // share of max rpm above which it shifts up
};

// CARLA's carla.VehiclePhysicsControl (with the wheel values folded in: all wheels alike).
struct VehiclePhysics {
  std::vector<std::pair<double, double>> torque_curve;  // (rpm, N m), rpm ascending
  double max_rpm = 5000;
  double moi = 1.0;                      // kg m^2, engine (kept for CARLA parity; folded into mass)
  double damping_rate_full_throttle = 0.15;
  bool use_gear_autobox = true;
  double gear_switch_time = 0.5;         // s
  double clutch_strength = 10;
  double final_ratio = 4.0;
  std::vector<GearSpec> forward_gears;
  double mass = 1500;                    // kg
  double drag_coefficient = 0.3;
  Vec3 center_of_mass = Vec3(0, 0, -0.2);  // m, body frame, from the bounding-box centre
  double frontal_area = 2.2;             // m^2
  // Wheels (all four alike; front wheels steer).
  double tire_friction = 1.0;            // Coulomb coefficient on dry asphalt
  double wheel_radius = 0.35;            // m
  double max_steer_angle = 0.61;         // rad, front wheels at full lock
  double max_brake_torque = 1500;        // N m per wheel
  double max_handbrake_torque = 3000;    // N m per rear wheel
  double suspension_stiffness = 50000;   // N/m per wheel
  double suspension_damping = 3500;      // N s/m per wheel
  double suspension_travel = 0.3;        // m, rest length of the ray below the mount
  double wheelbase = 2.8;                // m
  double track = 1.6;                    // m
  double ground_clearance = 0.25;        // m, chassis collision box starts this high
};

enum class BaseType { kCar, kTruck, kVan, kBus, kMotorcycle, kBicycle };
const char* ToString(BaseType t);

// Kind of object a contact is with (msg::ObjectKind on the wire).
enum class ObjectKind { kNone, kGround, kStatic, kVehicle, kWalker, kDrone };

}  // namespace lockstep::ground
