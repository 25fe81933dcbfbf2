#include "lockstep/sensors/sensor_world.h"

#include <cmath>
#include <map>
#include <optional>
#include <variant>

namespace lockstep::sensors {

size_t StepOutput::size() const {
  return point_clouds.size() + radar.size() + imu.size() + gnss.size() + barometer.size() + magnetometer.size() +
         distance.size() + obstacle.size() + collision.size() + lane_invasion.size() + v2x.size();
}

namespace {

// A V2X sensor: its radio, its CA service (sensor.other.v2x) or the text waiting to be sent
// (sensor.other.v2x_custom), and its own random stream (fading, CAM noise), as CARLA's.
struct V2XRadio {
  V2XRadio(const Attributes& a, bool custom, uint64_t seed) : radio(a), rng(seed) {
    if (!custom) cam.emplace(a);
  }
  void Save(StateOut& out) const {
    rng.Save(out);
    out.Put(pending.has_value());
    if (pending) out.Put(*pending);
    if (cam) cam->Save(out);
  }
  void Load(StateIn& in) {
    rng.Load(in);
    bool has = false;
    in.Get(has);
    pending.reset();
    if (has) in.Get(pending.emplace());
    if (cam) cam->Load(in);
  }
  PathLoss radio;
  std::optional<CaService> cam;
  std::optional<std::string> pending;
  Rng rng;
  uint64_t Fingerprint() const { return rng.Fingerprint(); }
};

using Model = std::variant<std::monostate, Lidar, Radar, Imu, Gnss, Barometer, Magnetometer, DistanceSensor, ObstacleDetector, V2XRadio>;

// Builds the model of a checked spawn.
Model MakeModel(SensorType type, const Attributes& a, uint64_t seed) {
  switch (type) {
    case SensorType::kLidar: return Lidar(a, false, seed);
    case SensorType::kSemanticLidar: return Lidar(a, true, seed);
    case SensorType::kRadar: return Radar(a, seed);
    case SensorType::kImu: return Imu(a, seed);
    case SensorType::kGnss: return Gnss(a, seed);
    case SensorType::kBarometer: return Barometer(a, seed);
    case SensorType::kMagnetometer: return Magnetometer(a, seed);
    case SensorType::kDistance: return DistanceSensor(a, seed);
    case SensorType::kObstacle: return ObstacleDetector(a);
    case SensorType::kV2X: return V2XRadio(a, false, seed);
    case SensorType::kCustomV2X: return V2XRadio(a, true, seed);
    case SensorType::kCollision:
    case SensorType::kLaneInvasion: return std::monostate{};
  }
  return std::monostate{};
}

// Combinations a declaration cannot express.
std::string CrossCheck(const SensorBlueprint& bp, const Attributes& a) {
  if (bp.type == SensorType::kLidar || bp.type == SensorType::kSemanticLidar) {
    if (a.Float("upper_fov") < a.Float("lower_fov")) {
      return bp.id + ": upper_fov (" + a.String("upper_fov") + ") is below lower_fov (" + a.String("lower_fov") + ")";
    }
  }
  if (bp.type == SensorType::kDistance && a.Float("min_distance") > a.Float("max_distance")) {
    return bp.id + ": min_distance is above max_distance";
  }
  return {};
}

}  // namespace

struct SensorWorld::Sensor {
  SensorSpawn spawn;
  SensorType type;
  double tick = 0;      // s, sensor_tick (0 = every frame)
  bool started = false;
  double t0 = 0;        // s, time of the first sample
  uint64_t next = 0;    // index of the next due sample: due at t0 + next * tick
  double last = 0;      // s, time of the last sample
  Model model;
  bool placed = false;  // last_pose is set
  Pose last_pose;       // world pose at the last step that found its parent

  // sensor_tick as CARLA's actor tick interval: sampled at the first frame, then at the
  // first frame at or after each multiple of sensor_tick (no drift, no doubling).
  bool Due(double t, double dt, double* elapsed) {
    if (!started) {
      started = true;
      t0 = t;
      next = 0;
      last = t - dt;
    }
    if (tick > 0 && t + 1e-9 < t0 + static_cast<double>(next) * tick) return false;
    // Whole nanoseconds: k * dt - (k - 1) * dt is not dt to the last bit, and a slice of
    // pps * dt / channels = 87.5 points must not flip between 87 and 88.
    *elapsed = std::round((t - last) * 1e9) / 1e9;
    last = t;
    if (tick > 0) next = static_cast<uint64_t>(std::floor((t - t0) / tick + 1e-9)) + 1;
    return true;
  }

  void Save(StateOut& out) const {
    out.Put(started);
    out.Put(t0);
    out.Put(next);
    out.Put(last);
    out.Put(placed);
    out.Put(last_pose);
    std::visit(
        [&](const auto& m) {
          using M = std::decay_t<decltype(m)>;
          if constexpr (!std::is_same_v<M, std::monostate> && !std::is_same_v<M, ObstacleDetector>) m.Save(out);
        },
        model);
  }
  void Load(StateIn& in) {
    in.Get(started);
    in.Get(t0);
    in.Get(next);
    in.Get(last);
    in.Get(placed);
    in.Get(last_pose);
    std::visit(
        [&](auto& m) {
          using M = std::decay_t<decltype(m)>;
          if constexpr (!std::is_same_v<M, std::monostate> && !std::is_same_v<M, ObstacleDetector>) m.Load(in);
        },
        model);
  }
};

void SensorWorld::Save(StateOut& out) const {
  out.Put(weather_.precipitation);
  out.Put(weather_.fog_density);
  out.Put(static_cast<uint64_t>(sensors_.size()));
  for (const auto& [id, s] : sensors_) {
    // The spawn as it stands (a detached sensor keeps its last world pose), then its state.
    out.Put(s->spawn.id);
    out.Put(s->spawn.blueprint);
    out.Put(s->spawn.attributes);
    out.Put(s->spawn.parent);
    out.Put(s->spawn.transform);
    s->Save(out);
  }
}

void SensorWorld::Restore(StateIn& in) {
  in.Get(weather_.precipitation);
  in.Get(weather_.fog_density);
  uint64_t n = 0;
  in.Get(n);
  sensors_.clear();
  for (uint64_t i = 0; i < n; ++i) {
    SensorSpawn spawn;
    in.Get(spawn.id);
    in.Get(spawn.blueprint);
    in.Get(spawn.attributes);
    in.Get(spawn.parent);
    in.Get(spawn.transform);
    if (std::string why = Add(spawn); !why.empty()) throw std::runtime_error("sensor snapshot: sensor " + std::to_string(spawn.id) + ": " + why);
    sensors_.at(spawn.id)->Load(in);
  }
}

// ---- snapshots: what each model changes from step to step ----
void Lidar::Save(StateOut& out) const {
  out.Put(angle_);
  rng_.Save(out);
}
void Lidar::Load(StateIn& in) {
  in.Get(angle_);
  rng_.Load(in);
}
void Radar::Save(StateOut& out) const {
  rng_.Save(out);
  out.Put(has_prev_);
  out.Put(prev_position_);
}
void Radar::Load(StateIn& in) {
  rng_.Load(in);
  in.Get(has_prev_);
  in.Get(prev_position_);
}
void Imu::Save(StateOut& out) const {
  out.Put(gyro_walk_);
  out.Put(accel_walk_);
  out.Put(started_);
  out.Put(prev_[0]);
  out.Put(prev_[1]);
  out.Put(prev_dt_);
  rng_.Save(out);
}
void Imu::Load(StateIn& in) {
  in.Get(gyro_walk_);
  in.Get(accel_walk_);
  in.Get(started_);
  in.Get(prev_[0]);
  in.Get(prev_[1]);
  in.Get(prev_dt_);
  rng_.Load(in);
}
void Gnss::Save(StateOut& out) const {
  out.Put(age_);
  out.Put(started_);
  rng_.Save(out);
}
void Gnss::Load(StateIn& in) {
  in.Get(age_);
  in.Get(started_);
  rng_.Load(in);
}
void Barometer::Save(StateOut& out) const {
  out.Put(factor_);
  rng_.Save(out);
}
void Barometer::Load(StateIn& in) {
  in.Get(factor_);
  rng_.Load(in);
}
void Magnetometer::Save(StateOut& out) const { rng_.Save(out); }
void Magnetometer::Load(StateIn& in) { rng_.Load(in); }
void DistanceSensor::Save(StateOut& out) const { rng_.Save(out); }
void DistanceSensor::Load(StateIn& in) { rng_.Load(in); }
void CaService::Save(StateOut& out) const {
  out.Put(started_);
  out.Put(elapsed_);
  out.Put(last_cam_);
  out.Put(last_low_cam_);
  out.Put(low_dynamics_counter_);
  out.Put(position_);
  out.Put(heading_);
  out.Put(speed_);
  out.Put(last_position_);
  out.Put(last_heading_);
  out.Put(last_speed_);
  out.Put(accel_started_);
  out.Put(prev_location_[0]);
  out.Put(prev_location_[1]);
  out.Put(prev_dt_);
}
void CaService::Load(StateIn& in) {
  in.Get(started_);
  in.Get(elapsed_);
  in.Get(last_cam_);
  in.Get(last_low_cam_);
  in.Get(low_dynamics_counter_);
  in.Get(position_);
  in.Get(heading_);
  in.Get(speed_);
  in.Get(last_position_);
  in.Get(last_heading_);
  in.Get(last_speed_);
  in.Get(accel_started_);
  in.Get(prev_location_[0]);
  in.Get(prev_location_[1]);
  in.Get(prev_dt_);
}

std::string CheckSensorSpawn(const SensorSpawn& spawn) {
  const SensorBlueprint* bp = FindSensorBlueprint(spawn.blueprint);
  if (!bp) return "'" + spawn.blueprint + "' is not a sensor blueprint of this service";
  Attributes a;
  if (std::string why = ResolveAttributes(*bp, spawn.attributes, &a); !why.empty()) return why;
  return CrossCheck(*bp, a);
}

SensorWorld::SensorWorld(uint64_t run_seed, GeoReference geo) : run_seed_(run_seed), geo_(geo) {}
SensorWorld::~SensorWorld() = default;

std::string SensorWorld::Add(const SensorSpawn& spawn) {
  const SensorBlueprint* bp = FindSensorBlueprint(spawn.blueprint);
  if (!bp) return "'" + spawn.blueprint + "' is not a sensor blueprint of this service";
  if (sensors_.count(spawn.id)) return "sensor " + std::to_string(spawn.id) + " exists already";
  Attributes a;
  if (std::string why = ResolveAttributes(*bp, spawn.attributes, &a); !why.empty()) return why;
  if (std::string why = CrossCheck(*bp, a); !why.empty()) return why;
  auto s = std::make_unique<Sensor>();
  s->spawn = spawn;
  s->type = bp->type;
  if (bp->type != SensorType::kCollision && bp->type != SensorType::kLaneInvasion) s->tick = a.Float("sensor_tick");
  // The sensor's noise stream: run seed, its actor id and its noise_seed attribute.
  const uint64_t noise_seed = a.Given("noise_seed") ? static_cast<uint64_t>(a.Int("noise_seed")) : 0;
  s->model = MakeModel(bp->type, a, MixSeed(run_seed_, spawn.id, noise_seed));
  sensors_[spawn.id] = std::move(s);
  return {};
}

bool SensorWorld::Remove(uint32_t id) { return sensors_.erase(id) > 0; }

void SensorWorld::Detach(uint32_t parent) {
  for (auto& [id, s] : sensors_) {
    if (parent == 0 || s->spawn.parent != parent) continue;
    s->spawn.parent = 0;
    if (s->placed) s->spawn.transform = s->last_pose;
  }
}

bool SensorWorld::HasEventSensors() const {
  for (const auto& [id, s] : sensors_) {
    if (s->type == SensorType::kCollision || s->type == SensorType::kLaneInvasion) return true;
  }
  return false;
}

bool SensorWorld::HasRaySensors() const {
  for (const auto& [id, s] : sensors_) {
    switch (s->type) {
      case SensorType::kLidar:
      case SensorType::kSemanticLidar:
      case SensorType::kRadar:
      case SensorType::kDistance:
      case SensorType::kObstacle:
      case SensorType::kV2X:
      case SensorType::kCustomV2X: return true;
      default: break;
    }
  }
  return false;
}

std::string SensorWorld::V2XSend(uint32_t sensor, const std::string& text) {
  auto it = sensors_.find(sensor);
  if (it == sensors_.end()) return "sensor " + std::to_string(sensor) + " is not simulated here";
  if (it->second->type != SensorType::kCustomV2X) {
    return "actor " + std::to_string(sensor) + " (" + it->second->spawn.blueprint + ") is not a sensor.other.v2x_custom";
  }
  if (text.size() > kCustomV2XMaxText) return "V2X message of " + std::to_string(text.size()) + " bytes (at most 1024)";
  std::get<V2XRadio>(it->second->model).pending = text;
  return {};
}

StepOutput SensorWorld::Step(const WorldFrame& frame, double dt, const FrameEvents& events) {
  StepOutput out;
  if (HasRaySensors()) scene_.SetActors(frame.actors);
  struct DueV2X {
    uint32_t id;
    Sensor* sensor;
    const Actor* parent;
    Pose pose;
  };
  std::vector<DueV2X> v2x;
  for (auto& [id, s] : sensors_) {
    const SensorSpawn& sp = s->spawn;
    const Actor* parent = sp.parent ? frame.Find(sp.parent) : nullptr;
    if (sp.parent && !parent) continue;  // not in this frame (yet, or any more)
    if (parent) {
      s->last_pose = MountPose(*parent).Compose(sp.transform);
      s->placed = true;
    }
    if (s->type == SensorType::kV2X || s->type == SensorType::kCustomV2X) {
      // CARLA's V2X sensors act for their parent (GetOwner()); unattached ones do nothing.
      double unused = 0;
      if (parent && s->Due(frame.sim_time, dt, &unused)) v2x.push_back({id, s.get(), parent, MountPose(*parent).Compose(sp.transform)});
      continue;
    }
    if (s->type == SensorType::kCollision) {
      for (const auto& e : events.collisions) {
        if (parent && e.actor == sp.parent) out.collision.push_back({id, sp.parent, MountPose(*parent).Compose(sp.transform), CollisionSample{e}});
      }
      continue;
    }
    if (s->type == SensorType::kLaneInvasion) {
      for (const auto& e : events.lane_invasions) {
        if (parent && e.actor == sp.parent) out.lane_invasion.push_back({id, sp.parent, MountPose(*parent).Compose(sp.transform), LaneInvasionSample{e.crossed}});
      }
      continue;
    }
    double elapsed = 0;
    if (!s->Due(frame.sim_time, dt, &elapsed)) continue;
    // Attached: relative to the parent's mount (vehicles and walkers: the bottom of the box).
    const Pose pose = parent ? MountPose(*parent).Compose(sp.transform) : sp.transform;
    const Vec3 omega = parent ? parent->angular_velocity : Vec3::Zero();
    const Vec3 velocity = parent ? Vec3(parent->velocity + omega.cross(pose.position - parent->pose.position)) : Vec3::Zero();
    std::visit(
        [&](auto& m) {
          using M = std::decay_t<decltype(m)>;
          if constexpr (std::is_same_v<M, Lidar>) {
            out.point_clouds.push_back({id, sp.parent, pose, m.Scan(scene_, pose, elapsed, weather_)});
          } else if constexpr (std::is_same_v<M, Radar>) {
            out.radar.push_back({id, sp.parent, pose, m.Scan(scene_, frame, pose, elapsed)});
          } else if constexpr (std::is_same_v<M, Imu>) {
            out.imu.push_back({id, sp.parent, pose, m.Sample(pose, velocity, omega, elapsed)});
          } else if constexpr (std::is_same_v<M, Gnss>) {
            out.gnss.push_back({id, sp.parent, pose, m.Sample(geo_, pose, elapsed)});
          } else if constexpr (std::is_same_v<M, Barometer>) {
            out.barometer.push_back({id, sp.parent, pose, m.Sample(geo_, pose, elapsed)});
          } else if constexpr (std::is_same_v<M, Magnetometer>) {
            out.magnetometer.push_back({id, sp.parent, pose, m.Sample(geo_, pose)});
          } else if constexpr (std::is_same_v<M, DistanceSensor>) {
            out.distance.push_back({id, sp.parent, pose, m.Sample(scene_, pose, sp.parent)});
          } else if constexpr (std::is_same_v<M, ObstacleDetector>) {
            ObstacleSample o = m.Sample(scene_, pose, sp.parent);
            if (o.other_kind != HitKind::kNone) out.obstacle.push_back({id, sp.parent, pose, o});
          }
        },
        s->model);
  }
  // V2X, CARLA's two phases: every due sensor first makes what its parent sends this step
  // (PrePhysTick: one message per parent and family, the lowest sensor id's), then each
  // receives the others' through its path-loss model (PostPhysTick), senders in id order.
  struct Sent {
    uint32_t sensor;
    double power;
    std::vector<uint8_t> payload;
  };
  std::map<uint32_t, Sent> sent[2];  // [0] CAM, [1] custom; by parent id
  for (auto& d : v2x) {
    auto& m = std::get<V2XRadio>(d.sensor->model);
    const bool custom = d.sensor->type == SensorType::kCustomV2X;
    if (custom) {
      if (!m.pending) continue;
      sent[1].emplace(d.parent->id, Sent{d.id, m.radio.transmit_power(), PackCustom(static_cast<int32_t>(d.parent->id), *m.pending)});
      m.pending.reset();
    } else if (d.parent->kind == ActorKind::kVehicle) {
      if (auto cam = m.cam->Trigger(*d.parent, frame.sim_time, dt, geo_, m.rng)) {
        sent[0].emplace(d.parent->id, Sent{d.id, m.radio.transmit_power(), PackCam(*cam)});
      }
    }
  }
  for (auto& d : v2x) {
    auto& m = std::get<V2XRadio>(d.sensor->model);
    const auto& family = sent[d.sensor->type == SensorType::kCustomV2X ? 1 : 0];
    std::vector<V2XMessage> got;
    for (const auto& [owner, msg] : family) {
      if (owner == d.parent->id) continue;
      const Actor* sender = frame.Find(owner);
      if (!sender) continue;
      if (auto power = m.radio.Receive(scene_, *d.parent, *sender, msg.power, frame, m.rng)) {
        got.push_back(V2XMessage{msg.sensor, *power, msg.payload});
      }
    }
    if (!got.empty()) out.v2x.push_back({d.id, d.parent->id, d.pose, std::move(got)});
  }
  return out;
}

uint64_t SensorWorld::StateHash() const {
  uint64_t h = MixSeed(run_seed_, sensors_.size());
  for (const auto& [id, s] : sensors_) {
    const uint64_t fp = std::visit(
        [](const auto& m) -> uint64_t {
          using M = std::decay_t<decltype(m)>;
          if constexpr (std::is_same_v<M, std::monostate> || std::is_same_v<M, ObstacleDetector>) {
            return 0;
          } else {
            return m.Fingerprint();
          }
        },
        s->model);
    h = MixSeed(h, id, fp ^ s->next);
  }
  return h;
}

}  // namespace lockstep::sensors
