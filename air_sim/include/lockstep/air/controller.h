// Flight controller: AirSim simple_flight style cascade
//   position -> velocity -> angle level -> angle rate -> mixer
// run at the physics rate. Usable alone (tests drive it against a model) or through Step().
#pragma once

#include <array>
#include <vector>

#include "lockstep/air/commands.h"
#include "lockstep/air/params.h"

namespace lockstep::air {

inline constexpr int kMaxRotors = 8;

// What the active command asks of the cascade at this instant (filled by the command layer).
struct ControlGoal {
  enum class Horizontal { kNone, kPosition, kVelocity, kAngle, kRate, kMotors };
  enum class Vertical { kNone, kPosition, kVelocity, kThrottle };
  Horizontal horizontal = Horizontal::kNone;  // kNone = motors off (idle)
  Vertical vertical = Vertical::kNone;
  Vec3 position = Vec3::Zero();      // m, world ENU (kPosition)
  Vec3 velocity = Vec3::Zero();      // m/s, world ENU: goal (kVelocity) or feed-forward (kPosition)
  Vec3 accel = Vec3::Zero();         // m/s^2, world ENU feed-forward
  double closing_gain_xy = 0;        // 1/s; > 0 replaces position_p_xy with a sqrt-limited gain
  double closing_gain_z = 0;         // 1/s; > 0 replaces position_p_z likewise
  double max_speed = 0;              // m/s, clamp of the speed goal; 0 = gains.max_velocity
  double roll = 0, pitch = 0;        // rad (kAngle)
  Vec3 rates = Vec3::Zero();         // rad/s body FLU (kRate)
  double throttle = 0;               // 1 (kThrottle)
  bool yaw_is_rate = true;           // yaw: rate (rad/s) integrated into a heading, or a heading
  double yaw = 0;                    // rad heading or rad/s rate
  std::array<double, kMaxRotors> motors{};  // 1 (kMotors)
};

// Mutable controller memory (part of the drone state).
struct ControllerState {
  ControllerGains gains;            // current gains (start as params.gains; SetGains replaces)
  double yaw_ref = 0;               // rad, heading being held / tracked
  double vz_integral = 0;           // throttle units
  Vec3 vxy_integral = Vec3::Zero(); // rad (x, y world)
  Vec3 rate_integral = Vec3::Zero();// normalised torque
  Vec3 prev_rate_error = Vec3::Zero();
  bool has_prev_rate_error = false;
  // Last outputs (for inspection and tests).
  double roll_goal = 0, pitch_goal = 0;  // rad
  Vec3 velocity_goal = Vec3::Zero();     // m/s, world ENU
  Vec3 rate_goal = Vec3::Zero();         // rad/s body FLU
  Vec3 torque_out = Vec3::Zero();        // normalised [-1, 1]
  double throttle_out = 0;               // 1
};

struct KinematicsView {
  Vec3 position;          // m, world ENU
  Quat orientation;       // FLU -> ENU
  Vec3 velocity;          // m/s, world ENU
  Vec3 angular_velocity;  // rad/s, body FLU
  bool grounded = false;  // ground-locked: tilt goals are held level until lift-off
};

// One controller update: goal + measured kinematics -> rotor control signals in [0, 1].
// density_ratio = air density / 1.225 (scales the hover throttle feed-forward).
void ControllerUpdate(const MultirotorParams& params, const DerivedParams& derived,
                      const ControlGoal& goal, const KinematicsView& k, double gravity,
                      double density_ratio, double h, ControllerState* state,
                      std::array<double, kMaxRotors>* motors);

// Mixer alone (gain_model physical): throttle + normalised torques -> motor signals with yaw
// authority limited so thrust and roll/pitch are kept (exposed for tests).
void Mix(const DerivedParams& derived, double throttle, const Vec3& torque,
         std::array<double, kMaxRotors>* motors);
// simple_flight's mixer (gain_model airsim): below min_angling_throttle (0.05) every motor gets
// the throttle; else throttle + torques, shifted up when a motor is below 0, scaled down when
// one is above 1.
inline constexpr double kMinAnglingThrottle = 0.05;
void MixAirSim(const DerivedParams& derived, double throttle, const Vec3& torque,
               std::array<double, kMaxRotors>* motors);

}  // namespace lockstep::air
