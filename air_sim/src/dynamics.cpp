// Multirotor rigid-body dynamics and contact.
//
// Integration (per sub-step h, forces evaluated once at the start of the sub-step):
//   v' = v + a h;  w' = w + alpha h
//   free flight:  p' = p + (v + v') h / 2          (exact for constant acceleration)
//   in contact:   p' = p + v'' h, v'' = v' after contact impulses (semi-implicit, stable)
//   q' = q * exp((w + w') h / 4)  (body rates, quaternion exponential map)
// Contacts: sequential impulses (projected Gauss-Seidel) with restitution, Coulomb friction
// (circular cone) against static geometry and kinematic vehicles, plus a position projection
// of the deepest penetration.
#include <algorithm>
#include <cmath>
#include <numbers>

#include "internal.h"
#include "lockstep/air/frames.h"

namespace lockstep::air::detail {
namespace {

constexpr int kMaxContacts = 32;
constexpr double kSlop = 0.002;          // m, allowed penetration
constexpr double kProjection = 0.4;      // fraction of excess penetration removed per sub-step
constexpr double kSupportNormalZ = 0.7;  // normal.z above which a contact supports the drone
constexpr double kLandedHold = 0.02;     // s, support contact recency for LANDED
constexpr double kOnsetGap = 0.1;        // s, contact gap that makes a new collision onset
constexpr double kDragMinVelocity = 0.1; // m/s, AirSim: slower faces feel no drag
constexpr double kAxisTolerance = 0.25;  // AirSim: |body z . normal| within 1 +- 0.25 is "level"

inline std::uint64_t Rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }

inline std::uint64_t SplitMix(std::uint64_t* x) {
  std::uint64_t z = (*x += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

struct Contact {
  ContactPoint cp;
  Vec3 r;             // contact point relative to the centre of mass, world
  Vec3 t1, t2;        // tangents
  double mass_n = 0, mass_t1 = 0, mass_t2 = 0;
  double target_vn = 0;
  double lambda_n = 0, lambda_t1 = 0, lambda_t2 = 0;
  double approach = 0;  // m/s, approach speed before the solve
  double share = 1;     // fraction of the contact this drone resolves (1 for static objects)
};

bool Finite(const DroneState& s) {
  return s.position.allFinite() && s.velocity.allFinite() && s.orientation.coeffs().allFinite() &&
         s.angular_velocity.allFinite() && s.position.cwiseAbs().maxCoeff() < 1e7 &&
         s.velocity.cwiseAbs().maxCoeff() < 1e4 && s.angular_velocity.cwiseAbs().maxCoeff() < 1e4;
}

const char* WhatIsWrong(const DroneState& s) {
  if (!s.position.allFinite()) return "position not finite";
  if (!s.velocity.allFinite()) return "velocity not finite";
  if (!s.orientation.coeffs().allFinite()) return "orientation not finite";
  if (!s.angular_velocity.allFinite()) return "angular velocity not finite";
  if (s.position.cwiseAbs().maxCoeff() >= 1e7) return "position beyond 1e7 m";
  if (s.velocity.cwiseAbs().maxCoeff() >= 1e4) return "velocity beyond 1e4 m/s";
  return "angular velocity beyond 1e4 rad/s";
}

}  // namespace

std::uint64_t NextRandom(RandomState* r) {
  auto& s = r->s;
  const std::uint64_t result = Rotl(s[1] * 5, 7) * 9;
  const std::uint64_t t = s[1] << 17;
  s[2] ^= s[0];
  s[3] ^= s[1];
  s[1] ^= s[2];
  s[0] ^= s[3];
  s[2] ^= t;
  s[3] = Rotl(s[3], 45);
  return result;
}

double NextGaussian(RandomState* r) {
  // Box-Muller on 53-bit uniforms (bit-reproducible given the same libm).
  const double u1 = (static_cast<double>(NextRandom(r) >> 11) + 1.0) * 0x1.0p-53;
  const double u2 = static_cast<double>(NextRandom(r) >> 11) * 0x1.0p-53;
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
}

RandomState SeedRandom(std::uint64_t seed, std::uint64_t stream) {
  std::uint64_t x = seed ^ (stream * 0xD1B54A32D192ED03ull);
  RandomState r;
  for (auto& w : r.s) w = SplitMix(&x);
  return r;
}

void ResetToSpawn(const DroneModel& dm, DroneState* s) {
  s->position = dm.spawn.position;
  s->orientation = dm.spawn.orientation.normalized();
  s->velocity.setZero();
  s->angular_velocity.setZero();
  s->acceleration.setZero();
  s->angular_acceleration.setZero();
  for (RotorState& r : s->rotors) r = RotorState{};
  s->total_thrust = 0;
  s->armed = false;
  s->grounded = false;
  s->carrier = 0;
  s->gust.setZero();
  const ControllerGains gains = s->controller.gains;
  s->controller = ControllerState{};
  s->controller.gains = gains;
  s->controller.yaw_ref = YawOf(s->orientation);
}

void BuildProximity(const World& model, WorldState* state, double dt) {
  WorldState::Proximity& px = state->proximity;
  const std::size_t n = model.drones.size();
  px.pose.resize(n);
  px.velocity.resize(n);
  px.reach.resize(n);
  px.order.resize(n);
  px.start.assign(n + 1, 0);
  px.count.assign(n, 0);
  px.others.clear();
  if (!model.drone_collisions || n < 2) return;
  double max_reach = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const DroneState& d = state->drones[i];
    px.pose[i] = Pose{d.position, d.orientation};
    px.velocity[i] = d.velocity;
    const bool ok = d.position.allFinite() && d.velocity.allFinite() && d.orientation.coeffs().allFinite();
    // Its own travel in the tick plus a margin for acceleration (10 m/s^2 over the tick).
    px.reach[i] = ok ? model.drones[i].derived.bounding_radius + d.velocity.norm() * dt + 5.0 * dt * dt + 0.01 : -1;
    max_reach = std::max(max_reach, px.reach[i]);
    px.order[i] = static_cast<std::uint32_t>(i);
  }
  std::sort(px.order.begin(), px.order.end(), [&](std::uint32_t a, std::uint32_t b) {
    const double xa = px.reach[a] < 0 ? 1e300 : px.pose[a].position.x();
    const double xb = px.reach[b] < 0 ? 1e300 : px.pose[b].position.x();
    return xa < xb || (xa == xb && a < b);
  });
  // Two passes over the sweep: count, then fill (CSR).
  for (int pass = 0; pass < 2; ++pass) {
    for (std::size_t a = 0; a < n; ++a) {
      const std::uint32_t i = px.order[a];
      if (px.reach[i] < 0) break;
      const Vec3& pi = px.pose[i].position;
      for (std::size_t b = a + 1; b < n; ++b) {
        const std::uint32_t j = px.order[b];
        if (px.reach[j] < 0) break;
        const Vec3& pj = px.pose[j].position;
        if (pj.x() - pi.x() > px.reach[i] + max_reach) break;
        const double r = px.reach[i] + px.reach[j];
        if ((pj - pi).squaredNorm() >= r * r) continue;
        if (pass == 0) {
          ++px.start[i + 1];
          ++px.start[j + 1];
        } else {
          px.others[px.start[i] + px.count[i]++] = j;
          px.others[px.start[j] + px.count[j]++] = i;
        }
      }
    }
    if (pass == 0) {
      for (std::size_t i = 0; i < n; ++i) px.start[i + 1] += px.start[i];
      px.others.resize(px.start[n]);
    }
  }
  // Deterministic neighbour order (by index) regardless of the sweep.
  for (std::size_t i = 0; i < n; ++i) std::sort(px.others.begin() + px.start[i], px.others.begin() + px.start[i + 1]);
}

void PhysicsSubstep(const World& model, const DroneModel& dm, DroneState* s, const Environment& env,
                    const Neighbours& near, double t, double t_tick, double h, std::uint64_t frame,
                    std::vector<AirEvent>* events) {
  const MultirotorParams& p = dm.params;
  const DerivedParams& d = dm.derived;
  const int nrot = static_cast<int>(d.rotors.size());
  const double rho = env.air_density;
  const double density_ratio = rho / 1.225;

  // ---- rotors: first-order lag on the control signal, thrust ~ signal (n^2 ~ signal)
  const double alpha = 1.0 - std::exp(-h / p.rotor.time_constant);
  Vec3 force_b = Vec3::Zero();
  Vec3 torque_b = Vec3::Zero();
  double total_thrust = 0;
  for (int i = 0; i < nrot; ++i) {
    RotorState& r = s->rotors[i];
    const double cmd = s->armed ? std::clamp(r.command, 0.0, 1.0) : 0.0;
    r.signal += (cmd - r.signal) * alpha;
    r.speed = d.max_rev_per_s * 2.0 * std::numbers::pi * std::sqrt(std::max(r.signal, 0.0));
    r.thrust = r.signal * d.max_thrust_per_rotor * density_ratio;  // C_T rho n^2 D^4
    r.torque = r.signal * d.max_torque_per_rotor * density_ratio;  // C_P rho n^2 D^5 / (2 pi)
    const RotorGeometry& g = d.rotors[i];
    force_b.z() += r.thrust;
    torque_b += Vec3(g.position.y() * r.thrust, -g.position.x() * r.thrust, -g.spin * r.torque);
    total_thrust += r.thrust;
  }
  s->total_thrust = total_thrust;

  // ---- drag on body faces and rotor discs (air-relative velocity, AirSim drag faces)
  const Mat3 rot = s->orientation.toRotationMatrix();
  if (env.turbulence_sigma > 0 && p.turbulence_scale > 0) {
    const double decay = std::exp(-h / env.turbulence_tau);
    const double sigma = env.turbulence_sigma * p.turbulence_scale * std::sqrt(1.0 - decay * decay);
    for (int i = 0; i < 3; ++i) s->gust[i] = s->gust[i] * decay + sigma * NextGaussian(&s->rng);
  }
  const Vec3 v_air_b = rot.transpose() * (s->velocity - env.wind - s->gust);
  const Vec3& w = s->angular_velocity;
  if (p.drag_model == DragModel::kAirSim) {
    // AirSim (FastPhysicsEngine::getDragWrench): each face feels the combined velocity of its
    // centre, v + w x r, squared, with one coefficient; faces slower than 0.1 m/s feel nothing.
    const double cl = 0.5 * rho * p.linear_drag_coefficient;
    if (cl > 0) {
      for (const DragFace& f : d.faces) {
        const double vn = f.normal.dot(v_air_b + w.cross(f.position));
        if (vn > kDragMinVelocity) {
          const Vec3 fd = -(cl * f.area * vn * vn) * f.normal;
          force_b += fd;
          torque_b += f.position.cross(fd);
        }
      }
    }
  } else {
    const double cl = 0.5 * rho * p.linear_drag_coefficient;
    const double ca = 0.5 * rho * p.angular_drag_coefficient;
    if (cl > 0 || ca > 0) {
      for (const DragFace& f : d.faces) {
        const double vn = f.normal.dot(v_air_b);
        const double wn = f.normal.dot(w.cross(f.position));
        double mag = 0;
        if (vn > 0) mag += cl * f.area * vn * vn;
        if (wn > 0) mag += ca * f.area * wn * wn;
        if (mag > 0) {
          const Vec3 fd = -mag * f.normal;
          force_b += fd;
          torque_b += f.position.cross(fd);
        }
      }
    }
  }

  // ---- accelerations
  const double m = p.mass;
  const Vec3 a = rot * force_b / m - Vec3(0, 0, model.gravity);
  const Vec3 alpha_b = d.inertia_inv * (torque_b - w.cross(d.inertia * w));
  const Vec3 v0 = s->velocity;
  const Vec3 w0 = w;
  Vec3 v1 = v0 + a * h;
  Vec3 w1 = w0 + alpha_b * h;

  // ---- contacts (obstacles at the end of the sub-step)
  Contact contacts[kMaxContacts];
  int nc = 0;
  bool grounded_step = false;
  const StaticGeometry& sg = model.statics;
  const double t_obj = t_tick + h;
  auto add = [&](const ContactPoint& cp) {
    if (nc < kMaxContacts) contacts[nc++].cp = cp;
  };
  const bool finite_pose = s->position.allFinite() && rot.allFinite();
  for (const ContactSphere& sp : d.spheres) {
    if (!finite_pose) break;  // reset below; no queries with NaN
    const Vec3 c = s->position + rot * sp.center;
    if (sg.has_ground) {
      const double depth = sg.ground_height - (c.z() - sp.radius);
      if (depth > 0) {
        ContactPoint cp;
        cp.point = Vec3(c.x(), c.y(), sg.ground_height);
        cp.normal = Vec3::UnitZ();
        cp.depth = depth;
        cp.kind = ObjectKind::kGround;
        cp.object_id = 0;
        add(cp);
      }
    }
    if (sg.mesh) {
      ContactPoint buf[4];
      const int k = sg.mesh->QuerySphere(c, sp.radius, buf, 4);
      for (int i = 0; i < k; ++i) add(buf[i]);
    }
  }
  for (const VehicleBox& vb : env.vehicles) {
    // Malformed vehicles (non-finite, empty) are ignored rather than poisoning the drone.
    if (!finite_pose || !vb.pose.position.allFinite() || !vb.velocity.allFinite() ||
        !vb.angular_velocity.allFinite() || !vb.pose.orientation.coeffs().allFinite() ||
        !(vb.half_extents.minCoeff() > 0) || !vb.half_extents.allFinite() ||
        vb.pose.orientation.norm() < 1e-6) {
      continue;
    }
    const Vec3 center = vb.pose.position + vb.velocity * t_obj;
    const double reach = vb.half_extents.norm() + d.bounding_radius;
    if ((center - s->position).squaredNorm() > reach * reach) continue;
    const Pose pose = ExtrapolateVehicle(vb, t_obj);
    for (const ContactSphere& sp : d.spheres) {
      const Vec3 c = s->position + rot * sp.center;
      ContactPoint cp;
      if (SphereBoxContact(c, sp.radius, pose, vb.half_extents, &cp)) {
        cp.kind = ObjectKind::kVehicle;
        cp.object_id = vb.id;
        cp.object_velocity = vb.velocity + vb.angular_velocity.cross(cp.point - pose.position);
        add(cp);
      }
    }
  }

  // Other drones: their contact spheres at the tick-start pose moved by the tick-start velocity.
  const int first_drone_contact = nc;
  for (const std::uint32_t* it = near.begin; finite_pose && it != near.end; ++it) {
    const std::uint32_t j = *it;
    const DroneModel& other = model.drones[j];
    const Pose& op = near.proximity->pose[j];
    const Vec3 ov = near.proximity->velocity[j];
    const Vec3 oc = op.position + ov * t_obj;
    const double reach = other.derived.bounding_radius + d.bounding_radius;
    if ((oc - s->position).squaredNorm() >= reach * reach) continue;
    const Mat3 orot = op.orientation.toRotationMatrix();
    for (const ContactSphere& sp : d.spheres) {
      const Vec3 c = s->position + rot * sp.center;
      for (const ContactSphere& osp : other.derived.spheres) {
        const Vec3 q = oc + orot * osp.center;
        const Vec3 diff = c - q;
        const double rr = sp.radius + osp.radius;
        const double d2 = diff.squaredNorm();
        if (d2 >= rr * rr) continue;
        const double dist = std::sqrt(d2);
        ContactPoint cp;
        cp.normal = dist > 1e-9 ? Vec3(diff / dist) : Vec3(Vec3::UnitZ());
        cp.point = q + cp.normal * osp.radius;
        cp.depth = rr - dist;
        cp.kind = ObjectKind::kDrone;
        cp.object_id = other.id;
        cp.object_velocity = ov;
        add(cp);
      }
    }
  }

  // ---- AirSim ground lock (FastPhysicsEngine::getNextKinematicsOnCollision): a level drone
  // descending onto a supporting surface stops there (no bounce, levelled, moving with the
  // surface) and stays until its thrust exceeds its weight.
  if (p.landing_model == LandingModel::kGroundLock && finite_pose) {
    int support = -1;
    for (int i = 0; i < nc; ++i) {
      if (contacts[i].cp.normal.z() > kSupportNormalZ &&
          (support < 0 || contacts[i].cp.depth > contacts[support].cp.depth)) {
        support = i;
      }
    }
    if (s->grounded && (support < 0 || total_thrust >= m * model.gravity)) s->grounded = false;
    if (!s->grounded) s->carrier = 0;
    if (!s->grounded && support >= 0) {
      const Vec3 vrel = v0 - contacts[support].cp.object_velocity;
      const Vec3 up_body = rot.transpose() * contacts[support].cp.normal;
      const bool level = std::abs(std::abs(up_body.z()) - 1.0) <= kAxisTolerance;
      const bool landing = -vrel.z() > std::abs(vrel.x()) && -vrel.z() > std::abs(vrel.y());
      s->grounded = level && landing && total_thrust < m * model.gravity;
    }
    if (s->grounded) {
      const Contact& c = contacts[support];
      const Vec3 v_surface = c.cp.object_velocity;
      double yaw = std::atan2(rot(1, 0), rot(0, 0));
      // Carried by the surface: a vehicle's rigid motion over the sub-step (turning with it),
      // static surfaces hold the drone still.
      const VehicleBox* carrier = nullptr;
      if (c.cp.kind == ObjectKind::kVehicle) {
        for (const VehicleBox& vb : env.vehicles) {
          if (vb.id == c.cp.object_id) carrier = &vb;
        }
      }
      if (carrier != nullptr && s->carrier == carrier->id) {
        // Riding: the pose it locked at, in the carrier's frame, carried to the carrier's pose
        // at the sub-step's end. The carrier's pose is read again every tick (its GroundState),
        // so the extrapolation's errors do not add up into a slide over the roof.
        const Pose cp = ExtrapolateVehicle(*carrier, t_tick + h);
        s->position = cp.position + cp.orientation * s->carrier_offset;
        const Mat3 cr = cp.orientation.toRotationMatrix();
        yaw = std::atan2(cr(1, 0), cr(0, 0)) + s->carrier_yaw;
      } else if (carrier != nullptr) {
        const Vec3 centre = carrier->pose.position + carrier->velocity * t_tick;
        const Vec3 turn = carrier->angular_velocity * h;
        const Quat q = turn.norm() > 0 ? Quat(Eigen::AngleAxisd(turn.norm(), turn.normalized())) : Quat::Identity();
        s->position = centre + carrier->velocity * h + q * (s->position - centre);
        yaw += turn.z();
        // Out of the surface, along its normal (the deepest support contact); then locked.
        const double excess = c.cp.depth - kSlop;
        if (excess > 0) s->position += c.cp.normal * excess;
        const Pose cp = ExtrapolateVehicle(*carrier, t_tick + h);
        const Mat3 cr = cp.orientation.toRotationMatrix();
        s->carrier = carrier->id;
        s->carrier_offset = cp.orientation.conjugate() * (s->position - cp.position);
        s->carrier_yaw = yaw - std::atan2(cr(1, 0), cr(0, 0));
      } else {
        s->carrier = 0;
        s->position += v_surface * h;
        const double excess = c.cp.depth - kSlop;
        if (excess > 0) s->position += c.cp.normal * excess;
      }
      s->orientation = Quat(Eigen::AngleAxisd(yaw, Vec3::UnitZ()));
      s->acceleration = (v_surface - v0) / h;
      s->angular_acceleration = -w0 / h;
      s->velocity = v_surface;
      s->angular_velocity.setZero();
      for (int i = 0; i < nc; ++i) {
        contacts[i].approach = std::max(0.0, -contacts[i].cp.normal.dot(v0 - contacts[i].cp.object_velocity));
      }
      grounded_step = true;
    }
  }

  Vec3 dv_contact = Vec3::Zero();
  if (nc > 0 && !grounded_step) {
    const Mat3 iw_inv = rot * d.inertia_inv * rot.transpose();
    Vec3 ww = rot * w1;  // world angular velocity
    const double inv_m = 1.0 / m;
    auto eff_mass = [&](const Vec3& r, const Vec3& dir) {
      const double k = inv_m + dir.dot((iw_inv * r.cross(dir)).cross(r));
      return k > 1e-12 ? 1.0 / k : 0.0;
    };
    for (int i = 0; i < nc; ++i) {
      Contact& c = contacts[i];
      c.r = c.cp.point - s->position;
      const Vec3& n = c.cp.normal;
      c.t1 = (std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY()).cross(n).normalized();
      c.t2 = n.cross(c.t1);
      c.mass_n = eff_mass(c.r, n);
      c.mass_t1 = eff_mass(c.r, c.t1);
      c.mass_t2 = eff_mass(c.r, c.t2);
      if (i >= first_drone_contact) {
        // Both drones resolve the same contact from their side: each takes its mass share of
        // the impulse, m_other / (m + m_other), which conserves momentum for a head-on pair.
        const double mo = model.Find(c.cp.object_id)->params.mass;
        c.share = mo / (m + mo);
        c.mass_n *= c.share;
        c.mass_t1 *= c.share;
        c.mass_t2 *= c.share;
      }
      const Vec3 vrel = v1 + ww.cross(c.r) - c.cp.object_velocity;
      const double vn = n.dot(vrel);
      c.approach = std::max(0.0, -n.dot(v0 + (rot * w0).cross(c.r) - c.cp.object_velocity));
      c.target_vn = vn < -model.restitution_threshold ? -p.restitution * vn : 0.0;
    }
    const Vec3 v_before = v1;
    for (int iter = 0; iter < 8; ++iter) {
      for (int i = 0; i < nc; ++i) {
        Contact& c = contacts[i];
        const Vec3& n = c.cp.normal;
        Vec3 vrel = v1 + ww.cross(c.r) - c.cp.object_velocity;
        const double old_n = c.lambda_n;
        c.lambda_n = std::max(0.0, old_n + c.mass_n * (c.target_vn - n.dot(vrel)));
        Vec3 impulse = n * (c.lambda_n - old_n);
        v1 += impulse * inv_m;
        ww += iw_inv * c.r.cross(impulse);
        // Friction (circular cone, accumulated).
        vrel = v1 + ww.cross(c.r) - c.cp.object_velocity;
        const double o1 = c.lambda_t1, o2 = c.lambda_t2;
        double l1 = o1 - c.mass_t1 * c.t1.dot(vrel);
        double l2 = o2 - c.mass_t2 * c.t2.dot(vrel);
        const double lim = p.friction * c.lambda_n;
        const double mag = std::hypot(l1, l2);
        if (mag > lim && mag > 0) {
          l1 *= lim / mag;
          l2 *= lim / mag;
        }
        c.lambda_t1 = l1;
        c.lambda_t2 = l2;
        impulse = c.t1 * (l1 - o1) + c.t2 * (l2 - o2);
        v1 += impulse * inv_m;
        ww += iw_inv * c.r.cross(impulse);
      }
    }
    dv_contact = v1 - v_before;
    w1 = rot.transpose() * ww;
  }

  // ---- integrate
  if (grounded_step) {
    // Pose and velocity were set by the ground lock.
  } else if (nc == 0) {
    s->position += (v0 + v1) * (0.5 * h);
  } else {
    s->position += v1 * h;
    int deepest = 0;
    for (int i = 1; i < nc; ++i)
      if (contacts[i].cp.depth > contacts[deepest].cp.depth) deepest = i;
    const double excess = contacts[deepest].cp.depth - kSlop;
    if (excess > 0) s->position += contacts[deepest].cp.normal * (kProjection * excess * contacts[deepest].share);
  }
  if (!grounded_step) {
    const Vec3 w_avg = (w0 + w1) * 0.5;
    const double angle = w_avg.norm() * h;
    if (angle > 0) {
      s->orientation = (s->orientation * Quat(Eigen::AngleAxisd(angle, w_avg.normalized()))).normalized();
    }
    s->acceleration = a + dv_contact / h;
    s->angular_acceleration = (w1 - w0) / h;
    s->velocity = v1;
    s->angular_velocity = w1;
  }
  const double t_end = t + h;

  // ---- contacts -> collision info, events, landed state
  int deepest = -1;
  for (int i = 0; i < nc; ++i) {
    const Contact& c = contacts[i];
    if (deepest < 0 || c.cp.depth > contacts[deepest].cp.depth) deepest = i;
    if (c.cp.normal.z() > kSupportNormalZ) {
      s->last_support_time = t_end;
      s->support_velocity = c.cp.object_velocity;
    }
    // Onset: this object was not touched within the last kOnsetGap seconds.
    int slot = -1, oldest = 0;
    for (int k = 0; k < static_cast<int>(s->touching.size()); ++k) {
      const auto& tk = s->touching[k];
      if (tk.kind == c.cp.kind && tk.id == c.cp.object_id && tk.time >= 0) slot = k;
      if (s->touching[k].time < s->touching[oldest].time) oldest = k;
    }
    const bool onset = slot < 0 || t_end - s->touching[slot].time > kOnsetGap;
    if (slot < 0) slot = oldest;
    s->touching[slot] = {c.cp.kind, c.cp.object_id, t_end};
    if (onset) {
      s->collision.collision_count += 1;
      s->collision.impact_speed = c.approach;
      AirEvent e;
      e.kind = EventKind::kCollision;
      e.drone = s->id;
      e.time = t_end;
      e.frame = frame;
      e.object_kind = c.cp.kind;
      e.object_id = c.cp.object_id;
      e.position = c.cp.point;
      e.normal = c.cp.normal;
      e.impact_speed = c.approach;
      events->push_back(e);
    }
  }
  if (deepest >= 0) {
    const Contact& c = contacts[deepest];
    CollisionInfo& ci = s->collision;
    ci.has_collided = true;
    ci.kind = c.cp.kind;
    ci.object_id = c.cp.object_id;
    ci.normal = c.cp.normal;
    ci.impact_point = c.cp.point;
    ci.position = s->position;
    ci.penetration_depth = c.cp.depth;
    ci.time = t_end;
    ci.frame = frame;
  }
  const LandedState before = s->landed;
  s->landed = (s->last_support_time >= 0 && t_end - s->last_support_time <= kLandedHold + 1e-12)
                  ? LandedState::kLanded
                  : LandedState::kFlying;
  if (s->landed != before) {
    AirEvent e;
    e.kind = s->landed == LandedState::kLanded ? EventKind::kLanded : EventKind::kTookOff;
    e.drone = s->id;
    e.time = t_end;
    e.frame = frame;
    e.position = s->position;
    events->push_back(e);
  }

  // ---- numerical blow-up: reset to spawn, record, continue (mj_checkPos style)
  if (!Finite(*s)) {
    AirEvent e;
    e.kind = EventKind::kReset;
    e.drone = s->id;
    e.time = t_end;
    e.frame = frame;
    e.message = WhatIsWrong(*s);
    ResetToSpawn(dm, s);
    e.position = s->position;
    s->reset_count += 1;
    events->push_back(e);
  }
}

}  // namespace lockstep::air::detail
