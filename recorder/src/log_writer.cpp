#include "lockstep/recorder/log_writer.h"

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <map>
#include <set>
#include <unordered_map>

#include "lockstep_log.pb.h"
#include "log_format.h"

namespace lockstep::recorder {

using namespace detail;

namespace {

struct Quantised {
  int64_t v[6] = {0, 0, 0, 0, 0, 0};
  bool operator==(const Quantised& o) const { return std::memcmp(v, o.v, sizeof v) == 0; }
};

Quantised QuantisePose(const msg::Pose& p) {
  const Rpy r = RpyOf(p.orientation());
  Quantised q;
  q.v[0] = Quantise(p.position().x(), kPositionQuantum);
  q.v[1] = Quantise(p.position().y(), kPositionQuantum);
  q.v[2] = Quantise(p.position().z(), kPositionQuantum);
  q.v[3] = Quantise(r.roll, kAngleQuantum);
  q.v[4] = Quantise(r.pitch, kAngleQuantum);
  q.v[5] = Quantise(r.yaw, kAngleQuantum);
  return q;
}

void FillHash(log::FrameHash* out, uint64_t frame, const FrameHashes& h, const std::vector<std::string>& names) {
  out->set_frame(frame);
  out->set_world_hash(h.world_hash);
  out->set_diverged(h.diverged);
  // Compact: one fixed64 per header service, when the acks are exactly those services.
  if (!names.empty() && h.services.size() == names.size()) {
    std::map<std::string, uint64_t> by(h.services.begin(), h.services.end());
    if (by.size() == names.size() && std::all_of(names.begin(), names.end(), [&](const std::string& n) { return by.count(n) > 0; })) {
      for (const auto& n : names) out->add_service_hashes(by[n]);
      return;
    }
  }
  for (const auto& [name, hash] : h.services) {
    auto* s = out->add_services();
    s->set_service(name);
    s->set_state_hash(hash);
  }
}

void FillActor(log::ActorInfo* out, const ActorInfo& a) {
  out->set_id(a.id);
  out->set_blueprint(a.blueprint);
  out->set_kind(static_cast<uint32_t>(a.kind));
  out->set_parent(a.parent);
  out->set_owner(a.owner);
  for (const auto& [k, v] : a.attributes) {
    auto* at = out->add_attributes();
    at->set_id(k);
    at->set_value(v);
  }
  out->set_half_x(static_cast<float>(a.half_extents[0]));
  out->set_half_y(static_cast<float>(a.half_extents[1]));
  out->set_half_z(static_cast<float>(a.half_extents[2]));
  out->set_x(a.spawn_pose.position().x());
  out->set_y(a.spawn_pose.position().y());
  out->set_z(a.spawn_pose.position().z());
  out->set_qw(a.spawn_pose.orientation().w());
  out->set_qx(a.spawn_pose.orientation().x());
  out->set_qy(a.spawn_pose.orientation().y());
  out->set_qz(a.spawn_pose.orientation().z());
}

// The slow parts, compared as serialized messages.
template <class M>
bool SameAs(const M& a, const std::string& previous) {
  return a.SerializeAsString() == previous;
}

}  // namespace

struct LogWriter::Impl {
  std::string path;
  FILE* file = nullptr;
  uint64_t offset = 0;
  uint64_t frames = 0;
  uint64_t first_frame = 0;
  uint64_t last_frame = 0;
  double first_sim_time = 0;
  double last_sim_time = 0;
  uint32_t keyframe_period = kDefaultKeyframePeriod;
  bool closed = false;
  std::vector<uint64_t> offsets;
  std::vector<uint64_t> keyframes;
  std::vector<double> sim_times;
  // The frames before, for the predictions: value one and two frames before, and how many
  // of them count (0 new, 1 after a keyframe or its first frame, 2 otherwise).
  struct History {
    Quantised q1, q2;
    int n = 0;
  };
  std::unordered_map<uint32_t, History> poses;
  std::map<uint32_t, std::array<int32_t, 3>> controls;  // vehicle -> throttle, steer, brake in 1/1000
  std::vector<std::string> service_names;  // the header's services, for the compact hashes
  std::set<uint32_t> present;
  std::unordered_map<uint32_t, std::string> slow;  // serialized slow info by actor
  std::unordered_map<uint32_t, double> light_elapsed;  // predicted elapsed of each light
  std::unordered_map<uint32_t, std::array<uint32_t, 5>> infractions;
  // Every actor of the log, for the footer.
  std::map<uint32_t, log::ActorInfo> actors;
  std::unordered_map<uint32_t, std::pair<uint64_t, uint64_t>> actor_frames;
  std::map<uint32_t, SensorStats> sensor_stats;  // for the footer
  std::string buffer;

  void Write(const log::Record& r) {
    buffer.clear();
    r.SerializeToString(&buffer);
    uint8_t len[10];
    const size_t n = PutVarint(buffer.size(), len);
    if (std::fwrite(len, 1, n, file) != n || std::fwrite(buffer.data(), 1, buffer.size(), file) != buffer.size() ||
        std::fflush(file) != 0) {
      throw LogError("recorder: cannot write " + path + ": " + std::strerror(errno));
    }
    offset += n + buffer.size();
  }
};

LogWriter::LogWriter(const std::string& path, const LogHeader& header) : impl_(std::make_unique<Impl>()) {
  impl_->path = path;
  std::error_code ec;
  const auto dir = std::filesystem::path(path).parent_path();
  if (!dir.empty()) std::filesystem::create_directories(dir, ec);
  impl_->file = std::fopen(path.c_str(), "wb");
  if (impl_->file == nullptr) throw LogError("recorder: cannot create " + path + ": " + std::strerror(errno));
  if (std::fwrite(kMagic, 1, sizeof kMagic, impl_->file) != sizeof kMagic) throw LogError("recorder: cannot write " + path);
  impl_->offset = sizeof kMagic;
  if (header.keyframe_period > 0) impl_->keyframe_period = header.keyframe_period;
  log::Record r;
  auto* h = r.mutable_header();
  h->set_format_version(kFormatVersion);
  h->set_name(header.name.empty() ? path : header.name);
  h->set_config_text(header.config_text);
  h->set_config_source(header.config_source);
  h->set_map_name(header.map_name);
  h->set_map_digest(header.map_digest);
  h->set_seed(header.seed);
  h->set_run(header.run);
  const auto world = ToCdr(header.world);
  h->set_world_info_cdr(world.data(), world.size());
  for (const auto& s : header.services) {
    impl_->service_names.push_back(s.name);
    auto* o = h->add_services();
    o->set_name(s.name);
    o->set_kind(s.kind);
    o->set_required(s.required);
    o->set_perception(s.perception);
    for (const auto& [id, kind] : s.blueprints) {
      auto* b = o->add_blueprints();
      b->set_id(id);
      b->set_kind(static_cast<uint32_t>(kind));
    }
    o->set_blueprint_set_cdr(s.blueprint_set_cdr.data(), s.blueprint_set_cdr.size());
  }
  h->set_first_frame(header.first_frame);
  h->set_first_sim_time(header.first_sim_time);
  h->set_start_unix_time(header.start_unix_time != 0 ? header.start_unix_time : static_cast<int64_t>(std::time(nullptr)));
  h->set_additional_data(header.additional_data);
  h->set_keyframe_period(impl_->keyframe_period);
  h->set_position_quantum(kPositionQuantum);
  h->set_angle_quantum(kAngleQuantum);
  for (uint32_t s : header.sensors) h->add_sensors(s);
  h->set_sensor_selection(header.sensor_selection);
  for (const auto& t : header.prelude) {
    const auto b = ToCdr(t);
    h->add_prelude_ticks_cdr(b.data(), b.size());
  }
  h->set_prelude_frames(header.prelude_frames);
  impl_->Write(r);
}

LogWriter::~LogWriter() {
  if (!impl_) return;
  try {
    if (!impl_->closed) Close("closed");
  } catch (...) {
  }
  if (impl_->file != nullptr) std::fclose(impl_->file);
}

const std::string& LogWriter::path() const { return impl_->path; }
uint64_t LogWriter::bytes() const { return impl_->offset; }
uint64_t LogWriter::frames() const { return impl_->frames; }
uint64_t LogWriter::last_frame() const { return impl_->last_frame; }

void LogWriter::WriteFrame(const FrameInputs& in) {
  Impl& m = *impl_;
  if (m.closed) throw LogError("recorder: " + m.path + " is closed");
  if (in.tick == nullptr) throw LogError("recorder: a frame without its tick");
  const msg::Tick& tick = *in.tick;
  const bool keyframe = m.frames % m.keyframe_period == 0;
  log::Record r;
  auto* f = r.mutable_frame();
  f->set_frame(tick.frame());
  f->set_run(tick.run());
  f->set_sim_time(tick.sim_time());
  f->set_dt(tick.dt());
  const auto tick_bytes = ToCdr(tick);
  f->set_tick_cdr(tick_bytes.data(), tick_bytes.size());
  f->set_command_count(static_cast<uint32_t>(tick.commands().size()));
  f->set_keyframe(keyframe);
  f->set_state_frame(in.state_frame);

  // Every actor with a state this frame, with its kind, pose and slow part.
  struct Entry {
    msg::ActorKind kind;
    const msg::Pose* pose;
    const char* blueprint;  // the state message's (no copy per actor and frame)
    const msg::Vector3* half;
  };
  std::map<uint32_t, Entry> now;
  std::unordered_map<uint32_t, std::string> slow_now;
  slow_now.reserve(m.slow.size() + 16);
  std::map<uint32_t, std::array<int32_t, 3>> controls_now;
  for (const auto* g : in.ground) {
    for (const auto& v : g->vehicles()) {
      now[v.actor()] = Entry{msg::ActorKind::ACTOR_VEHICLE, &v.transform(), v.blueprint().c_str(), &v.half_extents()};
      log::VehicleInfo vi;
      vi.set_id(v.actor());
      vi.set_hand_brake(v.control().hand_brake());
      vi.set_reverse(v.control().reverse());
      vi.set_gear(v.gear());
      vi.set_light_state(v.light_state());
      vi.set_autopilot(v.autopilot());
      std::string s = vi.SerializeAsString();
      if (keyframe || m.slow.count(v.actor()) == 0 || m.slow[v.actor()] != s) *f->add_vehicles() = vi;
      slow_now[v.actor()] = std::move(s);
      controls_now[v.actor()] = {static_cast<int32_t>(std::lround(v.control().throttle() * 1000.0)),
                                 static_cast<int32_t>(std::lround(v.control().steer() * 1000.0)),
                                 static_cast<int32_t>(std::lround(v.control().brake() * 1000.0))};
      // Infractions: the cumulative counters' increments.
      const std::array<uint32_t, 5> counts{v.red_light_infractions(), v.stop_sign_infractions(), v.collision_infractions(),
                                           v.opposite_lane_infractions(), v.offroad_infractions()};
      if (auto it = m.infractions.find(v.actor()); it != m.infractions.end()) {
        for (size_t i = 0; i < counts.size(); ++i) {
          if (counts[i] > it->second[i]) {
            auto* inf = f->add_infractions();
            inf->set_actor(v.actor());
            inf->set_kind(static_cast<log::InfractionKind>(i));
            inf->set_count(counts[i] - it->second[i]);
          }
        }
      }
      m.infractions[v.actor()] = counts;
    }
    for (const auto& w : g->walkers()) {
      now[w.actor()] = Entry{msg::ActorKind::ACTOR_WALKER, &w.transform(), w.blueprint().c_str(), &w.half_extents()};
      log::WalkerInfo wi;
      wi.set_id(w.actor());
      wi.set_speed(w.control().speed());
      wi.set_ai_controlled(w.ai_controlled());
      std::string s = wi.SerializeAsString();
      if (keyframe || m.slow.count(w.actor()) == 0 || m.slow[w.actor()] != s) *f->add_walkers() = wi;
      slow_now[w.actor()] = std::move(s);
    }
    for (const auto& l : g->traffic_lights()) {
      now[l.actor()] = Entry{msg::ActorKind::ACTOR_TRAFFIC_LIGHT, &l.transform(), "traffic.traffic_light", nullptr};
      log::TrafficLightInfo li;
      li.set_id(l.actor());
      li.set_state(static_cast<uint32_t>(l.state()));
      li.set_frozen(l.frozen());
      li.set_green_time(static_cast<float>(l.green_time()));
      li.set_yellow_time(static_cast<float>(l.yellow_time()));
      li.set_red_time(static_cast<float>(l.red_time()));
      li.set_opendrive_id(l.opendrive_id().to_string());
      std::string s = li.SerializeAsString();  // without elapsed: it changes every frame
      const auto predicted = m.light_elapsed.find(l.actor());
      const bool elapsed_as_predicted = predicted != m.light_elapsed.end() && predicted->second == l.elapsed();
      if (keyframe || m.slow.count(l.actor()) == 0 || m.slow[l.actor()] != s || !elapsed_as_predicted) {
        li.set_elapsed(l.elapsed());
        *f->add_traffic_lights() = li;
      }
      slow_now[l.actor()] = std::move(s);
    }
  }
  for (const auto* a : in.air) {
    for (const auto& d : a->drones()) {
      now[d.actor()] = Entry{msg::ActorKind::ACTOR_DRONE, &d.transform(), d.blueprint().c_str(), nullptr};
      log::DroneInfo di;
      di.set_id(d.actor());
      di.set_landed(d.landed() == msg::LandedState::LANDED_LANDED);
      di.set_armed(d.armed());
      di.set_command_id(d.command_id());
      di.set_command_status(static_cast<uint32_t>(d.command_status()));
      di.set_api_control(d.api_control());
      std::string s = di.SerializeAsString();
      if (keyframe || m.slow.count(d.actor()) == 0 || m.slow[d.actor()] != s) *f->add_drones() = di;
      slow_now[d.actor()] = std::move(s);
    }
  }

  // Poses: absolute in a keyframe, else the residual from the prediction (the .proto's
  // rule); an actor exactly where predicted is left out.
  auto* poses = f->mutable_poses();
  uint32_t last_id = 0;
  std::unordered_map<uint32_t, Impl::History> poses_now;
  poses_now.reserve(now.size());
  for (const auto& [id, e] : now) {
    const Quantised q = QuantisePose(*e.pose);
    const auto prev = m.poses.find(id);
    const Impl::History h = prev == m.poses.end() ? Impl::History{} : prev->second;
    Quantised base;
    if (!keyframe && h.n == 1) base = h.q1;
    if (!keyframe && h.n >= 2) {
      for (int k = 0; k < 6; ++k) base.v[k] = 2 * h.q1.v[k] - h.q2.v[k];
    }
    poses_now[id] = Impl::History{q, h.q1, keyframe ? 1 : std::min(h.n + 1, 2)};
    if (!keyframe && h.n > 0 && base == q) continue;
    poses->add_id_delta(id - last_id);
    last_id = id;
    poses->add_x(q.v[0] - base.v[0]);
    poses->add_y(q.v[1] - base.v[1]);
    poses->add_z(q.v[2] - base.v[2]);
    poses->add_roll(q.v[3] - base.v[3]);
    poses->add_pitch(q.v[4] - base.v[4]);
    poses->add_yaw(q.v[5] - base.v[5]);
  }
  // Pedals and wheel: absolute in a keyframe or for a new vehicle, else the change.
  auto* controls = f->mutable_controls();
  last_id = 0;
  for (const auto& [id, c] : controls_now) {
    const auto prev = m.controls.find(id);
    const bool known = prev != m.controls.end() && !keyframe;
    if (known && prev->second == c) continue;
    const std::array<int32_t, 3> base = known ? prev->second : std::array<int32_t, 3>{0, 0, 0};
    controls->add_id_delta(id - last_id);
    last_id = id;
    controls->add_throttle(c[0] - base[0]);
    controls->add_steer(c[1] - base[1]);
    controls->add_brake(c[2] - base[2]);
  }

  // Spawned and destroyed, against the frame before.
  std::set<uint32_t> present;
  for (const auto& [id, e] : now) present.insert(id);
  for (uint32_t id : in.stateless_actors) present.insert(id);
  for (uint32_t id : present) {
    if (m.present.count(id)) continue;
    std::optional<ActorInfo> info = in.describe ? in.describe(id) : std::nullopt;
    ActorInfo a = info.value_or(ActorInfo{});
    a.id = id;
    if (auto it = now.find(id); it != now.end()) {
      if (!info) {
        a.kind = it->second.kind;
        a.blueprint = it->second.blueprint;
        a.spawn_pose = *it->second.pose;
      }
      if (it->second.half != nullptr && a.half_extents[0] == 0 && a.half_extents[1] == 0 && a.half_extents[2] == 0) {
        a.half_extents[0] = it->second.half->x();
        a.half_extents[1] = it->second.half->y();
        a.half_extents[2] = it->second.half->z();
      }
      if (a.blueprint.empty()) a.blueprint = it->second.blueprint;
    }
    if (a.spawn_pose.orientation().w() == 0 && a.spawn_pose.orientation().x() == 0 && a.spawn_pose.orientation().y() == 0 &&
        a.spawn_pose.orientation().z() == 0) {
      a.spawn_pose.orientation().w(1);
    }
    FillActor(f->add_spawned(), a);
    FillActor(&m.actors[id], a);
    m.actor_frames[id] = {tick.frame(), tick.frame()};
  }
  for (uint32_t id : m.present) {
    if (!present.count(id)) f->add_destroyed(id);
  }
  if (keyframe) {
    for (uint32_t id : present) f->add_present(id);
  }
  for (uint32_t id : present) m.actor_frames[id].second = tick.frame();

  // Events.
  for (const auto* ev : in.events) {
    for (const auto& c : ev->collisions()) {
      auto* o = f->add_collisions();
      o->set_actor(c.actor());
      o->set_other_actor(c.other_actor());
      o->set_other_kind(static_cast<uint32_t>(c.other_kind()));
      o->set_impulse_x(static_cast<float>(c.normal_impulse().x()));
      o->set_impulse_y(static_cast<float>(c.normal_impulse().y()));
      o->set_impulse_z(static_cast<float>(c.normal_impulse().z()));
      o->set_x(static_cast<float>(c.location().x()));
      o->set_y(static_cast<float>(c.location().y()));
      o->set_z(static_cast<float>(c.location().z()));
    }
    for (const auto& l : ev->lane_invasions()) {
      auto* o = f->add_lane_invasions();
      o->set_actor(l.actor());
      for (const auto& c : l.crossed()) o->add_crossed(static_cast<uint32_t>(c.type()));
    }
  }
  for (const auto& [frame, h] : in.hashes) FillHash(f->add_hashes(), frame, h, m.service_names);
  for (const auto& s : in.sensors) {
    auto* o = f->add_sensors();
    o->set_sensor(s.sensor);
    o->set_type(s.type);
    o->set_cdr(s.cdr.data(), s.cdr.size());
    o->set_frame(s.frame);
    SensorStats& st = m.sensor_stats[s.sensor];
    if (st.samples == 0) {
      st.sensor = s.sensor;
      st.type = s.type;
      st.first_frame = s.frame;
    }
    ++st.samples;
    st.bytes += s.cdr.size();
    st.first_frame = std::min(st.first_frame, s.frame);
    st.last_frame = std::max(st.last_frame, s.frame);
  }

  const uint64_t at = m.offset;
  m.Write(r);
  if (m.frames == 0) {
    m.first_frame = tick.frame();
    m.first_sim_time = tick.sim_time();
  } else if (tick.frame() != m.last_frame + 1) {
    throw LogError("recorder: frame " + std::to_string(tick.frame()) + " after frame " + std::to_string(m.last_frame) +
                   " in " + m.path + " (frames must follow each other)");
  }
  m.offsets.push_back(at);
  if (keyframe) m.keyframes.push_back(tick.frame());
  m.sim_times.push_back(tick.sim_time());
  m.last_frame = tick.frame();
  m.last_sim_time = tick.sim_time();
  ++m.frames;
  m.poses = std::move(poses_now);
  m.controls = std::move(controls_now);
  m.present = std::move(present);
  m.slow = std::move(slow_now);
  // A running light's elapsed grows by the next tick's dt; the reader predicts it so.
  m.light_elapsed.clear();
  for (const auto* g : in.ground) {
    for (const auto& l : g->traffic_lights()) m.light_elapsed[l.actor()] = l.frozen() ? l.elapsed() : l.elapsed() + tick.dt();
  }
}

void LogWriter::Close(const std::string& reason, const std::vector<std::pair<uint64_t, FrameHashes>>& late_hashes) {
  Impl& m = *impl_;
  if (m.closed) return;
  m.closed = true;
  log::Record r;
  auto* f = r.mutable_footer();
  f->set_first_frame(m.first_frame);
  f->set_last_frame(m.last_frame);
  f->set_duration(m.frames ? m.last_sim_time - m.first_sim_time : 0);
  for (uint64_t o : m.offsets) f->add_offsets(o);
  for (uint64_t k : m.keyframes) f->add_keyframes(k);
  for (const auto& [frame, h] : late_hashes) FillHash(f->add_hashes(), frame, h, m.service_names);
  f->set_stop_reason(reason);
  for (const auto& [id, a] : m.actors) {
    *f->add_actors() = a;
    f->add_actor_first_frame(m.actor_frames[id].first);
    f->add_actor_last_frame(m.actor_frames[id].second);
  }
  for (double t : m.sim_times) f->add_sim_times(t);
  for (const auto& [id, st] : m.sensor_stats) {
    auto* o = f->add_sensor_stats();
    o->set_sensor(id);
    o->set_type(st.type);
    o->set_samples(st.samples);
    o->set_bytes(st.bytes);
    o->set_first_frame(st.first_frame);
    o->set_last_frame(st.last_frame);
  }
  const uint64_t at = m.offset;
  m.Write(r);
  uint8_t trailer[16];
  for (int i = 0; i < 8; ++i) trailer[i] = static_cast<uint8_t>(at >> (8 * i));
  std::memcpy(trailer + 8, kTrailerTag, 8);
  if (std::fwrite(trailer, 1, sizeof trailer, m.file) != sizeof trailer || std::fflush(m.file) != 0) {
    throw LogError("recorder: cannot write " + m.path + ": " + std::strerror(errno));
  }
  m.offset += sizeof trailer;
  std::fclose(m.file);
  m.file = nullptr;
}

}  // namespace lockstep::recorder
