#include "playback.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "lockstep/runtime/command_builders.h"
#include "lockstep/runtime/error.h"
#include "lockstep/runtime/log.h"

namespace lockstep {
namespace {

using msg::RecorderAction;

// Log times that differ by less than this are the same instant (sums of dt drift).
constexpr double kTimeEpsilon = 1e-6;
// CARLA's replayer spawns an actor high above its place and then moves it there, so the
// spawn never collides with what stands at that place now.
constexpr double kSpawnRaise = 1000.0;

bool IsHero(const msg::SpawnActor& s) {
  for (const auto& a : s.attributes()) {
    if (a.key().to_string() == "role_name" && a.value().to_string() == "hero") return true;
  }
  return false;
}

bool StartsWith(const std::string& s, const char* prefix) { return s.rfind(prefix, 0) == 0; }

msg::Quaternion Slerp(const msg::Quaternion& a, msg::Quaternion b, double t) {
  double dot = a.w() * b.w() + a.x() * b.x() + a.y() * b.y() + a.z() * b.z();
  if (dot < 0) {  // the short way round
    b.w(-b.w());
    b.x(-b.x());
    b.y(-b.y());
    b.z(-b.z());
    dot = -dot;
  }
  double wa = 1 - t, wb = t;
  if (dot < 0.9995) {
    const double theta = std::acos(std::min(1.0, dot));
    wa = std::sin((1 - t) * theta) / std::sin(theta);
    wb = std::sin(t * theta) / std::sin(theta);
  }
  msg::Quaternion q;
  q.w(wa * a.w() + wb * b.w());
  q.x(wa * a.x() + wb * b.x());
  q.y(wa * a.y() + wb * b.y());
  q.z(wa * a.z() + wb * b.z());
  const double n = std::sqrt(q.w() * q.w() + q.x() * q.x() + q.y() * q.y() + q.z() * q.z());
  q.w(q.w() / n);
  q.x(q.x() / n);
  q.y(q.y() / n);
  q.z(q.z() / n);
  return q;
}

msg::Pose Interpolate(const msg::Pose& a, const msg::Pose& b, double t) {
  msg::Pose p;
  p.position().x(a.position().x() + (b.position().x() - a.position().x()) * t);
  p.position().y(a.position().y() + (b.position().y() - a.position().y()) * t);
  p.position().z(a.position().z() + (b.position().z() - a.position().z()) * t);
  p.orientation(Slerp(a.orientation(), b.orientation(), t));
  return p;
}

// Largest frame index whose time is at or before `t` (0 when t is before the first).
size_t FrameAt(const PlaybackLog& log, double t) {
  size_t lo = 0, hi = log.Frames();
  while (hi - lo > 1) {
    const size_t mid = (lo + hi) / 2;
    if (log.Time(mid) <= t + kTimeEpsilon) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  return lo;
}

// C++ streams' default format of a double, as CARLA's replayer prints its times.
std::string Num(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

}  // namespace

bool IsReplayAction(msg::RecorderAction action) {
  switch (action) {
    case RecorderAction::REPLAY_START:
    case RecorderAction::REPLAY_STOP:
    case RecorderAction::REPLAY_TIME_FACTOR:
    case RecorderAction::REPLAY_IGNORE_HERO:
    case RecorderAction::REPLAY_IGNORE_SPECTATOR: return true;
    default: return false;
  }
}

std::string CheckReplayCommand(const msg::RecorderCommand& c) {
  switch (c.action()) {
    case RecorderAction::REPLAY_START:
      if (c.name().to_string().empty()) return "replay_file needs a file name";
      if (!std::isfinite(c.start())) return "replay_file: start is NaN or infinite";
      if (!std::isfinite(c.duration())) return "replay_file: duration is NaN or infinite";
      return {};
    case RecorderAction::REPLAY_TIME_FACTOR:
      // CARLA takes any factor; a negative one would run the log backwards, which it cannot.
      if (!std::isfinite(c.value()) || c.value() < 0) {
        return "set_replayer_time_factor: time factor = " + Num(c.value()) + " is negative or not finite";
      }
      return {};
    default: return {};
  }
}

Playback::Playback(PlaybackOpener opener, PlaybackResolver resolver)
    : opener_(std::move(opener)), resolver_(std::move(resolver)) {}

std::optional<double> Playback::time() const {
  if (!replay_) return std::nullopt;
  return replay_->now;
}

std::string Playback::Prepare(const msg::RecorderCommand& c, const std::string& map_name, uint64_t map_hash,
                              std::string* text) {
  prepared_.reset();
  std::unique_ptr<PlaybackLog> log;
  try {
    if (!opener_) throw InputError("this coordinator cannot read logs");
    log = opener_(c.name().to_string());
  } catch (const std::exception& e) {
    // CARLA answers a file it cannot open with text, not an error.
    const std::string path = resolver_ ? resolver_(c.name().to_string()) : c.name().to_string();
    if (text) *text = "Replaying File: " + path + "\nFile " + path + " not found on server\n";
    return e.what();
  }
  if (log->Frames() == 0) {
    if (text) *text = "Replaying File: " + log->Path() + "\nFile " + log->Path() + " has no frame\n";
    return "log '" + log->Path() + "' has no whole frame";
  }
  if (log->MapHash() != 0 && map_hash != 0 && log->MapHash() != map_hash) {
    const std::string why = "log '" + log->Path() + "' was recorded on map '" + log->MapName() +
                            "', this run has map '" + map_name + "' (another map or another version of it): load '" +
                            log->MapName() + "' first";
    if (text) *text = "Replaying File: " + log->Path() + "\nCould not load mapfile " + log->MapName() + "\n";
    return why;
  }
  prepared_ = std::move(log);
  return {};
}

std::string Playback::Apply(const msg::RecorderCommand& c) {
  switch (c.action()) {
    case RecorderAction::REPLAY_TIME_FACTOR: time_factor_ = c.value(); return {};
    case RecorderAction::REPLAY_IGNORE_HERO: ignore_hero_ = c.flag(); return {};
    case RecorderAction::REPLAY_IGNORE_SPECTATOR: ignore_spectator_ = c.flag(); return {};
    case RecorderAction::REPLAY_STOP:
      next_.reset();
      if (replay_) {
        stop_pending_ = true;
        stop_keep_actors_ = c.flag();
      }
      return {};
    case RecorderAction::REPLAY_START: break;
    default: return {};
  }
  if (!prepared_) throw InputError("replay_file: no log prepared");
  // A replay in course stops first (CARLA: Stop()); the new one starts at the next tick.
  if (replay_) {
    stop_pending_ = true;
    stop_keep_actors_ = false;
  }
  auto r = std::make_unique<Replay>();
  r->log = std::move(prepared_);
  r->total = r->log->Time(r->log->Frames() - 1);
  double start = c.start();
  if (start < 0) start = std::max(0.0, r->total + start);
  r->start = start;
  r->stop = c.duration() > 0 ? start + c.duration() : r->total;
  r->now = start;
  r->follow_id = c.follow_id();
  r->replay_sensors = c.replay_sensors();
  std::ostringstream info;
  info << "Replaying File: " << r->log->Path() << "\n";
  info << "Total time recorded: " << Num(r->total) << "\n";
  info << "Replaying from " << Num(r->start) << " s - " << Num(r->stop) << " s (" << Num(r->total) << " s) at "
       << std::fixed << std::setprecision(1) << time_factor_ << "x\n";
  if (ignore_hero_) info << "Ignoring Hero vehicle\n";
  if (ignore_spectator_) info << "Ignoring Spectator camera\n";
  spdlog::info("playback of '{}' from {} s to {} s ({} frames, map '{}')", r->log->Path(), r->start, r->stop,
               r->log->Frames(), r->log->MapName());
  if (replay_) {
    next_ = std::move(r);
  } else {
    replay_ = std::move(r);
  }
  return info.str();
}

void Playback::SpawnActor(const PlaybackActor& a, const msg::Pose& at, const PlaybackSubmit& submit,
                          const BlueprintOf& blueprint_of) {
  const std::string bp = a.spawn.blueprint().to_string();
  if (IsHero(a.spawn)) heroes_.insert(a.id);
  if (ignore_hero_ && IsHero(a.spawn)) return;  // CARLA: the hero is not created
  // Sensors only with replay_sensors; controllers (walker AI) are never started by a replay.
  if (a.kind == msg::ActorKind::ACTOR_SENSOR && !replay_->replay_sensors) return;
  if (a.kind == msg::ActorKind::ACTOR_CONTROLLER || a.kind == msg::ActorKind::ACTOR_TRAFFIC_LIGHT ||
      a.kind == msg::ActorKind::ACTOR_TRAFFIC_SIGN) {
    return;
  }
  uint32_t parent = 0;
  if (a.spawn.parent() != 0) {
    auto it = mapped_.find(a.spawn.parent());
    if (it == mapped_.end()) return;  // its parent is not in the replay
    parent = it->second;
  }
  const bool vehicle = a.kind == msg::ActorKind::ACTOR_VEHICLE;
  // CARLA reuses an actor of the same id and blueprint that exists already.
  if (const std::string* existing = blueprint_of(a.id); existing && *existing == bp && !targets_.count(a.id)) {
    mapped_[a.id] = a.id;
    targets_.insert(a.id);
    kinds_[a.id] = a.kind;
    if (vehicle) {
      submit(SimulatePhysicsBody(a.id, false));
      submit(AutopilotBody(a.id, false));
    }
    return;
  }
  msg::SpawnActor s = a.spawn;
  s.actor(0);
  s.parent(parent);
  s.owner("");
  // Vehicles and walkers appear where they were (through a spawn high above it); the rest
  // (drones keep their spawn point as home, props) where they spawned; every pose of the
  // frame follows in the same tick.
  const bool raise = parent == 0 && (vehicle || a.kind == msg::ActorKind::ACTOR_WALKER);
  msg::CommandReply reply;
  for (int attempt = 0; attempt < (raise ? 4 : 1); ++attempt) {
    if (raise) {
      msg::Pose p = at;
      p.position().z(at.position().z() + kSpawnRaise + 100.0 * attempt);
      s.transform(p);
    }
    msg::CommandBody b;
    b.spawn_actor(s);
    reply = submit(b);
    if (reply.accepted()) break;
  }
  if (!reply.accepted()) {
    spdlog::warn("playback: actor {} ({}) of the log could not be created: {}", a.id, bp, reply.reason().to_string());
    return;
  }
  const uint32_t id = reply.actor();
  mapped_[a.id] = id;
  targets_.insert(id);
  spawned_.insert(id);
  kinds_[id] = a.kind;
  if (vehicle) submit(SimulatePhysicsBody(id, false));
}

void Playback::Destroy(uint32_t log_id, const PlaybackSubmit& submit) {
  auto it = mapped_.find(log_id);
  if (it == mapped_.end()) return;
  msg::DestroyActor d;
  d.actor(it->second);
  msg::CommandBody b;
  b.destroy_actor(d);
  submit(b);  // refused when it is gone already: nothing to do
  targets_.erase(it->second);
  spawned_.erase(it->second);
  kinds_.erase(it->second);
  vehicle_lights_set_.erase(it->second);
  mapped_.erase(it);
}

void Playback::Forget() {
  mapped_.clear();
  targets_.clear();
  spawned_.clear();
  kinds_.clear();
  heroes_.clear();
  lights_set_.clear();
  vehicle_lights_set_.clear();
}

void Playback::Finish(bool keep_actors, bool destroy_spawned, const PlaybackSubmit& submit, const BlueprintOf& blueprint_of) {
  if (!replay_) return;
  const PlaybackLog& log = *replay_->log;
  if (destroy_spawned) {
    // Another replay_file follows: this one's actors go (the new one spawns its own).
    std::vector<uint32_t> mine;
    for (const auto& [log_id, id] : mapped_) {
      if (spawned_.count(id)) mine.push_back(log_id);
    }
    for (uint32_t log_id : mine) Destroy(log_id, submit);
  } else if (!keep_actors) {
    // CARLA's Stop(false): the log's remaining events happen (its later destroys and spawns).
    std::set<uint32_t> alive_at_end;
    const auto end = log.ActorsAt(log.Frames() - 1);
    for (const auto& a : end) alive_at_end.insert(a.id);
    std::vector<uint32_t> gone;
    for (const auto& [log_id, id] : mapped_) {
      if (!alive_at_end.count(log_id)) gone.push_back(log_id);
    }
    for (uint32_t log_id : gone) Destroy(log_id, submit);
    for (const auto& a : end) {
      if (!mapped_.count(a.id) && replay_->applied + 1 < log.Frames()) {
        // Spawned after the point the replay reached: where its spawn put it.
        msg::Pose at = a.spawn.transform();
        SpawnActor(a, at, submit, blueprint_of);
      }
    }
  }
  // CARLA's ProcessReplayerFinish: physics back on (and, when the actors stay, autopilot).
  for (const auto& [log_id, id] : mapped_) {
    if (kinds_[id] != msg::ActorKind::ACTOR_VEHICLE) continue;
    if (ignore_hero_ && heroes_.count(log_id)) continue;
    if (!blueprint_of(id)) continue;
    submit(SimulatePhysicsBody(id, true));
    if (keep_actors) submit(AutopilotBody(id, true));
  }
  for (const auto& [id, state] : lights_set_) {
    if (blueprint_of(id)) submit(TrafficLightBody(id, state, false));
  }
  lights_set_.clear();
  replay_.reset();
}

void Playback::NewRun() {
  replay_.reset();
  next_.reset();
  Forget();
  stop_pending_ = false;
  natural_end_ = false;
}

void Playback::Tick(double dt, const PlaybackSubmit& submit, const BlueprintOf& blueprint_of) {
  // Forget actors that are gone (a client destroyed them, or their parent went).
  for (auto it = mapped_.begin(); it != mapped_.end();) {
    if (!blueprint_of(it->second)) {
      targets_.erase(it->second);
      spawned_.erase(it->second);
      kinds_.erase(it->second);
      vehicle_lights_set_.erase(it->second);
      it = mapped_.erase(it);
    } else {
      ++it;
    }
  }
  if (stop_pending_ || natural_end_) {
    // The tick after the last frame shown (or after stop_replayer): the replay ends.
    Finish(natural_end_ || stop_keep_actors_, next_ != nullptr, submit, blueprint_of);
    stop_pending_ = false;
    natural_end_ = false;
    if (next_) {
      Forget();
      replay_ = std::move(next_);
    }
  }
  if (!replay_) return;
  Replay& r = *replay_;
  const PlaybackLog& log = *r.log;
  const double t = r.now;
  const size_t i = FrameAt(log, t);
  const PlaybackFrame frame = log.Frame(i);
  std::map<uint32_t, msg::Pose> poses;
  for (const auto& p : frame.poses) poses[p.id] = p.pose;
  if (r.first) {
    for (const auto& a : log.ActorsAt(i)) {
      auto it = poses.find(a.id);
      SpawnActor(a, it != poses.end() ? it->second : a.spawn.transform(), submit, blueprint_of);
    }
    r.first = false;
  } else if (i > r.applied) {
    // Every event between the last frame applied and this one (a time factor above 1 skips
    // frames): what the skipped frames spawned and destroyed, netted.
    std::map<uint32_t, PlaybackActor> born;
    std::vector<uint32_t> dead;
    for (size_t j = r.applied + 1; j <= i; ++j) {
      PlaybackFrame f = j == i ? frame : log.Frame(j);
      for (auto& a : f.spawned) born[a.id] = std::move(a);
      for (uint32_t id : f.destroyed) {
        std::vector<uint32_t> doomed{id};
        for (size_t k = 0; k < doomed.size(); ++k) {
          for (const auto& [bid, b] : born) {
            if (b.spawn.parent() == doomed[k]) doomed.push_back(bid);
          }
        }
        for (uint32_t d : doomed) {
          if (!born.erase(d)) dead.push_back(d);
        }
      }
    }
    for (uint32_t id : dead) Destroy(id, submit);
    for (const auto& [id, a] : born) {
      auto it = poses.find(id);
      SpawnActor(a, it != poses.end() ? it->second : a.spawn.transform(), submit, blueprint_of);
    }
  }
  r.applied = std::max(r.applied, i);
  // Poses: the frame's, or between it and the next (CARLA interpolates below a time factor of 2).
  std::map<uint32_t, msg::Pose> next_poses;
  double per = 0;
  if (time_factor_ < 2.0 && i + 1 < log.Frames() && t - log.Time(i) > kTimeEpsilon) {
    const double t0 = log.Time(i), t1 = log.Time(i + 1);
    per = (t - t0) / (t1 - t0);
    for (const auto& p : log.Frame(i + 1).poses) next_poses[p.id] = p.pose;
  }
  for (const auto& [log_id, pose] : poses) {
    auto m = mapped_.find(log_id);
    if (m == mapped_.end()) continue;
    if (ignore_hero_ && heroes_.count(log_id)) continue;
    const msg::ActorKind kind = kinds_[m->second];
    if (kind == msg::ActorKind::ACTOR_SENSOR) continue;  // sensors ride on their parents
    auto n = next_poses.find(log_id);
    submit(TransformBody(m->second, n != next_poses.end() ? Interpolate(pose, n->second, per) : pose));
  }
  // Vehicle lights (CARLA's replayer sets them too), when they change.
  for (const auto& v : frame.vehicle_lights) {
    auto m = mapped_.find(v.id);
    if (m == mapped_.end() || (ignore_hero_ && heroes_.count(v.id))) continue;
    auto it = vehicle_lights_set_.find(m->second);
    if (it != vehicle_lights_set_.end() && it->second == v.light_state) continue;
    if (submit(VehicleLightsBody(m->second, v.light_state)).accepted()) vehicle_lights_set_[m->second] = v.light_state;
  }
  for (const auto& l : frame.lights) {
    const std::string* bp = blueprint_of(l.id);
    if (!bp || !StartsWith(*bp, "traffic.")) continue;  // the map's lights keep their ids on the same map
    auto it = lights_set_.find(l.id);
    if (it != lights_set_.end() && it->second == l.state) continue;
    if (submit(TrafficLightBody(l.id, l.state, true)).accepted()) lights_set_[l.id] = l.state;
  }
  r.now = t + dt * time_factor_;
  if (t >= r.stop - kTimeEpsilon) natural_end_ = true;  // CARLA: the frame at the stop time is shown, then it stops
}

}  // namespace lockstep
