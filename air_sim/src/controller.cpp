#include "lockstep/air/controller.h"

#include <algorithm>
#include <cmath>

#include "lockstep/air/frames.h"

namespace lockstep::air {

void Mix(const DerivedParams& derived, double throttle, const Vec3& torque,
         std::array<double, kMaxRotors>* motors) {
  const int n = static_cast<int>(derived.rotors.size());
  std::array<double, kMaxRotors> base{};
  double hi = -1e300;
  for (int i = 0; i < n; ++i) {
    const RotorGeometry& r = derived.rotors[i];
    base[i] = throttle + torque.x() * r.mix_roll + torque.y() * r.mix_pitch;
    hi = std::max(hi, base[i]);
  }
  // Keep roll/pitch authority at full throttle: shift down rather than clip.
  if (hi > 1.0) {
    for (int i = 0; i < n; ++i) base[i] -= hi - 1.0;
  }
  // Yaw gets what is left inside [0, 1] for every motor.
  double ymin = -1e300, ymax = 1e300;
  for (int i = 0; i < n; ++i) {
    const double m = derived.rotors[i].mix_yaw;
    if (m == 0) continue;
    const double a = (1.0 - base[i]) / m, b = (0.0 - base[i]) / m;
    ymax = std::min(ymax, std::max(a, b));
    ymin = std::max(ymin, std::min(a, b));
  }
  double yaw = torque.z();
  if (ymin > ymax) {
    yaw = 0;
  } else {
    yaw = std::clamp(yaw, ymin, ymax);
  }
  for (int i = 0; i < kMaxRotors; ++i) {
    (*motors)[i] = i < n ? std::clamp(base[i] + yaw * derived.rotors[i].mix_yaw, 0.0, 1.0) : 0.0;
  }
}

void MixAirSim(const DerivedParams& derived, double throttle, const Vec3& torque,
               std::array<double, kMaxRotors>* motors) {
  const int n = static_cast<int>(derived.rotors.size());
  motors->fill(0.0);
  if (throttle < kMinAnglingThrottle) {  // too little thrust to steer: all motors alike
    for (int i = 0; i < n; ++i) (*motors)[i] = throttle;
    return;
  }
  double lo = 1e300, hi = -1e300;
  for (int i = 0; i < n; ++i) {
    const RotorGeometry& r = derived.rotors[i];
    (*motors)[i] = throttle + torque.x() * r.mix_roll + torque.y() * r.mix_pitch + torque.z() * r.mix_yaw;
    lo = std::min(lo, (*motors)[i]);
  }
  if (lo < 0) {
    for (int i = 0; i < n; ++i) (*motors)[i] -= lo;
  }
  for (int i = 0; i < n; ++i) hi = std::max(hi, (*motors)[i]);
  if (hi > 1.0) {
    for (int i = 0; i < n; ++i) (*motors)[i] /= hi;
  }
  for (int i = 0; i < n; ++i) (*motors)[i] = std::clamp((*motors)[i], 0.0, 1.0);
}

void ControllerUpdate(const MultirotorParams& params, const DerivedParams& derived,
                      const ControlGoal& goal, const KinematicsView& k, double gravity,
                      double density_ratio, double h, ControllerState* st,
                      std::array<double, kMaxRotors>* motors) {
  using H = ControlGoal::Horizontal;
  using V = ControlGoal::Vertical;
  const ControllerGains& g = st->gains;
  const int n = static_cast<int>(derived.rotors.size());
  motors->fill(0.0);
  if (goal.horizontal == H::kNone) {
    st->vz_integral = 0;
    st->vxy_integral.setZero();
    st->rate_integral.setZero();
    st->has_prev_rate_error = false;
    st->throttle_out = 0;
    st->torque_out.setZero();
    st->yaw_ref = YawOf(k.orientation);
    return;
  }
  if (goal.horizontal == H::kMotors) {
    for (int i = 0; i < n; ++i) (*motors)[i] = std::clamp(goal.motors[i], 0.0, 1.0);
    st->yaw_ref = YawOf(k.orientation);
    return;
  }
  const Mat3 rot = k.orientation.toRotationMatrix();
  const double roll = std::atan2(rot(2, 1), rot(2, 2));
  const double pitch = std::asin(std::clamp(-rot(2, 0), -1.0, 1.0));
  const double yaw = std::atan2(rot(1, 0), rot(0, 0));
  const double max_speed = goal.max_speed > 0 ? goal.max_speed : g.max_velocity;

  // ---- yaw reference
  double yaw_rate_ff = 0;
  if (goal.yaw_is_rate) {
    st->yaw_ref = WrapAngle(st->yaw_ref + goal.yaw * h);
    const double lead = WrapAngle(st->yaw_ref - yaw);
    if (std::abs(lead) > 0.5) st->yaw_ref = WrapAngle(yaw + std::copysign(0.5, lead));
    yaw_rate_ff = goal.yaw;
  } else {
    st->yaw_ref = WrapAngle(goal.yaw);
  }

  // ---- position -> velocity
  Vec3 v_goal = goal.velocity;
  // Speed goal from a position error: linear (p_gain) or, with a closing gain, linear near the
  // goal and sqrt-limited far from it (v = sqrt(2 a d): can still stop at path_accel).
  auto closing = [&](double err, double p_gain, double closing_gain) {
    if (closing_gain > 0) {
      const double d = std::abs(err);
      return std::copysign(std::min(closing_gain * d, std::sqrt(2.0 * params.path_accel * d)), err);
    }
    return p_gain * err;
  };
  const bool airsim = params.gain_model == GainModel::kAirSim;
  // simple_flight's PositionController: per world axis, clip(p e, -1, 1) * velocity limit.
  auto position_pid = [&](double err, double p_gain) { return std::clamp(p_gain * err, -1.0, 1.0) * g.max_velocity; };
  if (goal.horizontal == H::kPosition) {
    const Eigen::Vector2d e = (goal.position - k.position).head<2>();
    const double d = e.norm();
    if (airsim && goal.closing_gain_xy <= 0) {
      v_goal.x() += position_pid(e.x(), g.position_p_xy);
      v_goal.y() += position_pid(e.y(), g.position_p_xy);
    } else if (d > 1e-12) {
      const double sp = std::abs(closing(d, g.position_p_xy, goal.closing_gain_xy));
      v_goal.head<2>() += e / d * sp;
    }
  }
  if (goal.vertical == V::kPosition) {
    const double ez = goal.position.z() - k.position.z();
    v_goal.z() += airsim && goal.closing_gain_z <= 0 ? position_pid(ez, g.position_p_z)
                                                     : closing(ez, g.position_p_z, goal.closing_gain_z);
  }
  {
    const double sxy = v_goal.head<2>().norm();
    if (sxy > max_speed) v_goal.head<2>() *= max_speed / sxy;
    v_goal.z() = std::clamp(v_goal.z(), -max_speed, max_speed);
  }
  st->velocity_goal = v_goal;

  // ---- velocity -> angle level (horizontal)
  double roll_goal = 0, pitch_goal = 0;
  if (airsim && (goal.horizontal == H::kPosition || goal.horizontal == H::kVelocity)) {
    // simple_flight's VelocityController (x, y in the heading frame): tilt goal =
    // clip(p e + I, -1, 1) * max_tilt; forward speed error -> nose down, left -> roll left.
    // A moving reference's acceleration adds its tilt (Lockstep's path feed-forward).
    const double c = std::cos(yaw), s = std::sin(yaw);
    const Vec3 ev = v_goal - k.velocity;
    const Eigen::Vector2d e_h(c * ev.x() + s * ev.y(), -s * ev.x() + c * ev.y());
    Eigen::Vector2d integ = st->vxy_integral.head<2>() + g.velocity_i_xy * e_h * h;
    integ = integ.cwiseMax(-1.0).cwiseMin(1.0);
    st->vxy_integral.head<2>() = integ;
    const double a_fwd = c * goal.accel.x() + s * goal.accel.y();
    const double a_left = -s * goal.accel.x() + c * goal.accel.y();
    pitch_goal = std::clamp(g.velocity_p_xy * e_h.x() + integ.x(), -1.0, 1.0) * g.max_tilt + std::atan2(a_fwd, gravity);
    roll_goal = -std::clamp(g.velocity_p_xy * e_h.y() + integ.y(), -1.0, 1.0) * g.max_tilt - std::atan2(a_left, gravity);
  } else if (goal.horizontal == H::kPosition || goal.horizontal == H::kVelocity) {
    const Eigen::Vector2d ev = (v_goal - k.velocity).head<2>();
    Eigen::Vector2d integ = st->vxy_integral.head<2>() + g.velocity_i_xy * ev * h;
    const double ilim = g.max_tilt;
    if (integ.norm() > ilim) integ *= ilim / integ.norm();
    st->vxy_integral.head<2>() = integ;
    Eigen::Vector2d a = gravity * (g.velocity_p_xy * ev + integ) + goal.accel.head<2>();
    const double amax = gravity * std::tan(g.max_tilt);
    if (a.norm() > amax) a *= amax / a.norm();
    const double c = std::cos(yaw), s = std::sin(yaw);
    const double a_fwd = c * a.x() + s * a.y();
    const double a_left = -s * a.x() + c * a.y();
    pitch_goal = std::atan2(a_fwd, gravity);
    roll_goal = std::asin(std::clamp(-a_left / std::sqrt(a_fwd * a_fwd + a_left * a_left + gravity * gravity), -1.0, 1.0));
  } else if (goal.horizontal == H::kAngle) {
    roll_goal = goal.roll;
    pitch_goal = goal.pitch;
  }
  if (k.grounded && (goal.horizontal == H::kPosition || goal.horizontal == H::kVelocity)) {
    // A ground-locked drone cannot tilt: asking for it would saturate the rate loop and starve
    // the collective thrust it needs to lift off.
    roll_goal = 0;
    pitch_goal = 0;
    st->vxy_integral.setZero();
  }
  roll_goal = std::clamp(roll_goal, -g.max_tilt, g.max_tilt);
  pitch_goal = std::clamp(pitch_goal, -g.max_tilt, g.max_tilt);
  st->roll_goal = roll_goal;
  st->pitch_goal = pitch_goal;

  // ---- velocity -> throttle (vertical)
  double throttle = 0;
  if (airsim && (goal.vertical == V::kPosition || goal.vertical == V::kVelocity)) {
    // simple_flight's VelocityController z: u = clip(p e + I, -1, 1) with the integrator
    // discounted by 0.9999 per update and clipped to [-1, 1]; throttle = (1 + u) / 2 (AirSim
    // writes (1 - u) / 2 in NED), at least min_throttle. No hover feed-forward, no tilt term.
    const double ez = v_goal.z() - k.velocity.z();
    st->vz_integral = std::clamp(st->vz_integral * 0.9999 + g.velocity_i_z * ez * h, -1.0, 1.0);
    const double u = std::clamp(g.velocity_p_z * ez + st->vz_integral, -1.0, 1.0);
    throttle = std::max((1.0 + u) / 2.0, g.min_throttle);
  } else if (goal.vertical == V::kPosition || goal.vertical == V::kVelocity) {
    const double ez = v_goal.z() - k.velocity.z();
    const double ff = derived.hover_throttle / density_ratio * (1.0 + goal.accel.z() / gravity);
    const double tilt = std::max(std::cos(roll) * std::cos(pitch), 0.5);
    const double unclamped = (ff + g.velocity_p_z * ez + st->vz_integral) / tilt;
    // Anti-windup: integrate only when not pushing further into saturation.
    const bool sat_hi = unclamped >= 1.0 && ez > 0;
    const bool sat_lo = unclamped <= g.min_throttle && ez < 0;
    if (!sat_hi && !sat_lo) {
      st->vz_integral = std::clamp(st->vz_integral + g.velocity_i_z * ez * h, -g.integrator_limit, g.integrator_limit);
    }
    throttle = std::clamp((ff + g.velocity_p_z * ez + st->vz_integral) / tilt, g.min_throttle, 1.0);
  } else if (goal.vertical == V::kThrottle) {
    throttle = std::clamp(goal.throttle, 0.0, 1.0);
  }
  st->throttle_out = throttle;

  // ---- angle level -> angle rate
  Vec3 rate_goal;
  if (goal.horizontal == H::kRate) {
    rate_goal = goal.rates;
  } else {
    const double mr = g.max_angle_rate;
    // AirSim: rate goal = clip(p e, -1, 1) * max_angle_rate; physical: clamp(p e, +-max).
    auto level = [&](double p_gain, double err) {
      return airsim ? std::clamp(p_gain * err, -1.0, 1.0) * mr : std::clamp(p_gain * err, -mr, mr);
    };
    const double droll = level(g.angle_level_p.x(), roll_goal - roll);
    const double dpitch = level(g.angle_level_p.y(), pitch_goal - pitch);
    const double dyaw = std::clamp(level(g.angle_level_p.z(), WrapAngle(st->yaw_ref - yaw)) + yaw_rate_ff, -mr, mr);
    // Euler rates -> body rates (Z-Y-X).
    const double sr = std::sin(roll), cr = std::cos(roll), sp = std::sin(pitch), cp = std::cos(pitch);
    rate_goal = Vec3(droll - sp * dyaw, cr * dpitch + sr * cp * dyaw, -sr * dpitch + cr * cp * dyaw);
  }
  st->rate_goal = rate_goal;

  // ---- angle rate -> normalised torque
  const Vec3 err = rate_goal - k.angular_velocity;
  st->rate_integral = (st->rate_integral + g.angle_rate_i.cwiseProduct(err) * h).cwiseMax(-1.0).cwiseMin(1.0);
  Vec3 deriv = Vec3::Zero();
  if (st->has_prev_rate_error && h > 0) deriv = (err - st->prev_rate_error) / h;
  st->prev_rate_error = err;
  st->has_prev_rate_error = true;
  const Vec3 torque = (g.angle_rate_p.cwiseProduct(err) + st->rate_integral + g.angle_rate_d.cwiseProduct(deriv))
                          .cwiseMax(-1.0)
                          .cwiseMin(1.0);
  st->torque_out = torque;
  if (airsim) {
    MixAirSim(derived, throttle, torque, motors);
  } else {
    Mix(derived, throttle, torque, motors);
  }
}

}  // namespace lockstep::air
