#include "lockstep/client/multirotor.h"

#include <cmath>

namespace lockstep::client {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

struct Q {
  double w, x, y, z;
};
Q Mul(const Q& a, const Q& b) {
  return {a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z, a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
          a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x, a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w};
}
// ENU -> NED world axes (180 deg about (1,1,0)/sqrt2) and FLU <-> FRD body axes (180 deg about x).
const Q kWorld{0, std::sqrt(0.5), std::sqrt(0.5), 0};
const Q kBody{0, 1, 0, 0};

Ned FluToFrd(const msg::Vector3& v) { return {v.x(), -v.y(), -v.z()}; }
Ned EnuVecToNed(const msg::Vector3& v) { return {v.y(), v.x(), -v.z()}; }

double Timeout(double t) { return t >= 1e30 ? 0 : t; }  // AirSim's 3e38 = none

msg::YawMode ToYaw(const NedYawMode& y) {
  msg::YawMode m;
  m.is_rate(y.is_rate);
  m.value(y.is_rate ? -y.yaw_or_rate * kDeg : NedYawDegToEnu(y.yaw_or_rate));
  return m;
}

msg::Drivetrain ToDrive(NedDrivetrain d) {
  return d == NedDrivetrain::kForwardOnly ? msg::Drivetrain::DRIVETRAIN_FORWARD_ONLY
                                          : msg::Drivetrain::DRIVETRAIN_MAX_DEGREE_OF_FREEDOM;
}

msg::Vector3 V(double x, double y, double z) {
  msg::Vector3 v;
  v.x(x);
  v.y(y);
  v.z(z);
  return v;
}

}  // namespace

Ned EnuToNed(const msg::Vector3& enu, const msg::Vector3& home) {
  return {enu.y() - home.y(), enu.x() - home.x(), -(enu.z() - home.z())};
}

msg::Vector3 NedToEnu(const Ned& ned, const msg::Vector3& home) { return V(home.x() + ned.y, home.y() + ned.x, home.z() - ned.z); }

NedQuaternion EnuToNedQuaternion(const msg::Quaternion& q) {
  const Q r = Mul(Mul(kWorld, Q{q.w(), q.x(), q.y(), q.z()}), kBody);
  const double s = r.w < 0 ? -1 : 1;  // keep w >= 0
  return {s * r.w, s * r.x, s * r.y, s * r.z};
}

msg::Quaternion NedToEnuQuaternion(const NedQuaternion& q) {
  const Q r = Mul(Mul(kWorld, Q{q.w, q.x, q.y, q.z}), kBody);
  const double s = r.w < 0 ? -1 : 1;
  msg::Quaternion out;
  out.w(s * r.w);
  out.x(s * r.x);
  out.y(s * r.y);
  out.z(s * r.z);
  return out;
}

double NedYawDegToEnu(double deg) { return kPi / 2 - deg * kDeg; }
double EnuYawToNedDeg(double rad) { return 90.0 - rad / kDeg; }

msg::DroneCommandStatus CommandFuture::status(double timeout_s) {
  if (!done_) {
    if (client_ == nullptr) throw ClientError("join(): this future belongs to no command");
    done_ = client_->wait_drone(actor_, id_, timeout_s);
  }
  return *done_;
}

bool CommandFuture::join(double timeout_s) {
  const msg::DroneCommandStatus s = status(timeout_s);
  if (s == msg::DroneCommandStatus::DRONE_CMD_REJECTED) {
    // As AirSim, whose join() raises the server's exception: the reason is air_sim's.
    std::string why = client_->drone_failure(actor_, id_, 2.0);
    if (why.empty()) why = "no reason received";
    throw CommandRejected("drone " + std::to_string(actor_) + ": command rejected by air_sim: " + why, why);
  }
  return s == msg::DroneCommandStatus::DRONE_CMD_COMPLETED;
}

uint32_t MultirotorClient::Resolve(const std::string& vehicle_name) const {
  std::vector<ActorInfo> drones;
  for (const auto& a : client_.actors()) {
    if (a.kind == msg::ActorKind::ACTOR_DRONE) drones.push_back(a);
  }
  for (const auto& a : drones) {
    if (vehicle_name.empty() || a.Attribute("role_name") == vehicle_name || "Drone" + std::to_string(a.id) == vehicle_name) {
      return a.id;
    }
  }
  if (vehicle_name.empty()) throw ClientError("no drone in the simulation (spawn one, or call simAddVehicle)");
  std::string names;
  for (const auto& a : drones) names += (names.empty() ? "" : ", ") + a.Attribute("role_name", "Drone" + std::to_string(a.id));
  throw ClientError("no vehicle named '" + vehicle_name + "' (drones: " + (names.empty() ? "none" : names) + ")");
}

std::vector<std::string> MultirotorClient::listVehicles() const {
  std::vector<std::string> out;
  for (const auto& a : client_.actors()) {
    if (a.kind == msg::ActorKind::ACTOR_DRONE) out.push_back(a.Attribute("role_name", "Drone" + std::to_string(a.id)));
  }
  return out;
}

uint32_t MultirotorClient::addVehicle(const std::string& name, const std::string& blueprint, const msg::Pose& pose) {
  // AirSim's vehicles start without API control (enableApiControl takes it).
  return client_.spawn(blueprint, pose, {{"role_name", name}, {"api_control", "false"}});
}

// API control is the vehicle's (air_sim's DroneState.api_control), whichever client or process
// takes it, as AirSim's server holds it. Until the tick that carries this client's request is
// in the air state, the request is the answer (AirSim's call returns once the server has it).
void MultirotorClient::enableApiControl(bool enabled, const std::string& vehicle) {
  const uint32_t id = Resolve(vehicle);
  msg::DroneCommand c = MakeUnchecked(id, msg::DroneCommandKind::DRONE_SET_API_CONTROL);
  c.values(std::vector<double>{enabled ? 1.0 : 0.0});
  c.command_id(0);  // no future waits on it: it must not look like the end of the running command
  msg::CommandBody b;
  b.drone(c);
  const msg::CommandReply r = client_.Submit(std::move(b));
  std::lock_guard<std::mutex> lock(api_mu_);
  api_pending_[id] = PendingApiControl{enabled, r.run(), r.frame()};
}

bool MultirotorClient::isApiControlEnabled(const std::string& vehicle) const {
  const uint32_t id = Resolve(vehicle);
  const Snapshot snap = client_.snapshot();
  const msg::DroneState* d = snap.Drone(id);
  {
    std::lock_guard<std::mutex> lock(api_mu_);
    auto it = api_pending_.find(id);
    if (it != api_pending_.end()) {
      const bool same_run = snap.air && snap.air->stamp().run() == it->second.run;
      if (same_run && (d == nullptr || snap.air->stamp().frame() < it->second.frame)) return it->second.enabled;
      api_pending_.erase(it);
    }
  }
  return d != nullptr && d->api_control();
}

msg::DroneState MultirotorClient::State(uint32_t actor) const {
  auto s = client_.drone_state(actor);
  if (!s) {
    throw ClientError("drone " + std::to_string(actor) + " has no state yet (is air_sim running? in synchronous mode, tick once after spawning)");
  }
  return *s;
}

// Without API control air_sim applies AirSim's rules (arm and disarm refused, a move steers
// nothing and runs out its duration or timeout): no client-side check.
msg::DroneCommand MultirotorClient::Make(uint32_t actor, msg::DroneCommandKind kind) const { return MakeUnchecked(actor, kind); }

msg::DroneCommand MultirotorClient::MakeUnchecked(uint32_t actor, msg::DroneCommandKind kind) const {
  msg::DroneCommand c;
  c.actor(actor);
  c.kind(kind);
  msg::YawMode keep;
  keep.is_rate(true);
  keep.value(0);
  c.yaw(keep);
  return c;
}

CommandFuture MultirotorClient::Send(uint32_t actor, msg::DroneCommand cmd) {
  const uint64_t id = client_.send_drone(std::move(cmd));
  return CommandFuture(&client_, actor, id);
}

// simple_flight's arm() / disarm() answer false, never raise: without API control air_sim
// refuses them (its reason is in the log and the drone's failure events).
bool MultirotorClient::armDisarm(bool arm, const std::string& vehicle) {
  const uint32_t id = Resolve(vehicle);
  try {
    return Send(id, Make(id, arm ? msg::DroneCommandKind::DRONE_ARM : msg::DroneCommandKind::DRONE_DISARM)).join();
  } catch (const CommandRejected& e) {
    if (e.reason().find("API has not been given control") == std::string::npos) throw;
    return false;
  }
}

CommandFuture MultirotorClient::takeoffAsync(double timeout_s, const std::string& vehicle) {
  const uint32_t id = Resolve(vehicle);
  auto c = Make(id, msg::DroneCommandKind::DRONE_TAKEOFF);
  c.timeout(Timeout(timeout_s));
  return Send(id, c);
}

CommandFuture MultirotorClient::landAsync(double timeout_s, const std::string& vehicle) {
  const uint32_t id = Resolve(vehicle);
  auto c = Make(id, msg::DroneCommandKind::DRONE_LAND);
  c.timeout(Timeout(timeout_s));
  return Send(id, c);
}

CommandFuture MultirotorClient::goHomeAsync(double timeout_s, const std::string& vehicle) {
  const uint32_t id = Resolve(vehicle);
  auto c = Make(id, msg::DroneCommandKind::DRONE_GO_HOME);
  c.timeout(Timeout(timeout_s));
  c.velocity(5);  // AirSim's goHome speed
  return Send(id, c);
}

CommandFuture MultirotorClient::hoverAsync(const std::string& vehicle) {
  const uint32_t id = Resolve(vehicle);
  return Send(id, Make(id, msg::DroneCommandKind::DRONE_HOVER));
}

CommandFuture MultirotorClient::moveToPositionAsync(double x, double y, double z, double velocity, double timeout_s,
                                                    NedDrivetrain drivetrain, NedYawMode yaw, double lookahead,
                                                    const std::string& vehicle) {
  const uint32_t id = Resolve(vehicle);
  auto c = Make(id, msg::DroneCommandKind::DRONE_MOVE_TO_POSITION);
  c.target(NedToEnu({x, y, z}, homeEnu(vehicle)));
  c.velocity(velocity);
  c.timeout(Timeout(timeout_s));
  c.drivetrain(ToDrive(drivetrain));
  c.yaw(ToYaw(yaw));
  c.lookahead(lookahead);
  return Send(id, c);
}

CommandFuture MultirotorClient::moveToZAsync(double z, double velocity, double timeout_s, NedYawMode yaw, double lookahead,
                                             const std::string& vehicle) {
  const uint32_t id = Resolve(vehicle);
  auto c = Make(id, msg::DroneCommandKind::DRONE_MOVE_TO_Z);
  c.target(V(0, 0, homeEnu(vehicle).z() - z));  // only z counts: air_sim holds the horizontal position
  c.velocity(velocity);
  c.timeout(Timeout(timeout_s));
  c.yaw(ToYaw(yaw));
  c.lookahead(lookahead);
  return Send(id, c);
}

CommandFuture MultirotorClient::moveOnPathAsync(const std::vector<Ned>& path, double velocity, double timeout_s,
                                                NedDrivetrain drivetrain, NedYawMode yaw, double lookahead,
                                                const std::string& vehicle) {
  const uint32_t id = Resolve(vehicle);
  auto c = Make(id, msg::DroneCommandKind::DRONE_MOVE_ON_PATH);
  const msg::Vector3 home = homeEnu(vehicle);
  std::vector<msg::Vector3> enu;
  for (const auto& p : path) enu.push_back(NedToEnu(p, home));
  c.path(enu);
  c.velocity(velocity);
  c.timeout(Timeout(timeout_s));
  c.drivetrain(ToDrive(drivetrain));
  c.yaw(ToYaw(yaw));
  c.lookahead(lookahead);
  return Send(id, c);
}

CommandFuture MultirotorClient::moveByVelocityAsync(double vx, double vy, double vz, double duration, NedDrivetrain drivetrain,
                                                    NedYawMode yaw, const std::string& vehicle) {
  const uint32_t id = Resolve(vehicle);
  auto c = Make(id, msg::DroneCommandKind::DRONE_MOVE_BY_VELOCITY);
  c.target(V(vy, vx, -vz));
  c.duration(duration);
  c.drivetrain(ToDrive(drivetrain));
  c.yaw(ToYaw(yaw));
  return Send(id, c);
}

CommandFuture MultirotorClient::moveByVelocityBodyFrameAsync(double vx, double vy, double vz, double duration,
                                                             NedDrivetrain drivetrain, NedYawMode yaw,
                                                             const std::string& vehicle) {
  const uint32_t id = Resolve(vehicle);
  auto c = Make(id, msg::DroneCommandKind::DRONE_MOVE_BY_VELOCITY);
  c.target(V(vx, -vy, -vz));  // body FRD -> FLU
  c.body_frame(true);
  c.duration(duration);
  c.drivetrain(ToDrive(drivetrain));
  c.yaw(ToYaw(yaw));
  return Send(id, c);
}

CommandFuture MultirotorClient::moveByVelocityZAsync(double vx, double vy, double z, double duration, NedDrivetrain drivetrain,
                                                     NedYawMode yaw, const std::string& vehicle) {
  const uint32_t id = Resolve(vehicle);
  auto c = Make(id, msg::DroneCommandKind::DRONE_MOVE_BY_VELOCITY_Z);
  c.target(V(vy, vx, homeEnu(vehicle).z() - z));
  c.duration(duration);
  c.drivetrain(ToDrive(drivetrain));
  c.yaw(ToYaw(yaw));
  return Send(id, c);
}

CommandFuture MultirotorClient::rotateToYawAsync(double yaw_deg, double timeout_s, double margin_deg, const std::string& vehicle) {
  const uint32_t id = Resolve(vehicle);
  auto c = Make(id, msg::DroneCommandKind::DRONE_ROTATE_TO_YAW);
  msg::YawMode y;
  y.is_rate(false);
  y.value(NedYawDegToEnu(yaw_deg));
  c.yaw(y);
  c.timeout(Timeout(timeout_s));
  c.margin(margin_deg * kDeg);
  return Send(id, c);
}

CommandFuture MultirotorClient::rotateByYawRateAsync(double yaw_rate_deg, double duration, const std::string& vehicle) {
  const uint32_t id = Resolve(vehicle);
  auto c = Make(id, msg::DroneCommandKind::DRONE_ROTATE_BY_YAW_RATE);
  msg::YawMode y;
  y.is_rate(true);
  y.value(-yaw_rate_deg * kDeg);
  c.yaw(y);
  c.duration(duration);
  return Send(id, c);
}

CommandFuture MultirotorClient::moveByRollPitchYawThrottleAsync(double roll, double pitch, double yaw, double throttle,
                                                                double duration, const std::string& vehicle) {
  const uint32_t id = Resolve(vehicle);
  auto c = Make(id, msg::DroneCommandKind::DRONE_MOVE_BY_ROLL_PITCH_YAW_THROTTLE);
  c.values({roll, -pitch, kPi / 2 - yaw, throttle});
  c.duration(duration);
  return Send(id, c);
}

CommandFuture MultirotorClient::moveByRollPitchYawZAsync(double roll, double pitch, double yaw, double z, double duration,
                                                         const std::string& vehicle) {
  const uint32_t id = Resolve(vehicle);
  auto c = Make(id, msg::DroneCommandKind::DRONE_MOVE_BY_ROLL_PITCH_YAW_Z);
  c.values({roll, -pitch, kPi / 2 - yaw, homeEnu(vehicle).z() - z});
  c.duration(duration);
  return Send(id, c);
}

CommandFuture MultirotorClient::moveByAngleRatesThrottleAsync(double roll_rate, double pitch_rate, double yaw_rate,
                                                              double throttle, double duration, const std::string& vehicle) {
  const uint32_t id = Resolve(vehicle);
  auto c = Make(id, msg::DroneCommandKind::DRONE_MOVE_BY_ANGLE_RATES_THROTTLE);
  c.values({roll_rate, -pitch_rate, -yaw_rate, throttle});
  c.duration(duration);
  return Send(id, c);
}

CommandFuture MultirotorClient::moveByMotorPWMsAsync(const std::vector<double>& pwms, double duration, const std::string& vehicle) {
  const uint32_t id = Resolve(vehicle);
  auto c = Make(id, msg::DroneCommandKind::DRONE_MOVE_BY_MOTOR_PWMS);
  c.values(pwms);
  c.duration(duration);
  return Send(id, c);
}

CommandFuture MultirotorClient::moveByRollPitchYawrateThrottleAsync(double roll, double pitch, double yaw_rate, double throttle,
                                                                    double duration, const std::string& vehicle) {
  const uint32_t id = Resolve(vehicle);
  auto c = Make(id, msg::DroneCommandKind::DRONE_MOVE_BY_ROLL_PITCH_YAWRATE_THROTTLE);
  c.values({roll, -pitch, -yaw_rate, throttle});  // FRD -> FLU
  c.duration(duration);
  return Send(id, c);
}

CommandFuture MultirotorClient::moveByRollPitchYawrateZAsync(double roll, double pitch, double yaw_rate, double z,
                                                             double duration, const std::string& vehicle) {
  const uint32_t id = Resolve(vehicle);
  auto c = Make(id, msg::DroneCommandKind::DRONE_MOVE_BY_ROLL_PITCH_YAWRATE_Z);
  c.values({roll, -pitch, -yaw_rate, homeEnu(vehicle).z() - z});
  c.duration(duration);
  return Send(id, c);
}

CommandFuture MultirotorClient::moveByAngleRatesZAsync(double roll_rate, double pitch_rate, double yaw_rate, double z,
                                                       double duration, const std::string& vehicle) {
  const uint32_t id = Resolve(vehicle);
  auto c = Make(id, msg::DroneCommandKind::DRONE_MOVE_BY_ANGLE_RATES_Z);
  c.values({roll_rate, -pitch_rate, -yaw_rate, homeEnu(vehicle).z() - z});
  c.duration(duration);
  return Send(id, c);
}

CommandFuture MultirotorClient::moveToGPSAsync(double latitude, double longitude, double altitude, double velocity,
                                               double timeout_s, NedDrivetrain drivetrain, NedYawMode yaw, double lookahead,
                                               double adaptive_lookahead, const std::string& vehicle) {
  const uint32_t id = Resolve(vehicle);
  auto c = Make(id, msg::DroneCommandKind::DRONE_MOVE_TO_GPS);
  c.values({latitude, longitude, altitude});
  c.velocity(velocity);
  c.timeout(Timeout(timeout_s));
  c.drivetrain(ToDrive(drivetrain));
  c.yaw(ToYaw(yaw));
  c.lookahead(lookahead);
  c.adaptive_lookahead(adaptive_lookahead > 0 ? adaptive_lookahead : -1);  // AirSim's 0 = off; the wire's 0 = default
  return Send(id, c);
}

void MultirotorClient::setControllerGains(msg::GainsLoop loop, const Pid& a, const Pid& b, const Pid& c,
                                          const std::string& vehicle) {
  const uint32_t id = Resolve(vehicle);
  const bool linear = loop == msg::GainsLoop::GAINS_VELOCITY || loop == msg::GainsLoop::GAINS_POSITION;
  if (linear && (a.kp != b.kp || a.ki != b.ki || a.kd != b.kd)) {
    throw ClientError("set*ControllerGains: air_sim has one horizontal gain for x and y; give both the same PID");
  }
  auto cmd = Make(id, msg::DroneCommandKind::DRONE_SET_GAINS);
  cmd.gains_loop(loop);
  // Angle loops: roll, pitch, yaw are the same axes in FRD and FLU (gains, not signs);
  // linear loops: x, y (north, east) -> one horizontal gain, z -> z.
  msg::PidGains g;
  g.kp(V(a.kp, b.kp, c.kp));
  g.ki(V(a.ki, b.ki, c.ki));
  g.kd(V(a.kd, b.kd, c.kd));
  cmd.gains(g);
  Send(id, cmd);  // takes effect with the next tick, like every command
}

void MultirotorClient::simSetWind(const Ned& wind) {
  // The wind is every drone's and AirSim's simSetWind needs no API control, so any drone carries
  // the command (the first one may be a drone this client never enabled).
  const uint32_t id = Resolve("");
  auto c = MakeUnchecked(id, msg::DroneCommandKind::DRONE_SET_WIND);
  c.target(V(wind.y, wind.x, -wind.z));
  Send(id, c);
}

void MultirotorClient::simSetKinematics(const NedKinematics& state, const std::string& vehicle) {
  const uint32_t id = Resolve(vehicle);
  auto c = Make(id, msg::DroneCommandKind::DRONE_SET_KINEMATICS);
  c.target(NedToEnu(state.position, homeEnu(vehicle)));
  const msg::Quaternion q = NedToEnuQuaternion(state.orientation);
  const Ned& v = state.linear_velocity;
  const Ned& w = state.angular_velocity;
  c.values({q.w(), q.x(), q.y(), q.z(), v.y, v.x, -v.z, w.x, -w.y, -w.z});
  Send(id, c);
}

CommandFuture MultirotorClient::trackTargetAsync(const Ned& position, const Ned& velocity, double max_speed, double duration,
                                                 const std::string& vehicle) {
  const uint32_t id = Resolve(vehicle);
  auto c = Make(id, msg::DroneCommandKind::DRONE_TRACK_TARGET);
  c.target(NedToEnu(position, homeEnu(vehicle)));
  c.values({velocity.y, velocity.x, -velocity.z});
  c.velocity(max_speed);
  c.duration(duration);
  return Send(id, c);
}

void MultirotorClient::cancelLastTask(const std::string& vehicle) {
  const uint32_t id = Resolve(vehicle);
  Send(id, Make(id, msg::DroneCommandKind::DRONE_CANCEL));
}

msg::Vector3 MultirotorClient::homeEnu(const std::string& vehicle) const { return State(Resolve(vehicle)).home_pose().position(); }

MultirotorStateNed MultirotorClient::getMultirotorState(const std::string& vehicle) const {
  const msg::DroneState d = State(Resolve(vehicle));
  const msg::Vector3 home = d.home_pose().position();
  MultirotorStateNed s;
  s.kinematics.position = EnuToNed(d.transform().position(), home);
  s.kinematics.orientation = EnuToNedQuaternion(d.transform().orientation());
  s.kinematics.linear_velocity = EnuVecToNed(d.linear_velocity());
  s.kinematics.linear_acceleration = EnuVecToNed(d.linear_acceleration());
  s.kinematics.angular_velocity = FluToFrd(d.angular_velocity());
  s.kinematics.angular_acceleration = FluToFrd(d.angular_acceleration());
  s.collision = simGetCollisionInfo(vehicle);
  s.landed = d.landed() == msg::LandedState::LANDED_LANDED;
  s.armed = d.armed();
  const Snapshot snap = client_.snapshot();
  s.frame = snap.air ? snap.air->stamp().frame() : 0;
  s.timestamp_ns = snap.air ? snap.air->stamp().sim_time() * 1e9 : 0;
  for (const auto& r : d.rotors()) {
    s.rotor_speeds.push_back(r.speed());
    s.rotor_thrusts.push_back(r.thrust());
    s.rotor_controls.push_back(r.control());
  }
  return s;
}

NedCollision MultirotorClient::simGetCollisionInfo(const std::string& vehicle) const {
  const msg::DroneState d = State(Resolve(vehicle));
  const msg::Vector3 home = d.home_pose().position();
  const auto& c = d.collision();
  NedCollision out;
  out.has_collided = c.has_collided();
  out.normal = EnuVecToNed(c.normal());
  out.impact_point = EnuToNed(c.impact_point(), home);
  out.position = EnuToNed(d.transform().position(), home);
  out.penetration_depth = c.penetration_depth();
  out.object_id = c.other_actor();
  switch (c.other_kind()) {
    case msg::ObjectKind::OBJECT_GROUND: out.object_name = "ground"; break;
    case msg::ObjectKind::OBJECT_STATIC: out.object_name = "static"; break;
    case msg::ObjectKind::OBJECT_VEHICLE: out.object_name = "vehicle"; break;
    case msg::ObjectKind::OBJECT_WALKER: out.object_name = "walker"; break;
    case msg::ObjectKind::OBJECT_DRONE: out.object_name = "drone"; break;
    case msg::ObjectKind::OBJECT_NONE: break;
  }
  out.frame = c.frame();
  return out;
}

std::pair<Ned, NedQuaternion> MultirotorClient::simGetVehiclePose(const std::string& vehicle) const {
  const msg::DroneState d = State(Resolve(vehicle));
  return {EnuToNed(d.transform().position(), d.home_pose().position()), EnuToNedQuaternion(d.transform().orientation())};
}

void MultirotorClient::simSetVehiclePose(const Ned& position, const NedQuaternion& orientation, const std::string& vehicle) {
  const uint32_t id = Resolve(vehicle);
  msg::SetTransform t;
  t.actor(id);
  msg::Pose p;
  p.position(NedToEnu(position, homeEnu(vehicle)));
  p.orientation(NedToEnuQuaternion(orientation));
  t.transform(p);
  msg::CommandBody b;
  b.set_transform(t);
  client_.Submit(std::move(b));
}

}  // namespace lockstep::client
