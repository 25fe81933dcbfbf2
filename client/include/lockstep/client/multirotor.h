#pragma once
// A drone client shaped like AirSim's MultirotorClient, over a Client. Coordinates are
// AirSim's: NED metres from the drone's spawn point (DroneState.home_pose), body FRD,
// yaw angles and rates in degrees where AirSim uses degrees (YawMode, rotateToYaw),
// radians where it uses radians (moveByRollPitchYaw*). Every *Async call returns a
// CommandFuture that completes when air_sim reports the command finished in
// DroneState.command_status.
#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include "lockstep/client/client.h"

namespace lockstep::client {

struct Ned {
  double x = 0, y = 0, z = 0;  // m north, east, down (or m/s, m/s^2 for rates)
};

struct NedQuaternion {
  double w = 1, x = 0, y = 0, z = 0;  // body FRD to world NED
};

struct NedYawMode {
  bool is_rate = true;        // AirSim's default: rate 0, keep the heading
  double yaw_or_rate = 0;     // deg (heading, 0 = north, clockwise) or deg/s
};

enum class NedDrivetrain { kMaxDegreeOfFreedom = 0, kForwardOnly = 1 };  // AirSim's values

struct NedKinematics {
  Ned position, linear_velocity, linear_acceleration;  // world NED from home
  NedQuaternion orientation;
  Ned angular_velocity, angular_acceleration;          // rad/s, rad/s^2, body FRD
};

struct NedCollision {
  bool has_collided = false;
  Ned normal, impact_point, position;
  double penetration_depth = 0;
  uint32_t object_id = 0;
  std::string object_name;
  uint64_t frame = 0;
};

struct MultirotorStateNed {
  NedKinematics kinematics;
  NedCollision collision;
  bool landed = true;      // AirSim LandedState.Landed
  bool armed = false;
  double timestamp_ns = 0; // sim time, ns
  uint64_t frame = 0;
  std::vector<double> rotor_speeds;  // rad/s
  std::vector<double> rotor_thrusts; // N
  std::vector<double> rotor_controls; // 0..1
};

// ENU <-> NED helpers (world ENU position minus home; quaternions FLU<->FRD).
Ned EnuToNed(const msg::Vector3& enu, const msg::Vector3& home);
msg::Vector3 NedToEnu(const Ned& ned, const msg::Vector3& home);
NedQuaternion EnuToNedQuaternion(const msg::Quaternion& q);
msg::Quaternion NedToEnuQuaternion(const NedQuaternion& q);
// AirSim heading (deg from north, clockwise) <-> ENU heading (rad from east, counter-clockwise).
double NedYawDegToEnu(double deg);
double EnuYawToNedDeg(double rad);

class CommandFuture {
 public:
  CommandFuture() = default;
  CommandFuture(Client* client, uint32_t actor, uint64_t id) : client_(client), actor_(actor), id_(id) {}
  // Waits until air_sim reports the command finished (ticking in synchronous mode);
  // returns true when it completed, false when it timed out or was cancelled; throws
  // CommandRejected with air_sim's reason when it was rejected (AirSim raises too).
  bool join(double timeout_s = -1);
  msg::DroneCommandStatus status(double timeout_s = -1);
  uint64_t command_id() const { return id_; }
  uint32_t actor() const { return actor_; }

 private:
  Client* client_ = nullptr;
  uint32_t actor_ = 0;
  uint64_t id_ = 0;
  std::optional<msg::DroneCommandStatus> done_;
};

class MultirotorClient {
 public:
  explicit MultirotorClient(Client& client) : client_(client) {}

  // The drone named `vehicle_name` (its role_name, or "Drone<id>"); "" = the first drone
  // of the run. Throws ClientError if there is none.
  uint32_t Resolve(const std::string& vehicle_name) const;
  std::vector<std::string> listVehicles() const;
  // Spawns a drone (AirSim simAddVehicle): pose in world ENU, role_name = name.
  uint32_t addVehicle(const std::string& name, const std::string& blueprint, const msg::Pose& pose);

  void enableApiControl(bool enabled, const std::string& vehicle = "");
  bool isApiControlEnabled(const std::string& vehicle = "") const;
  bool armDisarm(bool arm, const std::string& vehicle = "");

  CommandFuture takeoffAsync(double timeout_s = 20, const std::string& vehicle = "");
  CommandFuture landAsync(double timeout_s = 60, const std::string& vehicle = "");
  CommandFuture goHomeAsync(double timeout_s = 3e38, const std::string& vehicle = "");
  CommandFuture hoverAsync(const std::string& vehicle = "");
  CommandFuture moveToPositionAsync(double x, double y, double z, double velocity, double timeout_s = 3e38,
                                    NedDrivetrain drivetrain = NedDrivetrain::kMaxDegreeOfFreedom, NedYawMode yaw = {},
                                    double lookahead = -1, const std::string& vehicle = "");
  CommandFuture moveToZAsync(double z, double velocity, double timeout_s = 3e38, NedYawMode yaw = {}, double lookahead = -1,
                             const std::string& vehicle = "");
  CommandFuture moveOnPathAsync(const std::vector<Ned>& path, double velocity, double timeout_s = 3e38,
                                NedDrivetrain drivetrain = NedDrivetrain::kMaxDegreeOfFreedom, NedYawMode yaw = {},
                                double lookahead = -1, const std::string& vehicle = "");
  CommandFuture moveByVelocityAsync(double vx, double vy, double vz, double duration,
                                    NedDrivetrain drivetrain = NedDrivetrain::kMaxDegreeOfFreedom, NedYawMode yaw = {},
                                    const std::string& vehicle = "");
  CommandFuture moveByVelocityBodyFrameAsync(double vx, double vy, double vz, double duration,
                                             NedDrivetrain drivetrain = NedDrivetrain::kMaxDegreeOfFreedom,
                                             NedYawMode yaw = {}, const std::string& vehicle = "");
  CommandFuture moveByVelocityZAsync(double vx, double vy, double z, double duration,
                                     NedDrivetrain drivetrain = NedDrivetrain::kMaxDegreeOfFreedom, NedYawMode yaw = {},
                                     const std::string& vehicle = "");
  CommandFuture rotateToYawAsync(double yaw_deg, double timeout_s = 3e38, double margin_deg = 5,
                                 const std::string& vehicle = "");
  CommandFuture rotateByYawRateAsync(double yaw_rate_deg, double duration, const std::string& vehicle = "");
  CommandFuture moveByRollPitchYawThrottleAsync(double roll, double pitch, double yaw, double throttle, double duration,
                                                const std::string& vehicle = "");
  CommandFuture moveByRollPitchYawZAsync(double roll, double pitch, double yaw, double z, double duration,
                                         const std::string& vehicle = "");
  CommandFuture moveByAngleRatesThrottleAsync(double roll_rate, double pitch_rate, double yaw_rate, double throttle,
                                              double duration, const std::string& vehicle = "");
  CommandFuture moveByMotorPWMsAsync(const std::vector<double>& pwms, double duration, const std::string& vehicle = "");
  CommandFuture moveByRollPitchYawrateThrottleAsync(double roll, double pitch, double yaw_rate, double throttle,
                                                    double duration, const std::string& vehicle = "");
  CommandFuture moveByRollPitchYawrateZAsync(double roll, double pitch, double yaw_rate, double z, double duration,
                                             const std::string& vehicle = "");
  CommandFuture moveByAngleRatesZAsync(double roll_rate, double pitch_rate, double yaw_rate, double z, double duration,
                                       const std::string& vehicle = "");
  // Geodetic goal (deg, deg, m) through the map's geo-reference (OpenDRIVE's, as CARLA's GNSS).
  CommandFuture moveToGPSAsync(double latitude, double longitude, double altitude, double velocity, double timeout_s = 3e38,
                               NedDrivetrain drivetrain = NedDrivetrain::kMaxDegreeOfFreedom, NedYawMode yaw = {},
                               double lookahead = -1, double adaptive_lookahead = 1, const std::string& vehicle = "");
  // AirSim's controller gains: one PID per axis, roll/pitch/yaw (angle loops) or x/y/z
  // (velocity and position loops, NED; air_sim has one horizontal gain: x and y must agree).
  struct Pid {
    double kp = 0, ki = 0, kd = 0;
  };
  void setControllerGains(msg::GainsLoop loop, const Pid& a, const Pid& b, const Pid& c, const std::string& vehicle = "");
  // simSetWind: one wind (m/s, world NED) for every drone, added to the weather's.
  void simSetWind(const Ned& wind);
  // simSetKinematics: pose (NED from home), linear velocity (m/s, world NED) and angular
  // velocity (rad/s, body FRD), at once.
  void simSetKinematics(const NedKinematics& state, const std::string& vehicle = "");
  // Lockstep extension: follow a moving target given in NED (position m, velocity m/s).
  CommandFuture trackTargetAsync(const Ned& position, const Ned& velocity, double max_speed, double duration,
                                 const std::string& vehicle = "");
  void cancelLastTask(const std::string& vehicle = "");

  MultirotorStateNed getMultirotorState(const std::string& vehicle = "") const;
  NedCollision simGetCollisionInfo(const std::string& vehicle = "") const;
  // Pose in NED from home; simSetVehiclePose teleports.
  std::pair<Ned, NedQuaternion> simGetVehiclePose(const std::string& vehicle = "") const;
  void simSetVehiclePose(const Ned& position, const NedQuaternion& orientation, const std::string& vehicle = "");
  msg::Vector3 homeEnu(const std::string& vehicle = "") const;

  Client& client() { return client_; }

 private:
  msg::DroneState State(uint32_t actor) const;
  CommandFuture Send(uint32_t actor, msg::DroneCommand cmd);
  msg::DroneCommand Make(uint32_t actor, msg::DroneCommandKind kind) const;
  msg::DroneCommand MakeUnchecked(uint32_t actor, msg::DroneCommandKind kind) const;
  Client& client_;
  struct PendingApiControl {
    bool enabled = false;
    uint32_t run = 0;
    uint64_t frame = 0;  // the tick that carries the request
  };
  mutable std::mutex api_mu_;
  mutable std::map<uint32_t, PendingApiControl> api_pending_;  // enableApiControl requests not yet in the air state
};

}  // namespace lockstep::client
