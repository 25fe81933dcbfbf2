// Drone commands (the AirSim multirotor API, in Lockstep's frames: world ENU metres, body FLU,
// radians, seconds). A Command is {id, drone, body}; body is one of the structs below.
// Long commands report RUNNING, then COMPLETED / TIMED_OUT / CANCELLED; a new motion command
// cancels the drone's running one. See docs/air.md for every command's semantics.
#pragma once

#include <limits>
#include <string>
#include <variant>
#include <vector>

#include "lockstep/air/params.h"
#include "lockstep/air/types.h"

namespace lockstep::air {

inline constexpr double kForever = 1e9;  // s, "no timeout"

struct YawMode {
  bool is_rate = true;     // true: yaw_or_rate is a yaw rate (rad/s, CCW positive, about world up)
  double yaw_or_rate = 0;  // false: an ENU heading (rad, 0 east, CCW); ForwardOnly: an offset
};                         // from the direction of travel

enum class Drivetrain { kMaxDegreeOfFreedom, kForwardOnly };
enum class VelocityFrame {
  kWorld,  // ENU
  kBody    // heading frame at command start: x forward, y left (horizontal), z up
};

namespace cmd {
struct Arm {};
struct Disarm {};  // motors stop at once, also in flight
struct Takeoff {               // AirSim: rejected while moving faster than 0.05 m/s; climbs at
  double height = 0;          // takeoff_speed (0.5 m/s) to height m above the current position;
  double timeout = 20;        // 0 = params.takeoff_height (2 m). timeout in s
};
struct Land {                 // descends at landing_speed (0.2 m/s); completes once LANDED with a
  double timeout = 60;        // vertical speed <= 0.05 m/s for 0.22 s, then motors idle (0)
};
struct Hover {};              // hold the current position and heading; completes at once
struct GoHome {               // AirSim: to the spawn point itself, at 0.5 m/s
  double velocity = 0.5;      // m/s (Lockstep option; AirSim has no velocity argument)
  double timeout = kForever;  // s
};
struct MoveToPosition {
  Vec3 position = Vec3::Zero();  // m, world ENU
  double velocity = 5;           // m/s, cruise speed along the straight line
  double timeout = kForever;     // s
  Drivetrain drivetrain = Drivetrain::kMaxDegreeOfFreedom;
  YawMode yaw_mode{};
  double lookahead = -1;         // m, max lead of the reference over the drone; -1 = auto
  double adaptive_lookahead = 1; // 1, adds adaptive_lookahead x cross-track error to it; 0 = off
};
struct MoveOnPath {
  std::vector<Vec3> path{};      // m, world ENU waypoints (the current position is prepended)
  double velocity = 5;           // m/s
  double timeout = kForever;     // s
  Drivetrain drivetrain = Drivetrain::kMaxDegreeOfFreedom;
  YawMode yaw_mode{};
  double lookahead = -1;         // m; -1 = auto
  double adaptive_lookahead = 1; // 1
};
struct MoveToZ {                 // AirSim moveToZ: to altitude z above the current x, y
  double z = 0;                  // m, world ENU
  double velocity = 5;           // m/s
  double timeout = kForever;     // s
  YawMode yaw_mode{};
  double lookahead = -1;         // m; -1 = auto
  double adaptive_lookahead = 1; // 1
};
// Lockstep extension: follow a moving target given by its position at the start of this tick
// and its velocity (feed-forward); the target is extrapolated at every physics sub-step.
// Re-send it every tick with the latest target state. Completes after `duration`.
struct TrackTarget {
  Vec3 position = Vec3::Zero();  // m, world ENU, target at the tick start
  Vec3 velocity = Vec3::Zero();  // m/s, world ENU
  double max_speed = 0;          // m/s, clamp of the speed goal; 0 = gains.max_velocity
  double gain = 1.0;             // 1/s, closing speed per metre of error (sqrt-limited by path_accel)
  double duration = 1.0;         // s
  YawMode yaw_mode{};
};
struct MoveByVelocity {
  Vec3 velocity = Vec3::Zero();  // m/s, in `frame`
  double duration = 1;           // s; afterwards the drone hovers where it is
  VelocityFrame frame = VelocityFrame::kWorld;
  Drivetrain drivetrain = Drivetrain::kMaxDegreeOfFreedom;
  YawMode yaw_mode{};
};
struct MoveByVelocityZ {
  double vx = 0, vy = 0;         // m/s, horizontal, in `frame`
  double z = 0;                  // m, world ENU altitude to hold
  double duration = 1;           // s
  VelocityFrame frame = VelocityFrame::kWorld;
  Drivetrain drivetrain = Drivetrain::kMaxDegreeOfFreedom;
  YawMode yaw_mode{};
};
struct MoveByRollPitchYawThrottle {
  double roll = 0, pitch = 0;    // rad, FLU (pitch > 0 nose down); |.| <= gains.max_tilt
  double yaw = 0;                // rad, ENU heading
  double throttle = 0;           // 1, [0, 1]
  double duration = 1;           // s
};
struct MoveByRollPitchYawZ {
  double roll = 0, pitch = 0, yaw = 0;  // rad
  double z = 0;                  // m, world ENU altitude
  double duration = 1;           // s
};
struct MoveByRollPitchYawrateThrottle {
  double roll = 0, pitch = 0;    // rad
  double yaw_rate = 0;           // rad/s about world up
  double throttle = 0;           // 1
  double duration = 1;           // s
};
struct MoveByRollPitchYawrateZ {
  double roll = 0, pitch = 0;    // rad
  double yaw_rate = 0;           // rad/s about world up
  double z = 0;                  // m, world ENU altitude
  double duration = 1;           // s
};
struct MoveByAngleRatesThrottle {
  Vec3 rates = Vec3::Zero();     // rad/s, body FLU (roll, pitch, yaw rates)
  double throttle = 0;           // 1
  double duration = 1;           // s
};
struct MoveByAngleRatesZ {
  Vec3 rates = Vec3::Zero();     // rad/s, body FLU
  double z = 0;                  // m, world ENU altitude
  double duration = 1;           // s
};
struct MoveByMotorPwms {
  std::vector<double> pwm{};     // 1, [0, 1] per rotor, in rotor order (one per rotor)
  double duration = 1;           // s
};
struct RotateToYaw {
  double yaw = 0;                // rad, ENU heading
  double timeout = kForever;     // s
  double margin = 0.0872664626;  // rad (5 deg): completes when |error| <= margin and the yaw
};                               // rate is at most 0.01 rad/s (AirSim)
struct RotateByYawRate {
  double yaw_rate = 0;           // rad/s, CCW positive
  double duration = 1;           // s
};
struct SetGains {
  ControllerGains gains{};       // replaces the drone's gains from the next sub-step
};
struct SetPose {                 // teleport (simSetVehiclePose): zero velocity, motors kept
  Pose pose{};                   // world ENU
};
struct SetKinematics {           // simSetKinematics: pose and velocities at once
  Pose pose{};                   // world ENU
  Vec3 velocity = Vec3::Zero();          // m/s, world ENU
  Vec3 angular_velocity = Vec3::Zero();  // rad/s, body FLU
};
// AirSim's enableApiControl: the vehicle's, whoever asks. Without API control a motion
// command is accepted but does not steer the drone (simple_flight refuses its goal): it runs
// its duration (COMPLETED) or its timeout (TIMED_OUT), as AirSim's call waits them out; arm
// and disarm are rejected. Releasing control in flight leaves the drone to simple_flight's
// goal without an RC: zero throttle (it falls), its running command unsteered.
struct SetApiControl {
  bool enable = true;
};
}  // namespace cmd

using CommandBody =
    std::variant<cmd::Arm, cmd::Disarm, cmd::Takeoff, cmd::Land, cmd::Hover, cmd::GoHome,
                 cmd::MoveToPosition, cmd::MoveOnPath, cmd::TrackTarget, cmd::MoveByVelocity,
                 cmd::MoveByVelocityZ, cmd::MoveByRollPitchYawThrottle, cmd::MoveByRollPitchYawZ,
                 cmd::MoveByRollPitchYawrateThrottle, cmd::MoveByAngleRatesThrottle,
                 cmd::MoveByAngleRatesZ, cmd::MoveByMotorPwms, cmd::RotateToYaw,
                 cmd::RotateByYawRate, cmd::SetGains, cmd::SetPose, cmd::MoveToZ,
                 cmd::MoveByRollPitchYawrateZ, cmd::SetKinematics, cmd::SetApiControl>;

struct Command {
  CommandId id = 0;   // chosen by the caller (the coordinator); echoed in reports
  DroneId drone = 0;
  CommandBody body;
};
using Commands = std::vector<Command>;

enum class CommandStatus : std::uint8_t {
  kRunning,    // accepted, in progress
  kCompleted,  // reached its goal / ran its duration / immediate command applied
  kTimedOut,   // timeout elapsed before the goal
  kCancelled,  // replaced by a newer motion command, disarmed, or the drone was reset
  kRejected    // failed validation; never ran (message says why)
};
const char* ToString(CommandStatus s);

// One status change of a command (emitted by Step, in order).
struct CommandReport {
  CommandId id = 0;
  DroneId drone = 0;
  CommandStatus status = CommandStatus::kRunning;
  double time = 0;          // s, sim time of the change
  std::uint64_t frame = 0;  // tick index during which it happened
  std::string message;      // reason for kRejected / kCancelled / kTimedOut
};

// Name of the command kind ("move_to_position").
const char* CommandName(const CommandBody& body);
// Immediate commands (arm, disarm, hover, set_gains, set_pose) complete at once; motion
// commands replace the running one.
bool IsMotionCommand(const CommandBody& body);

}  // namespace lockstep::air
