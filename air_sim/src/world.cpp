#include "lockstep/air/world.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>
#include <stdexcept>

#include "internal.h"
#include "lockstep/air/frames.h"

namespace lockstep::air {
namespace {

template <class... Ts>
struct Overloaded : Ts... {
  using Ts::operator()...;
};
template <class... Ts>
Overloaded(Ts...) -> Overloaded<Ts...>;

using H = ControlGoal::Horizontal;
using V = ControlGoal::Vertical;

constexpr double kMaxSpeedCmd = 100.0;   // m/s, largest accepted commanded speed
constexpr double kMaxRateCmd = 20.0;     // rad/s
constexpr double kMaxCoordinate = 1e6;   // m
// AirSim MultirotorApiBase constants.
constexpr double kTakeoffMaxSpeed = 0.05;    // m/s, approx_zero_vel_: takeoff refused above it
constexpr double kLandStillSpeed = 0.05;     // m/s, approx_zero_vel_: land's "stopped" speed
constexpr double kLandStillTime = 0.22;      // s, land: > 10 command periods of 20 ms stopped
constexpr double kYawStillRate = 0.01;       // rad/s, approx_zero_angular_vel_: rotateToYaw end
constexpr double kCommandPeriod = 0.02;      // s, simple_flight's command period (auto lookahead)

std::string Num(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

std::string CheckFinite(const char* what, double v) {
  return std::isfinite(v) ? std::string() : std::string(what) + " is not finite";
}
std::string CheckFinite(const char* what, const Vec3& v) {
  return v.allFinite() ? std::string() : std::string(what) + " is not finite";
}
std::string CheckPositive(const char* what, double v) {
  if (!std::isfinite(v)) return std::string(what) + " is not finite";
  if (v <= 0) return std::string(what) + " must be > 0 (got " + Num(v) + ")";
  return {};
}
std::string CheckRange(const char* what, double v, double lo, double hi, const char* unit) {
  if (!std::isfinite(v)) return std::string(what) + " is not finite";
  if (v < lo || v > hi) {
    return std::string(what) + " " + Num(v) + " " + unit + " is out of range [" + Num(lo) + ", " + Num(hi) + "]";
  }
  return {};
}
std::string CheckPosition(const char* what, const Vec3& v) {
  if (!v.allFinite()) return std::string(what) + " is not finite";
  if (v.cwiseAbs().maxCoeff() > kMaxCoordinate) return std::string(what) + " is beyond 1e6 m";
  return {};
}
std::string CheckYawMode(const YawMode& y, Drivetrain dt) {
  if (!std::isfinite(y.yaw_or_rate)) return "yaw_mode.yaw_or_rate is not finite";
  if (y.is_rate && std::abs(y.yaw_or_rate) > kMaxRateCmd) return "yaw_mode rate " + Num(y.yaw_or_rate) + " rad/s exceeds 20 rad/s";
  if (dt == Drivetrain::kForwardOnly && y.is_rate) {
    return "drivetrain ForwardOnly requires yaw_mode.is_rate = false (AirSim rule)";
  }
  return {};
}
std::string CheckLookahead(double la, double ala) {
  if (!std::isfinite(la) || (la != -1 && la <= 0)) return "lookahead must be -1 (auto) or > 0 (got " + Num(la) + ")";
  if (!std::isfinite(ala) || ala < 0) return "adaptive_lookahead must be >= 0 (got " + Num(ala) + ")";
  return {};
}
std::string CheckTilt(const char* what, double v, double max_tilt) {
  if (!std::isfinite(v)) return std::string(what) + " is not finite";
  if (std::abs(v) > max_tilt + 1e-12) {
    return std::string(what) + " " + Num(v) + " rad exceeds max_tilt " + Num(max_tilt) + " rad";
  }
  return {};
}
std::string First(std::initializer_list<std::string> checks) {
  for (const std::string& c : checks)
    if (!c.empty()) return c;
  return {};
}

std::string ValidateBody(const DroneModel& dm, const DroneState& ds, const CommandBody& body) {
  const ControllerGains& g = ds.controller.gains;
  return std::visit(
      Overloaded{
          [](const cmd::Arm&) { return std::string(); },
          [](const cmd::Disarm&) { return std::string(); },
          [](const cmd::Hover&) { return std::string(); },
          [](const cmd::SetApiControl&) { return std::string(); },
          [&](const cmd::Takeoff& c) {
            std::string e = First({CheckRange("takeoff height", c.height, 0, 1000, "m"), CheckPositive("timeout", c.timeout)});
            // AirSim refuses a takeoff while the drone moves (relative to what it stands on).
            const Vec3 rel = ds.velocity - (ds.landed == LandedState::kLanded ? ds.support_velocity : Vec3::Zero());
            if (e.empty() && rel.norm() > kTakeoffMaxSpeed) {
              e = "cannot take off while moving at " + Num(rel.norm()) + " m/s (AirSim limit 0.05 m/s)";
            }
            return e;
          },
          [](const cmd::Land& c) { return CheckPositive("timeout", c.timeout); },
          [](const cmd::GoHome& c) {
            return First({CheckPositive("velocity", c.velocity), CheckRange("velocity", c.velocity, 0, kMaxSpeedCmd, "m/s"),
                          CheckPositive("timeout", c.timeout)});
          },
          [](const cmd::MoveToPosition& c) {
            return First({CheckPosition("position", c.position), CheckPositive("velocity", c.velocity),
                          CheckRange("velocity", c.velocity, 0, kMaxSpeedCmd, "m/s"), CheckPositive("timeout", c.timeout),
                          CheckYawMode(c.yaw_mode, c.drivetrain), CheckLookahead(c.lookahead, c.adaptive_lookahead)});
          },
          [](const cmd::MoveOnPath& c) {
            if (c.path.empty()) return std::string("path is empty");
            if (c.path.size() > 100000) return std::string("path has more than 100000 points");
            for (const Vec3& pt : c.path) {
              if (std::string e = CheckPosition("path point", pt); !e.empty()) return e;
            }
            return First({CheckPositive("velocity", c.velocity), CheckRange("velocity", c.velocity, 0, kMaxSpeedCmd, "m/s"),
                          CheckPositive("timeout", c.timeout), CheckYawMode(c.yaw_mode, c.drivetrain),
                          CheckLookahead(c.lookahead, c.adaptive_lookahead)});
          },
          [](const cmd::TrackTarget& c) {
            std::string e = First({CheckPosition("target position", c.position), CheckFinite("target velocity", c.velocity),
                                   CheckRange("max_speed", c.max_speed, 0, kMaxSpeedCmd, "m/s"),
                                   CheckPositive("gain", c.gain), CheckPositive("duration", c.duration),
                                   CheckYawMode(c.yaw_mode, Drivetrain::kMaxDegreeOfFreedom)});
            if (e.empty() && c.velocity.norm() > kMaxSpeedCmd) e = "target velocity exceeds 100 m/s";
            return e;
          },
          [](const cmd::MoveToZ& c) {
            return First({CheckRange("z", c.z, -kMaxCoordinate, kMaxCoordinate, "m"), CheckPositive("velocity", c.velocity),
                          CheckRange("velocity", c.velocity, 0, kMaxSpeedCmd, "m/s"), CheckPositive("timeout", c.timeout),
                          CheckYawMode(c.yaw_mode, Drivetrain::kMaxDegreeOfFreedom),
                          CheckLookahead(c.lookahead, c.adaptive_lookahead)});
          },
          [&](const cmd::MoveByRollPitchYawrateZ& c) {
            return First({CheckTilt("roll", c.roll, g.max_tilt), CheckTilt("pitch", c.pitch, g.max_tilt),
                          CheckRange("yaw_rate", c.yaw_rate, -kMaxRateCmd, kMaxRateCmd, "rad/s"),
                          CheckRange("z", c.z, -kMaxCoordinate, kMaxCoordinate, "m"), CheckPositive("duration", c.duration)});
          },
          [](const cmd::SetKinematics& c) {
            std::string e = First({CheckPosition("pose position", c.pose.position), CheckFinite("velocity", c.velocity),
                                   CheckFinite("angular_velocity", c.angular_velocity)});
            if (e.empty() && (!c.pose.orientation.coeffs().allFinite() || c.pose.orientation.norm() < 1e-6)) {
              e = "pose orientation is not a finite non-zero quaternion";
            }
            if (e.empty() && c.velocity.norm() > kMaxSpeedCmd) e = "velocity exceeds 100 m/s";
            if (e.empty() && c.angular_velocity.cwiseAbs().maxCoeff() > kMaxRateCmd) e = "angular velocity exceeds 20 rad/s";
            return e;
          },
          [](const cmd::MoveByVelocity& c) {
            std::string e = First({CheckFinite("velocity", c.velocity), CheckPositive("duration", c.duration),
                                   CheckYawMode(c.yaw_mode, c.drivetrain)});
            if (e.empty() && c.velocity.norm() > kMaxSpeedCmd) e = "velocity " + Num(c.velocity.norm()) + " m/s exceeds 100 m/s";
            return e;
          },
          [](const cmd::MoveByVelocityZ& c) {
            std::string e = First({CheckFinite("vx", c.vx), CheckFinite("vy", c.vy), CheckRange("z", c.z, -kMaxCoordinate, kMaxCoordinate, "m"),
                                   CheckPositive("duration", c.duration), CheckYawMode(c.yaw_mode, c.drivetrain)});
            if (e.empty() && std::hypot(c.vx, c.vy) > kMaxSpeedCmd) e = "velocity exceeds 100 m/s";
            return e;
          },
          [&](const cmd::MoveByRollPitchYawThrottle& c) {
            return First({CheckTilt("roll", c.roll, g.max_tilt), CheckTilt("pitch", c.pitch, g.max_tilt),
                          CheckFinite("yaw", c.yaw), CheckRange("throttle", c.throttle, 0, 1, ""),
                          CheckPositive("duration", c.duration)});
          },
          [&](const cmd::MoveByRollPitchYawZ& c) {
            return First({CheckTilt("roll", c.roll, g.max_tilt), CheckTilt("pitch", c.pitch, g.max_tilt),
                          CheckFinite("yaw", c.yaw), CheckRange("z", c.z, -kMaxCoordinate, kMaxCoordinate, "m"),
                          CheckPositive("duration", c.duration)});
          },
          [&](const cmd::MoveByRollPitchYawrateThrottle& c) {
            return First({CheckTilt("roll", c.roll, g.max_tilt), CheckTilt("pitch", c.pitch, g.max_tilt),
                          CheckRange("yaw_rate", c.yaw_rate, -kMaxRateCmd, kMaxRateCmd, "rad/s"),
                          CheckRange("throttle", c.throttle, 0, 1, ""), CheckPositive("duration", c.duration)});
          },
          [](const cmd::MoveByAngleRatesThrottle& c) {
            std::string e = First({CheckFinite("rates", c.rates), CheckRange("throttle", c.throttle, 0, 1, ""),
                                   CheckPositive("duration", c.duration)});
            if (e.empty() && c.rates.cwiseAbs().maxCoeff() > kMaxRateCmd) e = "angle rate exceeds 20 rad/s";
            return e;
          },
          [](const cmd::MoveByAngleRatesZ& c) {
            std::string e = First({CheckFinite("rates", c.rates), CheckRange("z", c.z, -kMaxCoordinate, kMaxCoordinate, "m"),
                                   CheckPositive("duration", c.duration)});
            if (e.empty() && c.rates.cwiseAbs().maxCoeff() > kMaxRateCmd) e = "angle rate exceeds 20 rad/s";
            return e;
          },
          [&](const cmd::MoveByMotorPwms& c) {
            const std::size_t n = dm.derived.rotors.size();
            if (c.pwm.size() != n) {
              return "pwm has " + std::to_string(c.pwm.size()) + " values; this " + ToString(dm.params.frame) +
                     " drone has " + std::to_string(n) + " rotors";
            }
            for (double v : c.pwm) {
              if (std::string e = CheckRange("pwm", v, 0, 1, ""); !e.empty()) return e;
            }
            return CheckPositive("duration", c.duration);
          },
          [](const cmd::RotateToYaw& c) {
            return First({CheckFinite("yaw", c.yaw), CheckPositive("timeout", c.timeout), CheckPositive("margin", c.margin)});
          },
          [](const cmd::RotateByYawRate& c) {
            return First({CheckRange("yaw_rate", c.yaw_rate, -kMaxRateCmd, kMaxRateCmd, "rad/s"),
                          CheckPositive("duration", c.duration)});
          },
          [&](const cmd::SetGains& c) {
            MultirotorParams p = dm.params;
            p.gains = c.gains;
            const std::string e = ValidateParams(p);
            return e.empty() ? e : "gains: " + e;
          },
          [](const cmd::SetPose& c) {
            std::string e = CheckPosition("pose position", c.pose.position);
            if (e.empty() && (!c.pose.orientation.coeffs().allFinite() || c.pose.orientation.norm() < 1e-6)) {
              e = "pose orientation is not a finite non-zero quaternion";
            }
            return e;
          },
      },
      body);
}

bool NeedsArmed(const CommandBody& b) {
  return IsMotionCommand(b) && !std::holds_alternative<cmd::SetPose>(b) && !std::holds_alternative<cmd::SetKinematics>(b);
}

// ----------------------------------------------------------------- command bookkeeping
struct Ctx {
  const World& model;
  const DroneModel& dm;
  DroneState& ds;
  std::vector<CommandReport>& reports;
  std::uint64_t frame;
};

void Report(Ctx& c, CommandId id, CommandStatus st, double t, std::string msg = {}) {
  CommandReport r;
  r.id = id;
  r.drone = c.ds.id;
  r.status = st;
  r.time = t;
  r.frame = c.frame;
  r.message = std::move(msg);
  c.reports.push_back(std::move(r));
}

void Finish(Ctx& c, CommandStatus st, double t, std::string msg = {}) {
  ActiveCommand& ac = c.ds.command;
  if (ac.running) Report(c, ac.id, st, t, std::move(msg));
  ac.running = false;
}

void EnterHold(DroneState& ds, const Vec3& where) {
  ds.command.mode = CommandMode::kHold;
  ds.command.target = where;
}

void SetupPath(ActiveCommand& ac, const Vec3& start, const std::vector<Vec3>& pts, double speed,
               double lookahead, double adaptive) {
  ac.path.clear();
  ac.path_s.clear();
  ac.path.push_back(start);
  ac.path_s.push_back(0);
  for (const Vec3& p : pts) {
    const double seg = (p - ac.path.back()).norm();
    if (seg < 1e-9) continue;
    ac.path_s.push_back(ac.path_s.back() + seg);
    ac.path.push_back(p);
  }
  // Speed allowed at each vertex: full speed on a straight line, zero for a turn of 90 deg or
  // more, cos(turn) in between; zero at the end.
  ac.path_vmax.assign(ac.path.size(), 0.0);
  for (std::size_t i = 1; i + 1 < ac.path.size(); ++i) {
    const Vec3 a = (ac.path[i] - ac.path[i - 1]).normalized();
    const Vec3 b = (ac.path[i + 1] - ac.path[i]).normalized();
    ac.path_vmax[i] = speed * std::max(0.0, a.dot(b));
  }
  ac.s = 0;
  ac.s_dot = 0;
  ac.segment = 1;
  ac.speed = speed;
  // AirSim getAutoLookahead: speed x command period x (30 adaptive, else 40), at least 0.75 m
  // (1.5 x the distance accuracy 0.5 m).
  ac.lookahead = lookahead > 0 ? lookahead : std::max(speed * kCommandPeriod * (adaptive > 0 ? 30.0 : 40.0), 0.75);
  ac.adaptive_lookahead = adaptive;
}

// Point and unit tangent at arc length s.
void PathAt(const ActiveCommand& ac, double s, Vec3* point, Vec3* tangent) {
  const std::size_t n = ac.path.size();
  if (n < 2) {
    *point = ac.path.empty() ? Vec3::Zero() : ac.path.back();
    tangent->setZero();
    return;
  }
  // Segment i containing s: path_s[i - 1] < s <= path_s[i] (binary search).
  const std::size_t i = static_cast<std::size_t>(
      std::lower_bound(ac.path_s.begin() + 1, ac.path_s.end() - 1, s) - ac.path_s.begin());
  const double seg = ac.path_s[i] - ac.path_s[i - 1];
  const double u = std::clamp((s - ac.path_s[i - 1]) / seg, 0.0, 1.0);
  *tangent = (ac.path[i] - ac.path[i - 1]) / seg;
  *point = ac.path[i - 1] + (ac.path[i] - ac.path[i - 1]) * u;
}

Vec3 BodyToWorldHeading(const Vec3& v, double yaw) {
  const double c = std::cos(yaw), s = std::sin(yaw);
  return Vec3(c * v.x() - s * v.y(), s * v.x() + c * v.y(), v.z());
}

// How a command AirSim waits out ends when it steers nothing (no API control); kDuration with
// end 0 = it ends at once (Hover, a goal the drone is at already).
std::pair<DroneState::Unsteered::Ends, double> UnsteeredEnd(const DroneState& ds, const CommandBody& body) {
  using E = DroneState::Unsteered::Ends;
  auto at = [&](const Vec3& goal) { return (goal - ds.position).norm() < 1e-6; };
  return std::visit(
      Overloaded{
          [](const cmd::Takeoff& k) { return std::pair{E::kTimeout, k.timeout}; },
          [](const cmd::Land& k) { return std::pair{E::kLand, k.timeout}; },
          [&](const cmd::GoHome& k) { return std::pair{E::kTimeout, k.timeout}; },
          [&](const cmd::MoveToPosition& k) { return at(k.position) ? std::pair{E::kDuration, 0.0} : std::pair{E::kTimeout, k.timeout}; },
          [&](const cmd::MoveToZ& k) {
            return at(Vec3(ds.position.x(), ds.position.y(), k.z)) ? std::pair{E::kDuration, 0.0} : std::pair{E::kTimeout, k.timeout};
          },
          [&](const cmd::MoveOnPath& k) {
            const bool here = std::all_of(k.path.begin(), k.path.end(), at);
            return here ? std::pair{E::kDuration, 0.0} : std::pair{E::kTimeout, k.timeout};
          },
          [&](const cmd::RotateToYaw& k) {
            const double yaw_rate = (ds.orientation * ds.angular_velocity).z();
            const bool there = std::abs(WrapAngle(k.yaw - YawOf(ds.orientation))) <= k.margin && std::abs(yaw_rate) <= kYawStillRate;
            return there ? std::pair{E::kDuration, 0.0} : std::pair{E::kTimeout, k.timeout};
          },
          [](const cmd::TrackTarget& k) { return std::pair{E::kDuration, k.duration}; },
          [](const cmd::MoveByVelocity& k) { return std::pair{E::kDuration, k.duration}; },
          [](const cmd::MoveByVelocityZ& k) { return std::pair{E::kDuration, k.duration}; },
          [](const cmd::MoveByRollPitchYawThrottle& k) { return std::pair{E::kDuration, k.duration}; },
          [](const cmd::MoveByRollPitchYawZ& k) { return std::pair{E::kDuration, k.duration}; },
          [](const cmd::MoveByRollPitchYawrateThrottle& k) { return std::pair{E::kDuration, k.duration}; },
          [](const cmd::MoveByRollPitchYawrateZ& k) { return std::pair{E::kDuration, k.duration}; },
          [](const cmd::MoveByAngleRatesThrottle& k) { return std::pair{E::kDuration, k.duration}; },
          [](const cmd::MoveByAngleRatesZ& k) { return std::pair{E::kDuration, k.duration}; },
          [](const cmd::MoveByMotorPwms& k) { return std::pair{E::kDuration, k.duration}; },
          [](const cmd::RotateByYawRate& k) { return std::pair{E::kDuration, k.duration}; },
          [](const auto&) { return std::pair{E::kDuration, 0.0}; },  // Hover; the rest never get here
      },
      body);
}

void FinishUnsteered(Ctx& c, CommandStatus st, double t, std::string msg = {}) {
  DroneState::Unsteered& u = c.ds.unsteered;
  if (u.running) Report(c, u.id, st, t, std::move(msg));
  u.running = false;
}

// A motion command without API control (simple_flight's setGoalAndMode refuses it): it
// replaces the running command, as AirSim's SingleTaskCall, and steers nothing.
void StartUnsteered(Ctx& c, const Command& cm, double t) {
  DroneState& ds = c.ds;
  const std::string by = std::string("replaced by ") + CommandName(cm.body) + " (command " + std::to_string(cm.id) + ")";
  Finish(c, CommandStatus::kCancelled, t, by);
  FinishUnsteered(c, CommandStatus::kCancelled, t, by);
  const auto [ends, span] = UnsteeredEnd(ds, cm.body);
  Report(c, cm.id, CommandStatus::kRunning, t, "no API control: the command does not steer the drone");
  DroneState::Unsteered& u = ds.unsteered;
  u.id = cm.id;
  u.running = true;
  u.ends = ends;
  u.end_time = t + span;
  u.still_since = -1;
  u.resume = CommandMode::kIdle;
  u.start_time = t;
  ds.command.id = cm.id;  // not running: kept for API control taken back (SetApiControl)
  ds.command.body = cm.body;
  if (ends == DroneState::Unsteered::Ends::kDuration && span <= 0) FinishUnsteered(c, CommandStatus::kCompleted, t);
}

void ApplyCommand(Ctx& c, const Command& cm, double t);

// enableApiControl(true / false). Released, the running command goes on unsteered (AirSim's
// waiter runs on) and the drone gets simple_flight's goal without an RC: zero throttle.
// Taken back while that command (or one issued meanwhile) still runs, it steers again: AirSim's
// loop keeps sending its goals, which simple_flight accepts again (SimpleFlightApi::
// enableApiControl cancels nothing); its timeout or duration still counts from its call.
void SetApiControl(Ctx& c, bool enable, double t) {
  DroneState& ds = c.ds;
  if (enable == ds.api_control) return;
  ds.api_control = enable;
  ActiveCommand& ac = ds.command;
  DroneState::Unsteered& u = ds.unsteered;
  if (enable) {
    if (!u.running) return;
    u.running = false;
    if (u.resume != CommandMode::kIdle) {
      ac.mode = u.resume;  // the ActiveCommand kept its body, path and progress
      ac.running = true;
      Report(c, ac.id, CommandStatus::kRunning, t, "API control taken back: the command steers again");
      return;
    }
    if (ac.id != u.id) return;
    Command cm;
    cm.id = u.id;
    cm.drone = ds.id;
    cm.body = ac.body;
    ApplyCommand(c, cm, t);
    if (ac.running && ac.id == u.id) {
      ac.start_time = u.start_time;
      ac.end_time = u.end_time;
    }
    return;
  }
  if (ac.running) {
    using E = DroneState::Unsteered::Ends;
    u.id = ac.id;
    u.running = true;
    u.ends = ac.mode == CommandMode::kLand ? E::kLand
             : (ac.mode == CommandMode::kTakeoff || ac.mode == CommandMode::kPath || ac.mode == CommandMode::kRotateToYaw)
                 ? E::kTimeout
                 : E::kDuration;
    u.end_time = ac.end_time;
    u.still_since = -1;
    u.resume = ac.mode;
    u.start_time = ac.start_time;
    ac.running = false;
  }
  ac.mode = CommandMode::kIdle;
}

// After a sub-step ending at t_end: an unsteered command's end.
void CheckUnsteered(Ctx& c, double t_end) {
  DroneState::Unsteered& u = c.ds.unsteered;
  if (!u.running) return;
  if (u.ends == DroneState::Unsteered::Ends::kLand) {
    // AirSim's land(): done after more than 10 command periods with a NED z velocity <= 0.05 m/s.
    if (c.ds.velocity.z() >= -kLandStillSpeed) {
      if (u.still_since < 0) u.still_since = t_end;
      if (t_end - u.still_since >= kLandStillTime - 1e-9) {
        FinishUnsteered(c, CommandStatus::kCompleted, t_end);
        return;
      }
    } else {
      u.still_since = -1;
    }
  }
  if (t_end < u.end_time - 1e-9) return;
  if (u.ends == DroneState::Unsteered::Ends::kDuration) {
    FinishUnsteered(c, CommandStatus::kCompleted, t_end);
  } else {
    FinishUnsteered(c, CommandStatus::kTimedOut, t_end, "timeout without API control (the command did not steer the drone)");
  }
}

void ApplyCommand(Ctx& c, const Command& cm, double t) {
  DroneState& ds = c.ds;
  const MultirotorParams& p = c.dm.params;
  ActiveCommand& ac = ds.command;
  const double yaw_now = YawOf(ds.orientation);
  if (const auto* api = std::get_if<cmd::SetApiControl>(&cm.body)) {
    SetApiControl(c, api->enable, t);
    Report(c, cm.id, CommandStatus::kCompleted, t);
    return;
  }
  if (!ds.api_control && NeedsArmed(cm.body)) {
    StartUnsteered(c, cm, t);
    return;
  }
  if (IsMotionCommand(cm.body) && ds.unsteered.running) {
    FinishUnsteered(c, CommandStatus::kCancelled, t, std::string("replaced by ") + CommandName(cm.body) + " (command " +
                                                         std::to_string(cm.id) + ")");
  }
  if (IsMotionCommand(cm.body) || std::holds_alternative<cmd::Disarm>(cm.body)) {
    if (ac.running) {
      Finish(c, CommandStatus::kCancelled, t,
             std::string("replaced by ") + CommandName(cm.body) + " (command " + std::to_string(cm.id) + ")");
    }
    if (ac.mode == CommandMode::kIdle || ac.mode == CommandMode::kPwm) ds.controller.yaw_ref = yaw_now;
  }
  auto start = [&](CommandMode mode, double end_time) {
    ac.id = cm.id;
    ac.mode = mode;
    ac.running = true;
    ac.start_time = t;
    ac.end_time = t + end_time;
    ac.body = cm.body;
    ac.landed_since = -1;
    Report(c, cm.id, CommandStatus::kRunning, t);
  };
  auto immediate = [&] { Report(c, cm.id, CommandStatus::kCompleted, t); };
  std::visit(
      Overloaded{
          [&](const cmd::Arm&) {
            if (!ds.armed) {
              ds.armed = true;
              if (!ac.running) ac.mode = CommandMode::kIdle;
            }
            immediate();
          },
          [&](const cmd::Disarm&) {
            ds.armed = false;
            ac.mode = CommandMode::kIdle;
            immediate();
          },
          [&](const cmd::SetGains& g) {
            ds.controller.gains = g.gains;
            immediate();
          },
          [&](const cmd::SetApiControl&) { immediate(); },
          [&](const cmd::Hover&) {
            if (ds.armed) EnterHold(ds, ds.position);
            immediate();
          },
          [&](const cmd::SetKinematics& sk) {
            ds.position = sk.pose.position;
            ds.orientation = sk.pose.orientation.normalized();
            ds.velocity = sk.velocity;
            ds.angular_velocity = sk.angular_velocity;
            ds.grounded = false;
            ds.carrier = 0;
            ds.controller.yaw_ref = YawOf(ds.orientation);
            if (ds.armed) EnterHold(ds, ds.position);
            else ac.mode = CommandMode::kIdle;
            immediate();
          },
          [&](const cmd::SetPose& sp) {
            ds.position = sp.pose.position;
            ds.orientation = sp.pose.orientation.normalized();
            ds.velocity.setZero();
            ds.angular_velocity.setZero();
            ds.grounded = false;
            ds.carrier = 0;
            ds.controller.yaw_ref = YawOf(ds.orientation);
            ds.controller.vz_integral = 0;
            ds.controller.vxy_integral.setZero();
            if (ds.armed) EnterHold(ds, ds.position);
            else ac.mode = CommandMode::kIdle;
            immediate();
          },
          [&](const cmd::Takeoff& k) {
            const double hgt = k.height > 0 ? k.height : p.takeoff_height;
            SetupPath(ac, ds.position, {ds.position + Vec3(0, 0, hgt)}, p.takeoff_speed, -1, 1);
            start(CommandMode::kTakeoff, k.timeout);
          },
          [&](const cmd::Land& k) {
            ac.target = ds.position;
            start(CommandMode::kLand, k.timeout);
          },
          [&](const cmd::GoHome& k) {
            SetupPath(ac, ds.position, {c.dm.spawn.position}, k.velocity, -1, 1);
            start(CommandMode::kPath, k.timeout);
          },
          [&](const cmd::MoveToPosition& k) {
            SetupPath(ac, ds.position, {k.position}, k.velocity, k.lookahead, k.adaptive_lookahead);
            start(CommandMode::kPath, k.timeout);
          },
          [&](const cmd::MoveToZ& k) {
            SetupPath(ac, ds.position, {Vec3(ds.position.x(), ds.position.y(), k.z)}, k.velocity, k.lookahead,
                      k.adaptive_lookahead);
            start(CommandMode::kPath, k.timeout);
          },
          [&](const cmd::MoveOnPath& k) {
            SetupPath(ac, ds.position, k.path, k.velocity, k.lookahead, k.adaptive_lookahead);
            start(CommandMode::kPath, k.timeout);
          },
          [&](const cmd::TrackTarget& k) {
            ac.target = k.position;
            ac.velocity = k.velocity;
            start(CommandMode::kTrack, k.duration);
          },
          [&](const cmd::MoveByVelocity& k) {
            ac.velocity = k.frame == VelocityFrame::kBody ? BodyToWorldHeading(k.velocity, yaw_now) : k.velocity;
            start(CommandMode::kVelocity, k.duration);
          },
          [&](const cmd::MoveByVelocityZ& k) {
            const Vec3 v(k.vx, k.vy, 0);
            ac.velocity = k.frame == VelocityFrame::kBody ? BodyToWorldHeading(v, yaw_now) : v;
            start(CommandMode::kVelocityZ, k.duration);
          },
          [&](const cmd::MoveByRollPitchYawThrottle& k) { start(CommandMode::kRpyThrottle, k.duration); },
          [&](const cmd::MoveByRollPitchYawZ& k) { start(CommandMode::kRpyZ, k.duration); },
          [&](const cmd::MoveByRollPitchYawrateThrottle& k) { start(CommandMode::kRpyRateThrottle, k.duration); },
          [&](const cmd::MoveByRollPitchYawrateZ& k) { start(CommandMode::kRpyRateZ, k.duration); },
          [&](const cmd::MoveByAngleRatesThrottle& k) { start(CommandMode::kRatesThrottle, k.duration); },
          [&](const cmd::MoveByAngleRatesZ& k) { start(CommandMode::kRatesZ, k.duration); },
          [&](const cmd::MoveByMotorPwms& k) { start(CommandMode::kPwm, k.duration); },
          [&](const cmd::RotateToYaw& k) {
            ac.target = ds.position;
            start(CommandMode::kRotateToYaw, k.timeout);
          },
          [&](const cmd::RotateByYawRate& k) {
            ac.target = ds.position;
            start(CommandMode::kRotateByYawRate, k.duration);
          },
      },
      cm.body);
}

// Absolute-altitude commands: AirSim's position loop (0 = none) or, with the physical gain
// model, Lockstep's sqrt-limited closing gain.
double AltitudeGain(const MultirotorParams& p, const DroneState& ds) {
  return p.gain_model == GainModel::kPhysical ? ds.controller.gains.altitude_gain : 0.0;
}

void ApplyYawMode(const YawMode& ym, ControlGoal* g) {
  g->yaw_is_rate = ym.is_rate;
  g->yaw = ym.yaw_or_rate;
}

void ApplyDrivetrain(Drivetrain dt, const YawMode& ym, const Vec3& direction, ControlGoal* g) {
  ApplyYawMode(ym, g);
  if (dt == Drivetrain::kForwardOnly) {
    if (direction.head<2>().norm() > 0.1) {
      g->yaw_is_rate = false;
      g->yaw = std::atan2(direction.y(), direction.x()) + ym.yaw_or_rate;
    } else {
      g->yaw_is_rate = true;  // hold the current heading while (almost) still
      g->yaw = 0;
    }
  }
}

// After a sub-step ending at t_end: durations end (COMPLETED) and timeouts fire (TIMED_OUT).
void CheckDeadline(Ctx& c, double t_end) {
  DroneState& ds = c.ds;
  ActiveCommand& ac = ds.command;
  if (!ac.running || t_end < ac.end_time - 1e-9) return;
  switch (ac.mode) {
    case CommandMode::kTakeoff:
    case CommandMode::kLand:
    case CommandMode::kPath:
    case CommandMode::kRotateToYaw:
      Finish(c, CommandStatus::kTimedOut, t_end, "timeout after " + Num(ac.end_time - ac.start_time) + " s");
      break;
    default:
      Finish(c, CommandStatus::kCompleted, t_end);
      break;
  }
  if (!ds.armed || (ac.mode == CommandMode::kLand && ds.landed == LandedState::kLanded)) {
    ac.mode = CommandMode::kIdle;
  } else {
    EnterHold(ds, ds.position);
  }
}

// Per sub-step: command progress, completion, and the controller goal.
ControlGoal UpdateCommand(Ctx& c, double t, double h) {
  DroneState& ds = c.ds;
  ActiveCommand& ac = ds.command;
  const MultirotorParams& p = c.dm.params;
  ControlGoal g;
  if (!ds.armed) {
    ac.mode = CommandMode::kIdle;
    return g;
  }
  const double t_end = t + h;
  g.yaw_is_rate = true;
  g.yaw = 0;
  switch (ac.mode) {
    case CommandMode::kIdle:
      return g;  // motors off
    case CommandMode::kHold:
    case CommandMode::kRotateToYaw:
    case CommandMode::kRotateByYawRate: {
      g.horizontal = H::kPosition;
      g.vertical = V::kPosition;
      g.position = ac.target;
      if (ac.mode == CommandMode::kRotateToYaw) {
        const auto& k = std::get<cmd::RotateToYaw>(ac.body);
        g.yaw_is_rate = false;
        g.yaw = k.yaw;
        // AirSim: within the margin, hold the heading (yaw rate 0) until the yaw rate settles.
        if (std::abs(WrapAngle(k.yaw - YawOf(ds.orientation))) <= k.margin) {
          const double yaw_rate = (ds.orientation * ds.angular_velocity).z();
          if (std::abs(yaw_rate) <= kYawStillRate) {
            Finish(c, CommandStatus::kCompleted, t_end);
            EnterHold(ds, ac.target);
          }
        }
      } else if (ac.mode == CommandMode::kRotateByYawRate) {
        g.yaw = std::get<cmd::RotateByYawRate>(ac.body).yaw_rate;
      }
      return g;
    }
    case CommandMode::kTakeoff:
    case CommandMode::kPath: {
      const double total = ac.path_s.back();
      const double remaining = total - ac.s;
      Vec3 ref, tangent;
      PathAt(ac, ac.s, &ref, &tangent);
      // The reference waits while it leads the drone by more than the lookahead; AirSim's
      // adaptive lookahead adds adaptive_lookahead x the drone's cross-track error.
      const Vec3 off = ds.position - ref;
      double la = ac.lookahead;
      if (ac.adaptive_lookahead > 0) la += ac.adaptive_lookahead * (off - tangent * tangent.dot(off)).norm();
      const double lag = off.norm();
      double sdot_des = std::min(ac.speed, std::sqrt(2.0 * p.path_accel * std::max(remaining, 0.0)));
      while (ac.segment < ac.path.size() && ac.path_s[ac.segment] <= ac.s + 1e-9) ++ac.segment;
      for (std::size_t i = ac.segment; i < ac.path.size(); ++i) {  // slow down for the corners ahead
        const double dist = ac.path_s[i] - ac.s;
        if (dist <= 1e-9) continue;
        const double v2 = ac.path_vmax[i] * ac.path_vmax[i] + 2.0 * p.path_accel * dist;
        if (v2 >= ac.speed * ac.speed) break;
        sdot_des = std::min(sdot_des, std::sqrt(v2));
      }
      sdot_des *= std::clamp((2.0 * la - lag) / la, 0.0, 1.0);
      const double sdot_old = ac.s_dot;
      if (sdot_des > ac.s_dot) {
        ac.s_dot = std::min(sdot_des, ac.s_dot + p.path_accel * h);
      } else {
        ac.s_dot = std::max(sdot_des, ac.s_dot - 1.5 * p.path_accel * h);
      }
      ac.s = std::min(total, ac.s + ac.s_dot * h);
      if (ac.s >= total) ac.s_dot = 0;
      PathAt(ac, ac.s, &ref, &tangent);
      g.horizontal = H::kPosition;
      g.vertical = V::kPosition;
      g.position = ref;
      g.velocity = tangent * ac.s_dot;
      g.accel = tangent * ((ac.s_dot - sdot_old) / h);
      g.max_speed = std::max(p.gains.max_velocity, ac.speed * 1.2);
      if (ac.mode == CommandMode::kPath) {
        if (const auto* mp = std::get_if<cmd::MoveToPosition>(&ac.body)) {
          ApplyDrivetrain(mp->drivetrain, mp->yaw_mode, ac.path.back() - ds.position, &g);
        } else if (const auto* mop = std::get_if<cmd::MoveOnPath>(&ac.body)) {
          ApplyDrivetrain(mop->drivetrain, mop->yaw_mode, tangent, &g);
        }
      }
      const Vec3& end = ac.path.back();
      if (ac.running && ac.s >= total && (ds.position - end).norm() < p.arrival_tolerance &&
          ds.velocity.norm() < 0.5) {
        Finish(c, CommandStatus::kCompleted, t_end);
        EnterHold(ds, end);
      }
      return g;
    }
    case CommandMode::kLand: {
      g.horizontal = H::kPosition;
      g.vertical = V::kVelocity;
      g.position = ac.target;
      g.velocity = Vec3(0, 0, -p.landing_speed);
      // AirSim: done once the vertical speed stays within 0.05 m/s for more than 10 command
      // periods (counted here only while LANDED, see docs/air.md).
      const double vz_rel = ds.velocity.z() - ds.support_velocity.z();
      if (ds.landed == LandedState::kLanded && std::abs(vz_rel) <= kLandStillSpeed) {
        if (ac.landed_since < 0) ac.landed_since = t;
        if (t_end - ac.landed_since >= kLandStillTime - 1e-9) {
          Finish(c, CommandStatus::kCompleted, t_end);
          ac.mode = CommandMode::kIdle;
          return ControlGoal{};
        }
      } else {
        ac.landed_since = -1;
      }
      return g;
    }
    case CommandMode::kTrack: {
      const auto& k = std::get<cmd::TrackTarget>(ac.body);
      g.horizontal = H::kPosition;
      g.vertical = V::kPosition;
      g.position = ac.target + ac.velocity * (t_end - ac.start_time);
      g.velocity = ac.velocity;
      g.closing_gain_xy = k.gain;
      g.closing_gain_z = k.gain;
      g.max_speed = k.max_speed;
      ApplyYawMode(k.yaw_mode, &g);
      return g;
    }
    case CommandMode::kVelocity: {
      const auto& k = std::get<cmd::MoveByVelocity>(ac.body);
      g.horizontal = H::kVelocity;
      g.vertical = V::kVelocity;
      g.velocity = ac.velocity;
      g.max_speed = std::max(p.gains.max_velocity, ac.velocity.norm());
      ApplyDrivetrain(k.drivetrain, k.yaw_mode, ac.velocity, &g);
      return g;
    }
    case CommandMode::kVelocityZ: {
      const auto& k = std::get<cmd::MoveByVelocityZ>(ac.body);
      g.horizontal = H::kVelocity;
      g.vertical = V::kPosition;
      g.velocity = ac.velocity;
      g.position = Vec3(0, 0, k.z);
      g.closing_gain_z = AltitudeGain(p, ds);
      g.max_speed = std::max(p.gains.max_velocity, ac.velocity.norm());
      ApplyDrivetrain(k.drivetrain, k.yaw_mode, ac.velocity, &g);
      return g;
    }
    case CommandMode::kRpyThrottle: {
      const auto& k = std::get<cmd::MoveByRollPitchYawThrottle>(ac.body);
      g.horizontal = H::kAngle;
      g.vertical = V::kThrottle;
      g.roll = k.roll;
      g.pitch = k.pitch;
      g.yaw_is_rate = false;
      g.yaw = k.yaw;
      g.throttle = k.throttle;
      return g;
    }
    case CommandMode::kRpyZ: {
      const auto& k = std::get<cmd::MoveByRollPitchYawZ>(ac.body);
      g.horizontal = H::kAngle;
      g.vertical = V::kPosition;
      g.roll = k.roll;
      g.pitch = k.pitch;
      g.yaw_is_rate = false;
      g.yaw = k.yaw;
      g.position = Vec3(0, 0, k.z);
      g.closing_gain_z = AltitudeGain(p, ds);
      return g;
    }
    case CommandMode::kRpyRateThrottle: {
      const auto& k = std::get<cmd::MoveByRollPitchYawrateThrottle>(ac.body);
      g.horizontal = H::kAngle;
      g.vertical = V::kThrottle;
      g.roll = k.roll;
      g.pitch = k.pitch;
      g.yaw = k.yaw_rate;
      g.throttle = k.throttle;
      return g;
    }
    case CommandMode::kRpyRateZ: {
      const auto& k = std::get<cmd::MoveByRollPitchYawrateZ>(ac.body);
      g.horizontal = H::kAngle;
      g.vertical = V::kPosition;
      g.roll = k.roll;
      g.pitch = k.pitch;
      g.yaw = k.yaw_rate;
      g.position = Vec3(0, 0, k.z);
      g.closing_gain_z = AltitudeGain(p, ds);
      return g;
    }
    case CommandMode::kRatesThrottle: {
      const auto& k = std::get<cmd::MoveByAngleRatesThrottle>(ac.body);
      g.horizontal = H::kRate;
      g.vertical = V::kThrottle;
      g.rates = k.rates;
      g.throttle = k.throttle;
      return g;
    }
    case CommandMode::kRatesZ: {
      const auto& k = std::get<cmd::MoveByAngleRatesZ>(ac.body);
      g.horizontal = H::kRate;
      g.vertical = V::kPosition;
      g.rates = k.rates;
      g.position = Vec3(0, 0, k.z);
      g.closing_gain_z = AltitudeGain(p, ds);
      return g;
    }
    case CommandMode::kPwm: {
      const auto& k = std::get<cmd::MoveByMotorPwms>(ac.body);
      g.horizontal = H::kMotors;
      for (std::size_t i = 0; i < k.pwm.size() && i < g.motors.size(); ++i) g.motors[i] = k.pwm[i];
      return g;
    }
  }
  return g;
}

}  // namespace

const char* ToString(EventKind k) {
  switch (k) {
    case EventKind::kCollision: return "collision";
    case EventKind::kReset: return "reset";
    case EventKind::kLanded: return "landed";
    case EventKind::kTookOff: return "took_off";
  }
  return "?";
}

const DroneModel* World::Find(DroneId id) const {
  auto it = std::lower_bound(drones.begin(), drones.end(), id, [](const DroneModel& d, DroneId v) { return d.id < v; });
  return it != drones.end() && it->id == id ? &*it : nullptr;
}

DroneState* WorldState::Find(DroneId id) {
  auto it = std::lower_bound(drones.begin(), drones.end(), id, [](const DroneState& d, DroneId v) { return d.id < v; });
  return it != drones.end() && it->id == id ? &*it : nullptr;
}
const DroneState* WorldState::Find(DroneId id) const { return const_cast<WorldState*>(this)->Find(id); }

DroneState MakeDroneState(const World& model, const DroneModel& dm) {
  DroneState s;
  s.id = dm.id;
  s.controller.gains = dm.params.gains;
  s.rng = detail::SeedRandom(model.seed, dm.id);
  detail::ResetToSpawn(dm, &s);
  s.landed = LandedState::kLanded;
  return s;
}

void AddDrone(World* model, WorldState* state, DroneId id, const MultirotorParams& params, const Pose& spawn) {
  if (model->Find(id) != nullptr) throw std::invalid_argument("drone " + std::to_string(id) + ": id already exists");
  if (!spawn.position.allFinite() || !spawn.orientation.coeffs().allFinite() || spawn.orientation.norm() < 1e-6) {
    throw std::invalid_argument("drone " + std::to_string(id) + ": spawn pose is not finite");
  }
  DroneModel dm;
  dm.id = id;
  dm.params = params;
  try {
    dm.derived = DeriveParams(params);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("drone " + std::to_string(id) + ": " + e.what());
  }
  dm.spawn = spawn;
  dm.spawn.orientation.normalize();
  auto it = std::lower_bound(model->drones.begin(), model->drones.end(), id,
                             [](const DroneModel& d, DroneId v) { return d.id < v; });
  const auto index = it - model->drones.begin();
  model->drones.insert(it, dm);
  if (state != nullptr) {
    state->drones.insert(state->drones.begin() + index, MakeDroneState(*model, model->drones[index]));
  }
}

bool RemoveDrone(World* model, WorldState* state, DroneId id) {
  auto it = std::find_if(model->drones.begin(), model->drones.end(), [&](const DroneModel& d) { return d.id == id; });
  if (it == model->drones.end()) return false;
  model->drones.erase(it);
  if (state != nullptr) {
    std::erase_if(state->drones, [&](const DroneState& d) { return d.id == id; });
  }
  return true;
}

WorldState MakeState(const World& model) {
  WorldState s;
  for (const DroneModel& dm : model.drones) s.drones.push_back(MakeDroneState(model, dm));
  return s;
}

std::string ValidateCommand(const World& model, const WorldState& state, const Command& c) {
  const DroneModel* dm = model.Find(c.drone);
  const DroneState* ds = state.Find(c.drone);
  const std::string who = "command " + std::to_string(c.id) + " (" + CommandName(c.body) + ") for drone " +
                          std::to_string(c.drone) + ": ";
  if (dm == nullptr || ds == nullptr) return who + "unknown drone id";
  // simple_flight's arm() / disarm() without API control (armDisarm returns False).
  if (!ds->api_control && std::holds_alternative<cmd::Arm>(c.body)) {
    return who + "Vehicle cannot be armed via API because API has not been given control";
  }
  if (!ds->api_control && std::holds_alternative<cmd::Disarm>(c.body)) {
    return who + "Vehicle cannot be disarmed via API because API has not been given control";
  }
  // Without API control a motion command steers nothing, armed or not (StartUnsteered).
  if (NeedsArmed(c.body) && ds->api_control && !ds->armed) return who + "drone is disarmed; arm it first";
  std::string e = ValidateBody(*dm, *ds, c.body);
  return e.empty() ? e : who + e;
}

void Step(const World& model, WorldState* state, const Commands& commands, const Environment& env, double dt) {
  if (!std::isfinite(dt) || dt <= 0) throw std::invalid_argument("Step: dt must be finite and > 0 (got " + Num(dt) + ")");
  if (!(model.physics_dt > 0)) throw std::invalid_argument("Step: model.physics_dt must be > 0");
  if (!(env.air_density > 0) || !env.wind.allFinite() || !std::isfinite(env.turbulence_sigma) ||
      !(env.turbulence_tau > 0)) {
    throw std::invalid_argument("Step: environment has a non-finite wind or a non-positive density/tau");
  }
  if (state->drones.size() != model.drones.size()) {
    throw std::invalid_argument("Step: state has " + std::to_string(state->drones.size()) + " drones, model has " +
                                std::to_string(model.drones.size()));
  }
  state->reports.clear();
  state->events.clear();
  const double t0 = state->time;
  for (const Command& c : commands) {
    std::string why = ValidateCommand(model, *state, c);
    if (!why.empty()) {
      CommandReport r;
      r.id = c.id;
      r.drone = c.drone;
      r.status = CommandStatus::kRejected;
      r.time = t0;
      r.frame = state->frame;
      r.message = std::move(why);
      state->reports.push_back(std::move(r));
      continue;
    }
    const std::size_t i = static_cast<std::size_t>(model.Find(c.drone) - model.drones.data());
    Ctx ctx{model, model.drones[i], state->drones[i], state->reports, state->frame};
    ApplyCommand(ctx, c, t0);
  }
  const int n = std::max(1, static_cast<int>(std::llround(dt / model.physics_dt)));
  const double h = dt / n;
  detail::BuildProximity(model, state, dt);
  const WorldState::Proximity& px = state->proximity;
  const double density_ratio = env.air_density / 1.225;
  for (std::size_t i = 0; i < model.drones.size(); ++i) {
    const DroneModel& dm = model.drones[i];
    DroneState& ds = state->drones[i];
    if (ds.id != dm.id) throw std::invalid_argument("Step: state drones are not in model order");
    Ctx ctx{model, dm, ds, state->reports, state->frame};
    detail::Neighbours near;
    near.proximity = &px;
    if (px.others.size() > 0) {
      near.begin = px.others.data() + px.start[i];
      near.end = px.others.data() + px.start[i + 1];
    }
    for (int k = 0; k < n; ++k) {
      const double t = t0 + k * h;
      const ControlGoal goal = UpdateCommand(ctx, t, h);
      std::array<double, kMaxRotors> motors{};
      const KinematicsView kv{ds.position, ds.orientation, ds.velocity, ds.angular_velocity, ds.grounded};
      ControllerUpdate(dm.params, dm.derived, goal, kv, model.gravity, density_ratio, h, &ds.controller, &motors);
      for (int r = 0; r < kMaxRotors; ++r) ds.rotors[r].command = motors[r];
      const std::uint64_t resets = ds.reset_count;
      detail::PhysicsSubstep(model, dm, &ds, env, near, t, k * h, h, state->frame, &state->events);
      if (ds.reset_count != resets) {
        Finish(ctx, CommandStatus::kCancelled, t + h, "drone reset to spawn: non-finite state");
        ds.command.mode = CommandMode::kIdle;
      }
      CheckDeadline(ctx, t + h);
      CheckUnsteered(ctx, t + h);
    }
  }
  state->time = t0 + dt;
  state->frame += 1;
}

AirSimKinematics ToAirSim(const DroneModel& model, const DroneState& s) {
  AirSimKinematics k;
  k.position = WorldToAirSimPosition(s.position, model.spawn.position);
  k.orientation = EnuFluToNedFrd(s.orientation);
  k.linear_velocity = EnuToNed(s.velocity);
  k.angular_velocity = FluToFrd(s.angular_velocity);
  k.linear_acceleration = EnuToNed(s.acceleration);
  return k;
}

AirSimCollisionInfo ToAirSim(const DroneModel& model, const CollisionInfo& c) {
  AirSimCollisionInfo a;
  a.has_collided = c.has_collided;
  a.normal = EnuToNed(c.normal);
  a.impact_point = WorldToAirSimPosition(c.impact_point, model.spawn.position);
  a.position = WorldToAirSimPosition(c.position, model.spawn.position);
  a.penetration_depth = c.penetration_depth;
  a.time_stamp_ns = static_cast<std::uint64_t>(std::llround(c.time * 1e9));
  a.object_name = std::string(ToString(c.kind)) + (c.kind == ObjectKind::kGround ? "" : "_" + std::to_string(c.object_id));
  a.object_id = c.kind == ObjectKind::kNone ? -1 : static_cast<std::int64_t>(c.object_id);
  a.collision_count = c.collision_count;
  return a;
}

std::uint64_t StateHash(const WorldState& state) {
  std::uint64_t hsh = 0xcbf29ce484222325ull;
  auto mix = [&](const void* data, std::size_t n) {
    const auto* b = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < n; ++i) {
      hsh ^= b[i];
      hsh *= 0x100000001b3ull;
    }
  };
  auto mixd = [&](double v) { mix(&v, sizeof v); };
  auto mixv = [&](const Vec3& v) {
    for (int i = 0; i < 3; ++i) mixd(v[i]);
  };
  auto mixb = [&](bool b) {
    const unsigned char c = b ? 1 : 0;
    mix(&c, 1);
  };
  mix(&state.frame, sizeof state.frame);
  mixd(state.time);
  for (const DroneState& d : state.drones) {
    mix(&d.id, sizeof d.id);
    // Rigid body and rotors.
    mixv(d.position);
    mixv(d.velocity);
    mixv(d.angular_velocity);
    for (int i = 0; i < 4; ++i) mixd(d.orientation.coeffs()[i]);
    for (const RotorState& r : d.rotors) {
      mixd(r.command);
      mixd(r.signal);
    }
    mixb(d.armed);
    mixb(d.api_control);
    mix(&d.unsteered.id, sizeof d.unsteered.id);
    mixb(d.unsteered.running);
    mix(&d.unsteered.ends, sizeof d.unsteered.ends);
    mixd(d.unsteered.end_time);
    mixd(d.unsteered.still_since);
    mix(&d.unsteered.resume, sizeof d.unsteered.resume);
    mixd(d.unsteered.start_time);
    mixb(d.grounded);
    mix(&d.carrier, sizeof d.carrier);
    mixv(d.carrier_offset);
    mixd(d.carrier_yaw);
    mix(&d.landed, sizeof d.landed);
    mixd(d.last_support_time);
    mixv(d.support_velocity);
    for (const auto& t : d.touching) {
      mix(&t.kind, sizeof t.kind);
      mix(&t.id, sizeof t.id);
      mixd(t.time);
    }
    mix(&d.collision.collision_count, sizeof d.collision.collision_count);
    mix(&d.reset_count, sizeof d.reset_count);
    // Controller memory and gains.
    const ControllerState& cs = d.controller;
    const ControllerGains& g = cs.gains;
    for (const Vec3* v : {&g.angle_rate_p, &g.angle_rate_i, &g.angle_rate_d, &g.angle_level_p}) mixv(*v);
    for (double v : {g.max_angle_rate, g.max_tilt, g.velocity_p_xy, g.velocity_i_xy, g.velocity_p_z, g.velocity_i_z,
                     g.max_velocity, g.min_throttle, g.position_p_xy, g.position_p_z, g.integrator_limit, g.altitude_gain}) {
      mixd(v);
    }
    mixd(cs.yaw_ref);
    mixd(cs.vz_integral);
    mixv(cs.vxy_integral);
    mixv(cs.rate_integral);
    mixv(cs.prev_rate_error);
    mixb(cs.has_prev_rate_error);
    // Active command (its body is summarised by its id, mode and reference state).
    const ActiveCommand& ac = d.command;
    mix(&ac.id, sizeof ac.id);
    mix(&ac.mode, sizeof ac.mode);
    mixb(ac.running);
    const std::size_t body_index = ac.body.index();
    mix(&body_index, sizeof body_index);
    mixd(ac.start_time);
    mixd(ac.end_time);
    for (const Vec3& pt : ac.path) mixv(pt);
    mixd(ac.s);
    mixd(ac.s_dot);
    mix(&ac.segment, sizeof ac.segment);
    mixd(ac.speed);
    mixd(ac.lookahead);
    mixd(ac.adaptive_lookahead);
    mixv(ac.velocity);
    mixv(ac.target);
    mixd(ac.landed_since);
    // Turbulence and the random generator.
    mixv(d.gust);
    for (std::uint64_t w : d.rng.s) mix(&w, sizeof w);
  }
  return hsh;
}

}  // namespace lockstep::air
