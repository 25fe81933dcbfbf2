// Ray-cast suspension vehicle: one rigid chassis, four wheels as rays against the town
// with spring-damper suspension and a slip-angle tyre inside the friction circle.
// (Measured against ODE hinge-2 jointed wheels in bench/ground: see docs/ground.md.)
#include <algorithm>
#include <cmath>

#include "internal.h"

namespace lockstep::ground {
namespace {

constexpr double kCorneringStiffness = 8.0;  // lateral force per unit load per rad of slip
constexpr double kRollCentreLift = 0.3;      // m above the contact where tyre forces act
constexpr double kDrivelineEfficiency = 0.9;

struct RayHit {
  bool hit = false;
  double distance = 0;
  Vec3 normal = Vec3::UnitZ();
};

struct WheelRay {
  RayHit* out;
};

void WheelRayCallback(void* data, dGeomID o1, dGeomID o2) {
  auto* hit = static_cast<WheelRay*>(data)->out;
  dContactGeom c[4];
  const int n = dCollide(o1, o2, 4, c, sizeof(dContactGeom));
  for (int i = 0; i < n; ++i) {
    if (!hit->hit || c[i].depth < hit->distance) {
      hit->hit = true;
      hit->distance = c[i].depth;
      hit->normal = Vec3(c[i].normal[0], c[i].normal[1], c[i].normal[2]);
    }
  }
}

double EngineTorque(const VehiclePhysics& p, double rpm) {
  if (rpm >= p.max_rpm) return 0;
  const auto& c = p.torque_curve;
  if (c.empty()) return 0;
  if (rpm <= c.front().first) return c.front().second;
  for (size_t i = 1; i < c.size(); ++i) {
    if (rpm <= c[i].first) {
      const double t = (rpm - c[i - 1].first) / std::max(1e-9, c[i].first - c[i - 1].first);
      return c[i - 1].second + t * (c[i].second - c[i - 1].second);
    }
  }
  return c.back().second;
}

double GearRatio(const VehiclePhysics& p, int gear) {
  if (gear < 0) return -p.forward_gears.front().ratio;
  if (gear == 0) return 0;
  return p.forward_gears[static_cast<size_t>(std::min<int>(gear, static_cast<int>(p.forward_gears.size())) - 1)].ratio;
}

}  // namespace

void World::Impl::UpdateGear(VehicleActor* v, double h) {
  const VehiclePhysics& p = v->physics;
  if (v->control.manual_gear_shift) {
    v->gear = std::clamp(v->control.gear, -1, static_cast<int>(p.forward_gears.size()));
    return;
  }
  if (v->control.reverse) {
    v->gear = -1;
    return;
  }
  if (v->gear <= 0) v->gear = 1;
  if (v->gear_timer > 0) {
    v->gear_timer -= h;
    return;
  }
  const Pose pose = BodyPose(v->body);
  const double speed = std::abs((pose.orientation * Vec3::UnitX()).dot(ToVec(dBodyGetLinearVel(v->body))));
  const double rpm = speed / p.wheel_radius * GearRatio(p, v->gear) * p.final_ratio * 60 / (2 * M_PI);
  const GearSpec& g = p.forward_gears[static_cast<size_t>(v->gear - 1)];
  if (rpm > g.up_ratio * p.max_rpm && v->gear < static_cast<int>(p.forward_gears.size())) {
    ++v->gear;
    v->gear_timer = p.gear_switch_time;
  } else if (v->gear > 1 && rpm < g.down_ratio * p.max_rpm * GearRatio(p, v->gear) / GearRatio(p, v->gear - 1)) {
    --v->gear;
  }
}

void World::Impl::AckermannToControl(VehicleActor* v, double h) {
  const AckermannControl& a = v->ackermann;
  const double target = std::clamp(a.steer, -v->physics.max_steer_angle, v->physics.max_steer_angle);
  if (a.steer_speed > 0) {
    const double step = a.steer_speed * h;
    v->steer_angle += std::clamp(target - v->steer_angle, -step, step);
  } else {
    v->steer_angle = target;
  }
  v->control.steer = std::clamp(-v->steer_angle / v->physics.max_steer_angle, -1.0, 1.0);
  const Pose pose = BodyPose(v->body);
  const double speed = (pose.orientation * Vec3::UnitX()).dot(ToVec(dBodyGetLinearVel(v->body)));
  const bool reverse = a.speed < 0;
  const double err = (reverse ? -1 : 1) * (a.speed - speed);  // > 0: must speed up in the travel direction
  v->ackermann_integral = std::clamp(v->ackermann_integral + 0.2 * err * h, -0.3, 0.3);
  double drive = 0.35 * err + v->ackermann_integral;
  if (a.acceleration > 0) drive = std::clamp(drive, -a.acceleration / 9.81, a.acceleration / 9.81);
  v->control.reverse = reverse;
  v->control.manual_gear_shift = false;
  v->control.hand_brake = false;
  if (std::abs(a.speed) < 0.05 && std::abs(speed) < 0.3) {
    v->control.throttle = 0;
    v->control.brake = 1;
  } else if (drive >= 0) {
    v->control.throttle = std::clamp(drive, 0.0, 1.0);
    v->control.brake = 0;
  } else {
    v->control.throttle = 0;
    v->control.brake = std::clamp(-drive, 0.0, 1.0);
  }
}

void World::Impl::ApplyWheelForces(VehicleActor* v, double h) {
  const VehiclePhysics& p = v->physics;
  const Vec3 half = v->spec->half_extents;
  const Pose pose = BodyPose(v->body);
  const Eigen::Matrix3d R = pose.orientation.toRotationMatrix();
  const Vec3 up = R.col(2), fwd = R.col(0);
  const Vec3 vel = ToVec(dBodyGetLinearVel(v->body));
  const Vec3 omega = ToVec(dBodyGetAngularVel(v->body));
  const double wheel_mass = p.mass / 4.0;
  const double travel = p.suspension_travel;
  const double ray_len = p.wheel_radius + travel;

  // Steering: bicycle angle from the control (CARLA: steer > 0 turns right), then
  // Ackermann geometry for the inner and outer front wheel.
  if (!v->use_ackermann) v->steer_angle = -v->control.steer * p.max_steer_angle;
  const double delta = v->steer_angle;
  double steer_left = delta, steer_right = delta;
  if (std::abs(delta) > 1e-4) {
    const double radius = p.wheelbase / std::tan(delta);  // signed, + = turning left
    steer_left = std::atan(p.wheelbase / (radius - p.track / 2));
    steer_right = std::atan(p.wheelbase / (radius + p.track / 2));
  }

  const double long_speed = fwd.dot(vel);
  const int gear = v->gear;
  const double ratio = GearRatio(p, gear) * p.final_ratio;
  double rpm = std::abs(long_speed) / p.wheel_radius * std::abs(ratio) * 60 / (2 * M_PI);
  rpm = std::max(rpm, 1000.0);  // the clutch slips below idle
  const bool shifting = v->gear_timer > 0 && !v->control.manual_gear_shift;
  double drive_total = 0;
  if (!shifting && ratio != 0) drive_total = v->control.throttle * EngineTorque(p, rpm) * ratio * kDrivelineEfficiency / p.wheel_radius;

  // Aerodynamic drag at the centre of mass.
  const double drag = 0.5 * 1.225 * p.drag_coefficient * p.frontal_area * vel.squaredNorm();
  if (vel.norm() > 0.1) {
    const Vec3 f = -vel.normalized() * drag;
    dBodyAddForce(v->body, f.x(), f.y(), f.z());
  }

  for (int i = 0; i < 4; ++i) {
    const bool front = i < 2, left = (i % 2) == 0;
    const Vec3 mount_local(front ? p.wheelbase / 2 : -p.wheelbase / 2, left ? p.track / 2 : -p.track / 2,
                           -half.z() + p.wheel_radius + travel / 2);
    const Vec3 origin = pose.position + R * mount_local;
    RayHit hit;
    WheelRay ctx{&hit};
    dGeomID ray = dCreateRay(nullptr, ray_len);
    dGeomRaySet(ray, origin.x(), origin.y(), origin.z(), -up.x(), -up.y(), -up.z());
    dGeomRaySetClosestHit(ray, 1);
    dSpaceCollide2(ray, reinterpret_cast<dGeomID>(static_space), &ctx, &WheelRayCallback);
    dGeomDestroy(ray);
    if (!hit.hit) continue;
    const double compression = ray_len - hit.distance;
    const Vec3 contact = origin - up * hit.distance;
    const Vec3 r = contact - pose.position;
    const Vec3 v_point = vel + omega.cross(r);
    const double compression_rate = v_point.dot(-up);
    double fz = wheel_mass * 9.81 + p.suspension_stiffness * (compression - travel / 2) + p.suspension_damping * compression_rate;
    if (compression > travel) fz += 10 * p.suspension_stiffness * (compression - travel);  // bump stop
    fz = std::max(0.0, fz);
    if (fz <= 0) continue;

    const Vec3 n = hit.normal.dot(up) < 0 ? Vec3(-hit.normal) : hit.normal;
    const double steer = front ? (left ? steer_left : steer_right) : 0.0;
    Vec3 heading = Eigen::AngleAxisd(steer, up) * fwd;
    heading = (heading - n * heading.dot(n)).normalized();
    const Vec3 lateral = n.cross(heading);
    const double v_long = v_point.dot(heading), v_lat = v_point.dot(lateral);
    const double mu_fz = p.tire_friction * fz;
    const double stop_long = std::abs(v_long) * wheel_mass / h;  // force that stops the wheel in one substep

    double fx = drive_total / 4.0;
    double resist = 0.012 * fz;  // rolling resistance
    if (v->control.throttle < 0.01 && gear != 0) resist += 0.02 * fz;  // engine braking
    resist += v->control.brake * p.max_brake_torque / p.wheel_radius;
    if (!front && v->control.hand_brake) resist += p.max_handbrake_torque / p.wheel_radius;
    if (std::abs(v_long) > 1e-6) {
      fx -= std::copysign(std::min(resist, stop_long), v_long);
    }
    double fy = -kCorneringStiffness * fz * std::atan2(v_lat, std::max(std::abs(v_long), 1.0));
    fy = std::clamp(fy, -std::abs(v_lat) * wheel_mass / h, std::abs(v_lat) * wheel_mass / h);
    const double total = std::hypot(fx, fy);
    if (total > mu_fz) {
      fx *= mu_fz / total;
      fy *= mu_fz / total;
    }
    const Vec3 suspension = up * fz;
    const Vec3 tyre = heading * fx + lateral * fy;
    dBodyAddForceAtPos(v->body, suspension.x(), suspension.y(), suspension.z(), contact.x(), contact.y(), contact.z());
    const Vec3 at = contact + up * kRollCentreLift;
    dBodyAddForceAtPos(v->body, tyre.x(), tyre.y(), tyre.z(), at.x(), at.y(), at.z());
  }
}

}  // namespace lockstep::ground
