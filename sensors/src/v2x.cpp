#include "lockstep/sensors/v2x.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstring>

namespace lockstep::sensors {

namespace {

constexpr double kSpeedOfLight = 299792458.0;  // m/s
constexpr double kEpsilonR = 1.02;             // ground permittivity of CARLA's two-ray model
constexpr double kLowFrequencyInterval = 0.5;  // s between low-frequency containers
constexpr unsigned kLowDynamicsLimit = 3;      // ETSI EN 302 637-2 N_GenCam
constexpr double kTimeEps = 1e-6;              // s: tick times summed in doubles compare as the floats CARLA sums

void PutInt32(std::vector<uint8_t>& out, int32_t v) {
  const uint32_t u = static_cast<uint32_t>(v);
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<uint8_t>((u >> (8 * i)) & 0xFF));
}

double Deg(double rad) { return rad * 180.0 / M_PI; }

// The antenna height above an actor's reference point (CARLA: the collision height + 2 cm).
double AntennaHeight(const Actor& a) { return 2.0 * a.half_extents.z() + 0.02; }

// Rounds as CARLA's std::round on a float.
int32_t RoundI(double v) { return static_cast<int32_t>(std::lround(v)); }

}  // namespace

// ---------------------------------------------------------------------------- payload

std::vector<uint8_t> PackCam(const CamMessage& cam) {
  std::vector<uint8_t> out;
  out.reserve(4 * kCamFields);
  for (int32_t v : cam) PutInt32(out, v);
  return out;
}

int32_t PayloadField(const std::vector<uint8_t>& payload, int index) {
  const size_t at = 4 * static_cast<size_t>(index);
  if (index < 0 || at + 4 > payload.size()) return 0;
  uint32_t u = 0;
  for (int i = 0; i < 4; ++i) u |= static_cast<uint32_t>(payload[at + i]) << (8 * i);
  return static_cast<int32_t>(u);
}

CamMessage UnpackCam(const std::vector<uint8_t>& payload) {
  CamMessage cam{};
  for (int i = 0; i < kCamFields; ++i) cam[i] = PayloadField(payload, i);
  return cam;
}

std::vector<uint8_t> PackCustom(int32_t station_id, const std::string& text) {
  std::vector<uint8_t> out;
  out.reserve(kV2XHeaderBytes + text.size());
  PutInt32(out, kV2XProtocolVersion);
  PutInt32(out, kMessageIdCustom);
  PutInt32(out, station_id);
  out.insert(out.end(), text.begin(), text.end());
  return out;
}

std::string CustomText(const std::vector<uint8_t>& payload) {
  if (payload.size() <= kV2XHeaderBytes) return {};
  return std::string(payload.begin() + kV2XHeaderBytes, payload.end());
}

int32_t StationType(const Actor& a) {
  int32_t type = 0;  // unknown
  switch (ActorTag(a)) {
    case 12: type = 1; break;   // Pedestrian -> pedestrian
    case 19: type = 2; break;   // Bicycle -> cyclist
    case 18: type = 4; break;   // Motorcycle -> motorcycle
    case 14: type = 5; break;   // Car -> passenger car
    case 16: type = 6; break;   // Bus -> bus
    case 15: type = 7; break;   // Truck -> light truck (CARLA has one truck class)
    case 3: case 4: case 5: case 6: case 7: case 8: type = 15; break;  // Buildings .. TrafficSigns -> road side unit
    case 17: type = 11; break;  // Train -> tram
    default: type = 0;
  }
  if (a.kind == ActorKind::kVehicle && a.special_type == "emergency") type = 10;  // special vehicles
  return type;
}

// ---------------------------------------------------------------------------- path loss

PathLoss::PathLoss(const Attributes& a)
    : transmit_power_(a.Float("transmit_power")),
      sensitivity_(a.Float("receiver_sensitivity")),
      gain_(a.Float("combined_antenna_gain")),
      path_loss_exponent_(a.Float("path_loss_exponent")),
      d_ref_(a.Float("d_ref")),
      filter_distance_(a.Float("filter_distance")),
      custom_fading_(a.Float("custom_fading_stddev")),
      frequency_ghz_(a.Float("frequency_ghz")),
      etsi_fading_(a.Bool("use_etsi_fading")),
      winner_(a.String("path_loss_model") == "winner") {
  frequency_ = frequency_ghz_ * 1e9;
  lambda_ = kSpeedOfLight / frequency_;
  fspl_d0_ = 20.0 * std::log10(d_ref_) + 20.0 * std::log10(frequency_) + 20.0 * std::log10(4.0 * M_PI / kSpeedOfLight);
  const std::string& s = a.String("scenario");
  scenario_ = s == "urban" ? 2 : s == "rural" ? 1 : 0;
}

double PathLoss::KnifeEdge(double d1, double d2, double h) const {
  const double v = h * std::sqrt(2.0 * (d1 + d2) / (lambda_ * d1 * d2));
  if (v >= -0.78) {
    const double t = (v - 0.1) * (v - 0.1);
    return 6.9 + 20.0 * std::log10(std::sqrt(t + 1.0) + v - 0.1);
  }
  return 0.0;
}

double PathLoss::PathLossDb(PathState state, double d, double ht, double hr, double knife_edge) const {
  if (winner_) {
    // WINNER+ B1 as ETSI TR 103 257-1 takes it.
    if (state == PathState::kNlosBuilding) return 36.85 + 30.0 * std::log10(d) + 18.9 * std::log10(frequency_ghz_);
    const double los = scenario_ == 0 ? 32.4 + 20.0 * std::log10(d) + 20.0 * std::log10(frequency_ghz_)
                                      : 38.77 + 16.7 * std::log10(d) + 18.2 * std::log10(frequency_ghz_);
    return state == PathState::kNlosVehicle ? los + knife_edge : los;
  }
  switch (state) {
    case PathState::kLos: {
      // The full two-ray ground reflection model.
      const double d_ground = std::sqrt(d * d - (ht - hr) * (ht - hr));
      const double d_refl = std::sqrt(d * d + 4.0 * ht * hr);
      const double sin_t = (ht + hr) / d_refl;
      const double cos_t = d_ground / d_refl;
      const double root = std::sqrt(kEpsilonR - cos_t * cos_t);
      const double gamma = (sin_t - root) / (sin_t + root);
      const double phi = 2.0 * M_PI / lambda_ * (d - d_refl);
      return 20.0 * std::log10(4.0 * M_PI * d_ground / lambda_ * 1.0 /
                               std::sqrt(std::pow(1 + gamma * std::cos(phi), 2) + gamma * gamma * std::pow(std::sin(phi), 2)));
    }
    case PathState::kNlosBuilding: return fspl_d0_ + 10.0 * path_loss_exponent_ * std::log10(d / d_ref_);
    case PathState::kNlosVehicle: return 20.0 * std::log10(d) + 20.0 * std::log10(4.0 * M_PI / lambda_) + knife_edge;
  }
  return 0.0;
}

double PathLoss::FadingStddev(PathState state) const {
  if (!etsi_fading_) return custom_fading_;
  // ETSI TR 103 257-1 table 6 (rural: CARLA takes the middle of highway and urban).
  switch (state) {
    case PathState::kLos: return scenario_ == 0 ? 3.3 : scenario_ == 2 ? 5.2 : 4.25;
    case PathState::kNlosBuilding: return 6.8;
    case PathState::kNlosVehicle: return scenario_ == 0 ? 3.8 : scenario_ == 2 ? 5.3 : 4.55;
  }
  return 0.0;
}

std::optional<float> PathLoss::Receive(const RayScene& scene, const Actor& receiver, const Actor& sender, double tx_power,
                                       const WorldFrame& frame, Rng& rng, PathState* state_out) const {
  // CARLA's PathLossModel::Simulate: both antennas on the roofs of their actors; the lower
  // of the two reference points is the ground the heights are measured from.
  const Vec3 rx_ref = MountPose(receiver).position;
  const Vec3 tx_ref = MountPose(sender).position;
  const double rx_local = AntennaHeight(receiver), tx_local = AntennaHeight(sender);
  const double ground = std::min(rx_ref.z(), tx_ref.z());
  const double h_rx = rx_ref.z() + rx_local - ground;
  const double h_tx = tx_ref.z() + tx_local - ground;
  const Vec3 a = rx_ref + Vec3(0, 0, rx_local);
  const Vec3 b = tx_ref + Vec3(0, 0, tx_local);
  const double distance = (a - b).norm();
  if (!(distance < filter_distance_)) return std::nullopt;

  // The path state from the objects between the antennas (CARLA traces world static,
  // physics bodies, vehicles and world dynamic objects; pedestrians are not traced):
  // vehicles make it NLOSv (each a knife edge), anything else NLOSb.
  PathState state = PathState::kLos;
  double knife = 0.0;
  for (const Hit& h : scene.IntersectAll(a, b)) {
    if (h.geometry == 0 && (h.actor == receiver.id || h.actor == sender.id)) continue;
    if (h.kind == HitKind::kWalker) continue;
    const Actor* obstacle = h.geometry == 0 ? frame.Find(h.actor) : nullptr;
    if (obstacle && obstacle->kind == ActorKind::kVehicle) {
      state = PathState::kNlosVehicle;
      const Vec3 o = MountPose(*obstacle).position;
      const double height = o.z() - ground + AntennaHeight(*obstacle);
      const double d1 = std::hypot(o.x() - rx_ref.x(), o.y() - rx_ref.y());
      const double d2 = std::hypot(tx_ref.x() - o.x(), tx_ref.y() - o.y());
      knife = std::max(knife, KnifeEdge(d1, d2, height));
      continue;
    }
    state = PathState::kNlosBuilding;
    break;
  }
  if (state_out) *state_out = state;
  const double loss = PathLossDb(state, distance, h_rx, h_tx, state == PathState::kNlosVehicle ? knife : 0.0) +
                      rng.Normal(0.0, FadingStddev(state));
  const float power = static_cast<float>(tx_power + gain_ - loss);
  if (!(power >= sensitivity_)) return std::nullopt;
  return power;
}

// ---------------------------------------------------------------------------- CA service

CaService::CaService(const Attributes& a)
    : gen_cam_min_(a.Float("gen_cam_min")),
      gen_cam_max_(a.Float("gen_cam_max")),
      gen_cam_(a.Float("gen_cam_max")),
      fixed_rate_(a.Bool("fixed_rate")),
      lat_sd_(a.Float("noise_lat_stddev")),
      lat_bias_(a.Float("noise_lat_bias")),
      lon_sd_(a.Float("noise_lon_stddev")),
      lon_bias_(a.Float("noise_lon_bias")),
      alt_sd_(a.Float("noise_alt_stddev")),
      alt_bias_(a.Float("noise_alt_bias")),
      head_sd_(a.Float("noise_head_stddev")),
      head_bias_(a.Float("noise_head_bias")),
      accel_sd_(a.Float("noise_accel_stddev_x"), a.Float("noise_accel_stddev_y"), a.Float("noise_accel_stddev_z")),
      yaw_sd_(a.Float("noise_yawrate_stddev")),
      yaw_bias_(a.Float("noise_yawrate_bias")),
      vel_sd_(a.Float("noise_vel_stddev_x")) {}

std::optional<CamMessage> CaService::Trigger(const Actor& owner, double t, double dt, const GeoReference& geo, Rng& rng) {
  if (!started_) {
    // CaService::SetOwner: as if the last CAM went out gen_cam_max ago, the last
    // low-frequency container 0.5 s ago.
    started_ = true;
    last_cam_ = t - gen_cam_max_;
    last_low_cam_ = t - kLowFrequencyInterval;
  }
  elapsed_ = t;
  const Vec3 forward = owner.pose.orientation * Vec3::UnitX();
  const double t_elapsed = elapsed_ - last_cam_;
  if (t_elapsed + kTimeEps < gen_cam_min_) return std::nullopt;
  auto generate = [&] {
    CamMessage cam = Create(owner, dt, geo, rng);
    last_position_ = position_;
    last_speed_ = speed_;
    last_heading_ = heading_;
    last_cam_ = elapsed_;
    return cam;
  };
  if (fixed_rate_) return generate();
  // CARLA evaluates heading, then position, then speed, and stops at the first that
  // triggers: the later ones keep the values of their last evaluation.
  auto heading_changed = [&] {
    heading_ = forward;
    const double c = last_heading_.dot(heading_) / (last_heading_.norm() * heading_.norm());
    return Deg(std::acos(c)) > 4.0;  // NaN (no CAM yet: a zero heading) is no change
  };
  auto position_changed = [&] {
    position_ = MountPose(owner).position;
    return (position_ - last_position_).norm() > 4.0;
  };
  auto speed_changed = [&] {
    speed_ = owner.velocity.dot(forward);
    return std::abs(speed_ - last_speed_) > 0.5;
  };
  if (heading_changed() || position_changed() || speed_changed()) {
    CamMessage cam = generate();
    gen_cam_ = std::min(t_elapsed, gen_cam_max_);
    low_dynamics_counter_ = 0;
    return cam;
  }
  if (t_elapsed + kTimeEps >= gen_cam_) {
    CamMessage cam = generate();
    if (++low_dynamics_counter_ >= kLowDynamicsLimit) gen_cam_ = gen_cam_max_;
    return cam;
  }
  return std::nullopt;
}

CamMessage CaService::Create(const Actor& owner, double dt, const GeoReference& geo, Rng& rng) {
  CamMessage m{};
  m[kProtocolVersion] = kV2XProtocolVersion;
  m[kMessageId] = kMessageIdCam;
  m[kStationId] = static_cast<int32_t>(owner.id);
  // generationDeltaTime: ms of the timestamp modulo 65536. CARLA adds the wall clock's ms
  // since 2004 at the sensor's creation; here simulation time only (deterministic).
  m[kGenerationDeltaTime] = static_cast<int32_t>(static_cast<int64_t>(elapsed_ * 1000.0) % 65536);
  const int32_t station = StationType(owner);
  m[kStationType] = station;

  // Basic container: the reference position (GNSS with noise, CARLA's GeoLocation, in floats).
  const Pose mount = MountPose(owner);
  const GeoPoint g = ToGeo(geo, mount.position);
  const double lat_err = rng.Normal(0.0, lat_sd_);
  const double lon_err = rng.Normal(0.0, lon_sd_);
  const double alt_err = rng.Normal(0.0, alt_sd_);
  const float lat = static_cast<float>(g.latitude + lat_bias_ + lat_err);
  const float lon = static_cast<float>(g.longitude + lon_bias_ + lon_err);
  const float alt = static_cast<float>(g.altitude + alt_bias_ + alt_err);
  m[kLatitude] = RoundI(static_cast<double>(lat) * 1e6) * 10;
  m[kLongitude] = RoundI(static_cast<double>(lon) * 1e6) * 10;
  m[kSemiMajorConfidence] = 4095;   // unavailable
  m[kSemiMinorConfidence] = 4095;
  m[kSemiMajorOrientation] = 3601;  // unavailable
  m[kAltitudeValue] = RoundI(static_cast<double>(alt) * 100.0);
  m[kAltitudeConfidence] = 15;      // unavailable

  if (station == 15 || station == 1) {
    // Road side units and pedestrians: CARLA has no container for them here.
    m[kHighFrequencyPresent] = 0;
    return m;
  }
  const Quat& q = owner.pose.orientation;
  const Vec3 forward = q * Vec3::UnitX();
  m[kHighFrequencyPresent] = 1;
  // Heading: clockwise from north, degrees (0 exactly north, with no noise drawn).
  {
    Vec3 f2(forward.x(), forward.y(), 0.0);
    f2 = f2.norm() > 0 ? Vec3(f2 / f2.norm()) : Vec3::Zero();
    const double dot = f2.y();  // with north
    double heading = 0.0;
    if (!(static_cast<float>(dot) >= 1.0f)) {
      double h = std::acos(dot);
      if (f2.x() < 0.0) h = 2.0 * M_PI - h;
      heading = Deg(h) + head_bias_ + rng.Normal(0.0, head_sd_);
    }
    m[kHeadingValue] = RoundI(heading * 10.0);
  }
  m[kHeadingConfidence] = 10;  // equal or within one degree
  const double forward_speed = owner.velocity.dot(forward);
  {
    const double v = std::clamp(forward_speed + rng.Normal(0.0, vel_sd_), 0.0, static_cast<double>(FLT_MAX));
    m[kSpeedValue] = v >= 163.82 ? 16382 : v >= 0.0 ? RoundI(v * 100.0) : 16383;
  }
  m[kSpeedConfidence] = 3;
  m[kDriveDirection] = forward_speed >= 0.0 ? 0 : 1;
  // CARLA's length and width: the box in centimetres times 10 (its 0.1 m comment notwithstanding).
  m[kVehicleLengthValue] = RoundI(2.0 * owner.half_extents.x() * 100.0 * 10.0);
  m[kVehicleLengthConfidence] = 4;  // unavailable
  m[kVehicleWidth] = RoundI(2.0 * owner.half_extents.y() * 100.0 * 10.0);

  // Accelerometer: the second derivative of the positions at this and the last two CAMs
  // (CARLA updates them only when a CAM is made), gravity added, in the vehicle's frame
  // (x forward, y right, z up, as CARLA's), then noise.
  Vec3 accel;
  {
    const Vec3 y0 = mount.position;
    if (!accel_started_) {
      accel_started_ = true;
      prev_location_[0] = prev_location_[1] = y0;
      prev_dt_ = dt;
    }
    const Vec3 y2 = prev_location_[0], y1 = prev_location_[1];
    const double h1 = dt, h2 = prev_dt_, h12 = h1 + h2;
    Vec3 world = -2.0 * (y1 / (h1 * h2) - y2 / (h2 * h12) - y0 / (h1 * h12));
    prev_location_[0] = prev_location_[1];
    prev_location_[1] = y0;
    prev_dt_ = dt;
    world.z() += 9.81;
    const Vec3 body = q.conjugate() * world;
    accel = Vec3(body.x() + rng.Normal(0.0, accel_sd_.x()), -body.y() + rng.Normal(0.0, accel_sd_.y()),
                 body.z() + rng.Normal(0.0, accel_sd_.z()));
  }
  auto accel_value = [](double a) { return a >= -160.0 && a <= 161.0 ? RoundI(a) : 161; };
  m[kLongitudinalAccelerationValue] = accel_value(accel.x() * 10.0);
  m[kLongitudinalAccelerationConfidence] = 102;  // unavailable
  m[kCurvatureValue] = 30001;                    // unavailable
  m[kCurvatureConfidence] = 7;                   // unavailable
  m[kCurvatureCalculationMode] = 0;              // yaw rate used
  {
    // CARLA's gyroscope z of the vehicle (positive turning right), bias and noise.
    const double yaw_rate = -(q * owner.angular_velocity).z() + yaw_bias_ + rng.Normal(0.0, yaw_sd_);
    const int32_t v = RoundI(Deg(yaw_rate) * 100.0);
    m[kYawRateValue] = v < -32766 || v > 32766 ? 32767 : v;
  }
  m[kYawRateConfidence] = 8;  // unavailable
  m[kOptionalPresent] = (1 << 3) | (1 << 4);
  m[kLateralAccelerationValue] = accel_value(accel.y() * 10.0);
  m[kLateralAccelerationConfidence] = 102;
  m[kVerticalAccelerationValue] = accel_value(accel.z() * 10.0);
  m[kVerticalAccelerationConfidence] = 102;

  if (elapsed_ - last_low_cam_ + kTimeEps >= kLowFrequencyInterval) {
    m[kLowFrequencyPresent] = 1;
    m[kVehicleRole] = station == 6 || station == 11 ? 1 : station == 10 ? 6 : 0;  // public transport, emergency, default
    // carla.VehicleLightState bits -> ETSI ExteriorLights (bit 7 - n of the first octet).
    const uint32_t l = owner.light_state;
    int32_t lights = 0;
    if (l & 0x02) lights |= 1 << 7;  // low beam
    if (l & 0x04) lights |= 1 << 6;  // high beam
    if (l & 0x20) lights |= 1 << 5;  // left blinker
    if (l & 0x10) lights |= 1 << 4;  // right blinker
    if (l & 0x40) lights |= 1 << 2;  // reverse
    if (l & 0x80) lights |= 1 << 1;  // fog
    if (l & 0x01) lights |= 1 << 0;  // position -> parking lights
    m[kExteriorLights] = lights;
    m[kPathHistoryPoints] = 0;
    last_low_cam_ = elapsed_;
  } else {
    m[kLowFrequencyPresent] = 0;
  }
  return m;
}

}  // namespace lockstep::sensors
