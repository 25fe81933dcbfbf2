#include "lockstep/air/commands.h"

namespace lockstep::air {

const char* ToString(CommandStatus s) {
  switch (s) {
    case CommandStatus::kRunning: return "RUNNING";
    case CommandStatus::kCompleted: return "COMPLETED";
    case CommandStatus::kTimedOut: return "TIMED_OUT";
    case CommandStatus::kCancelled: return "CANCELLED";
    case CommandStatus::kRejected: return "REJECTED";
  }
  return "?";
}

namespace {
template <class... Ts>
struct Overloaded : Ts... {
  using Ts::operator()...;
};
template <class... Ts>
Overloaded(Ts...) -> Overloaded<Ts...>;
}  // namespace

const char* CommandName(const CommandBody& body) {
  return std::visit(
      Overloaded{
          [](const cmd::Arm&) { return "arm"; },
          [](const cmd::Disarm&) { return "disarm"; },
          [](const cmd::Takeoff&) { return "takeoff"; },
          [](const cmd::Land&) { return "land"; },
          [](const cmd::Hover&) { return "hover"; },
          [](const cmd::GoHome&) { return "go_home"; },
          [](const cmd::MoveToPosition&) { return "move_to_position"; },
          [](const cmd::MoveOnPath&) { return "move_on_path"; },
          [](const cmd::TrackTarget&) { return "track_target"; },
          [](const cmd::MoveByVelocity&) { return "move_by_velocity"; },
          [](const cmd::MoveByVelocityZ&) { return "move_by_velocity_z"; },
          [](const cmd::MoveByRollPitchYawThrottle&) { return "move_by_roll_pitch_yaw_throttle"; },
          [](const cmd::MoveByRollPitchYawZ&) { return "move_by_roll_pitch_yaw_z"; },
          [](const cmd::MoveByRollPitchYawrateThrottle&) { return "move_by_roll_pitch_yawrate_throttle"; },
          [](const cmd::MoveByAngleRatesThrottle&) { return "move_by_angle_rates_throttle"; },
          [](const cmd::MoveByAngleRatesZ&) { return "move_by_angle_rates_z"; },
          [](const cmd::MoveByMotorPwms&) { return "move_by_motor_pwms"; },
          [](const cmd::RotateToYaw&) { return "rotate_to_yaw"; },
          [](const cmd::RotateByYawRate&) { return "rotate_by_yaw_rate"; },
          [](const cmd::SetGains&) { return "set_gains"; },
          [](const cmd::SetPose&) { return "set_pose"; },
          [](const cmd::MoveToZ&) { return "move_to_z"; },
          [](const cmd::MoveByRollPitchYawrateZ&) { return "move_by_roll_pitch_yawrate_z"; },
          [](const cmd::SetKinematics&) { return "set_kinematics"; },
          [](const cmd::SetApiControl&) { return "set_api_control"; },
      },
      body);
}

bool IsMotionCommand(const CommandBody& body) {
  return !(std::holds_alternative<cmd::Arm>(body) || std::holds_alternative<cmd::Disarm>(body) ||
           std::holds_alternative<cmd::SetGains>(body) || std::holds_alternative<cmd::SetApiControl>(body));
}

}  // namespace lockstep::air
