#include "lockstep/recorder/log_reader.h"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <set>

#include "lockstep/recorder/log_writer.h"
#include "lockstep_log.pb.h"
#include "log_format.h"

namespace lockstep::recorder {

using namespace detail;

std::string ActorInfo::Attribute(const std::string& key) const {
  for (const auto& [k, v] : attributes) {
    if (k == key) return v;
  }
  return {};
}

msg::Pose ActorState::pose() const {
  msg::Pose p;
  p.position().x(x);
  p.position().y(y);
  p.position().z(z);
  p.orientation(QuatOf(roll, pitch, yaw));
  return p;
}

const ActorState* LogFrame::Find(uint32_t id) const {
  auto it = std::lower_bound(actors.begin(), actors.end(), id, [](const ActorState& a, uint32_t v) { return a.id < v; });
  return it != actors.end() && it->id == id ? &*it : nullptr;
}

int CarlaActorType(msg::ActorKind kind) {
  switch (kind) {
    case msg::ActorKind::ACTOR_VEHICLE: return 1;
    case msg::ActorKind::ACTOR_WALKER: return 2;
    case msg::ActorKind::ACTOR_TRAFFIC_LIGHT: return 3;
    case msg::ActorKind::ACTOR_TRAFFIC_SIGN: return 4;
    case msg::ActorKind::ACTOR_SENSOR: return 5;
    default: return 0;
  }
}

namespace {

ActorInfo FromProto(const log::ActorInfo& a) {
  ActorInfo o;
  o.id = a.id();
  o.blueprint = a.blueprint();
  o.kind = static_cast<msg::ActorKind>(a.kind());
  o.parent = a.parent();
  o.owner = a.owner();
  for (const auto& at : a.attributes()) o.attributes.emplace_back(at.id(), at.value());
  o.half_extents[0] = a.half_x();
  o.half_extents[1] = a.half_y();
  o.half_extents[2] = a.half_z();
  o.spawn_pose.position().x(a.x());
  o.spawn_pose.position().y(a.y());
  o.spawn_pose.position().z(a.z());
  o.spawn_pose.orientation().w(a.qw());
  o.spawn_pose.orientation().x(a.qx());
  o.spawn_pose.orientation().y(a.qy());
  o.spawn_pose.orientation().z(a.qz());
  return o;
}

FrameHashes FromProto(const log::FrameHash& h, const std::vector<ServiceInfo>& services) {
  FrameHashes o;
  o.world_hash = h.world_hash();
  o.diverged = h.diverged();
  for (const auto& s : h.services()) o.services.emplace_back(s.service(), s.state_hash());
  for (int i = 0; i < h.service_hashes_size() && i < static_cast<int>(services.size()); ++i) {
    o.services.emplace_back(services[static_cast<size_t>(i)].name, h.service_hashes(i));
  }
  std::sort(o.services.begin(), o.services.end());
  return o;
}

// The actors' state carried from frame to frame while reading.
struct Quantised {
  int64_t v[6] = {0, 0, 0, 0, 0, 0};
};
struct Tracked {
  ActorState state;
  Quantised q;                    // this frame's value
  Quantised q1, q2;               // one and two frames before
  int n = 0;                      // how many of q1, q2 count (the writer's rule)
  bool posed = false;
  bool moved_from_known = false;  // had a pose the frame before (velocity defined)
  Quantised prev;
  int32_t ctl[3] = {0, 0, 0};     // throttle, steer, brake in 1/1000
  bool has_ctl = false;
};

}  // namespace

struct LogReader::Impl {
  std::string path;
  FILE* file = nullptr;
  uint64_t size = 0;
  LogHeader header;
  std::map<uint32_t, ActorInfo> actors;
  std::vector<uint64_t> offsets;      // by frame - first
  std::vector<double> sim_times;      // by frame - first
  std::vector<uint64_t> keyframes;    // frames, ascending
  std::map<uint64_t, FrameHashes> late_hashes;  // from the footer
  std::vector<SensorStats> sensor_stats;        // by sensor id
  uint64_t first = 0;
  uint64_t frames_start = 0;  // offset of the first frame record
  bool truncated = true;
  std::string stop_reason;
  std::string scratch;

  ~Impl() {
    if (file != nullptr) std::fclose(file);
  }

  [[noreturn]] void Fail(const std::string& what) const { throw LogError("log " + path + ": " + what); }

  // Reads the record at `at`; false if the file ends inside it or it does not parse.
  bool ReadRecord(uint64_t at, log::Record* r, uint64_t* next) {
    if (at >= size) return false;
    if (std::fseek(file, static_cast<long>(at), SEEK_SET) != 0) return false;
    uint64_t len = 0;
    int shift = 0;
    uint64_t pos = at;
    for (;;) {
      const int c = std::fgetc(file);
      if (c == EOF || shift > 63) return false;
      ++pos;
      len |= static_cast<uint64_t>(c & 0x7f) << shift;
      if ((c & 0x80) == 0) break;
      shift += 7;
    }
    if (pos + len > size) return false;
    scratch.resize(len);
    if (len > 0 && std::fread(scratch.data(), 1, len, file) != len) return false;
    if (!r->ParseFromString(scratch)) return false;
    *next = pos + len;
    return true;
  }

  void Open() {
    file = std::fopen(path.c_str(), "rb");
    if (file == nullptr) Fail(std::string("cannot open: ") + std::strerror(errno));
    std::fseek(file, 0, SEEK_END);
    size = static_cast<uint64_t>(std::ftell(file));
    char magic[8] = {};
    std::fseek(file, 0, SEEK_SET);
    if (size < sizeof magic || std::fread(magic, 1, sizeof magic, file) != sizeof magic ||
        std::memcmp(magic, kMagic, sizeof magic) != 0) {
      Fail("not a Lockstep log (no LSLOG magic at its start)");
    }
    log::Record r;
    uint64_t next = 0;
    if (!ReadRecord(sizeof kMagic, &r, &next) || !r.has_header()) Fail("no header record (the file is cut short or damaged)");
    ReadHeader(r.header());
    frames_start = next;
    // A closed log: the trailer points at the footer with the index.
    if (size >= frames_start + 16) {
      uint8_t trailer[16];
      std::fseek(file, static_cast<long>(size - 16), SEEK_SET);
      if (std::fread(trailer, 1, 16, file) == 16 && std::memcmp(trailer + 8, kTrailerTag, 8) == 0) {
        uint64_t at = 0;
        for (int i = 0; i < 8; ++i) at |= static_cast<uint64_t>(trailer[i]) << (8 * i);
        log::Record fr;
        uint64_t end = 0;
        if (ReadRecord(at, &fr, &end) && fr.has_footer() && end + 16 == size) {
          ReadFooter(fr.footer());
          return;
        }
      }
    }
    Scan(frames_start);
  }

  void ReadHeader(const log::Header& h) {
    header.format_version = h.format_version();
    if (header.format_version != kFormatVersion) {
      Fail("format version " + std::to_string(header.format_version) + "; this build reads version " + std::to_string(kFormatVersion));
    }
    header.name = h.name();
    header.config_text = h.config_text();
    header.config_source = h.config_source();
    header.map_name = h.map_name();
    header.map_digest = h.map_digest();
    header.seed = h.seed();
    header.run = h.run();
    try {
      if (!h.world_info_cdr().empty()) header.world = FromCdr<msg::WorldInfo>(h.world_info_cdr().data(), h.world_info_cdr().size());
      for (const auto& t : h.prelude_ticks_cdr()) header.prelude.push_back(FromCdr<msg::Tick>(t.data(), t.size()));
    } catch (const std::exception& e) {
      Fail(std::string("damaged header: ") + e.what());
    }
    for (const auto& s : h.services()) {
      ServiceInfo o;
      o.name = s.name();
      o.kind = s.kind();
      o.required = s.required();
      o.perception = s.perception();
      for (const auto& b : s.blueprints()) o.blueprints.emplace_back(b.id(), static_cast<msg::ActorKind>(b.kind()));
      o.blueprint_set_cdr.assign(s.blueprint_set_cdr().begin(), s.blueprint_set_cdr().end());
      header.services.push_back(std::move(o));
    }
    header.first_frame = h.first_frame();
    header.first_sim_time = h.first_sim_time();
    header.start_unix_time = h.start_unix_time();
    header.additional_data = h.additional_data();
    header.keyframe_period = h.keyframe_period();
    header.position_quantum = h.position_quantum();
    header.angle_quantum = h.angle_quantum();
    header.sensors.assign(h.sensors().begin(), h.sensors().end());
    header.sensor_selection = h.sensor_selection();
    header.prelude_frames = h.prelude_frames();
  }

  void ReadFooter(const log::Footer& f) {
    truncated = false;
    stop_reason = f.stop_reason();
    first = f.first_frame();
    offsets.assign(f.offsets().begin(), f.offsets().end());
    sim_times.assign(f.sim_times().begin(), f.sim_times().end());
    keyframes.assign(f.keyframes().begin(), f.keyframes().end());
    if (sim_times.size() != offsets.size()) Fail("damaged footer (index and times differ in length)");
    for (int i = 0; i < f.actors_size(); ++i) {
      ActorInfo a = FromProto(f.actors(i));
      a.first_frame = i < f.actor_first_frame_size() ? f.actor_first_frame(i) : first;
      a.last_frame = i < f.actor_last_frame_size() ? f.actor_last_frame(i) : first + offsets.size() - 1;
      actors[a.id] = std::move(a);
    }
    for (const auto& h : f.hashes()) late_hashes[h.frame()] = FromProto(h, header.services);
    for (const auto& st : f.sensor_stats()) {
      sensor_stats.push_back(SensorStats{st.sensor(), st.type(), st.samples(), st.bytes(), st.first_frame(), st.last_frame()});
    }
  }

  // No footer: every whole record in turn, up to the first one cut short.
  void Scan(uint64_t at) {
    log::Record r;
    uint64_t next = 0;
    std::set<uint32_t> alive;
    std::map<uint32_t, SensorStats> stats;
    while (ReadRecord(at, &r, &next)) {
      if (r.has_footer()) break;
      if (!r.has_frame()) break;
      const auto& f = r.frame();
      if (offsets.empty()) first = f.frame();
      if (f.frame() != first + offsets.size()) break;  // not the next frame: damaged
      offsets.push_back(at);
      sim_times.push_back(f.sim_time());
      if (f.keyframe()) keyframes.push_back(f.frame());
      for (const auto& s : f.spawned()) {
        ActorInfo a = FromProto(s);
        a.first_frame = f.frame();
        actors[a.id] = std::move(a);
        alive.insert(s.id());
      }
      for (uint32_t d : f.destroyed()) alive.erase(d);
      for (uint32_t id : alive) actors[id].last_frame = f.frame();
      for (const auto& s : f.sensors()) {
        SensorStats& st = stats[s.sensor()];
        if (st.samples == 0) {
          st.sensor = s.sensor();
          st.type = s.type();
          st.first_frame = s.frame();
        }
        ++st.samples;
        st.bytes += s.cdr().size();
        st.first_frame = std::min(st.first_frame, s.frame());
        st.last_frame = std::max(st.last_frame, s.frame());
      }
      at = next;
    }
    for (auto& [id, st] : stats) sensor_stats.push_back(std::move(st));
    if (!offsets.empty() && (keyframes.empty() || keyframes.front() != first)) Fail("damaged: the first frame is not a keyframe");
  }

  uint64_t last() const { return offsets.empty() ? 0 : first + offsets.size() - 1; }

  log::Frame FrameRecord(uint64_t frame) {
    log::Record r;
    uint64_t next = 0;
    if (!ReadRecord(offsets.at(frame - first), &r, &next) || !r.has_frame() || r.frame().frame() != frame) {
      Fail("damaged record of frame " + std::to_string(frame));
    }
    return std::move(*r.mutable_frame());
  }

  // Applies record `f` to `state` and builds its LogFrame.
  void Apply(const log::Frame& f, std::map<uint32_t, Tracked>* state, double prev_dt, LogFrame* out) {
    auto& st = *state;
    for (auto& [id, t] : st) {
      t.prev = t.q;
      t.moved_from_known = t.posed;
      // The prediction (the writer's rule); a listed residual is added below.
      if (!f.keyframe() && t.n == 1) t.q = t.q1;
      if (!f.keyframe() && t.n >= 2) {
        for (int k = 0; k < 6; ++k) t.q.v[k] = 2 * t.q1.v[k] - t.q2.v[k];
      }
    }
    for (uint32_t d : f.destroyed()) st.erase(d);
    if (f.keyframe()) {
      // A keyframe lists every live actor: a reader may start here.
      std::set<uint32_t> live(f.present().begin(), f.present().end());
      std::erase_if(st, [&](const auto& e) { return !live.count(e.first); });
      for (uint32_t id : live) {
        if (st.count(id)) continue;
        Tracked t;
        t.state.id = id;
        if (auto a = actors.find(id); a != actors.end()) t.state.kind = a->second.kind;
        st[id] = t;
      }
    }
    for (const auto& s : f.spawned()) {
      Tracked t;
      t.state.id = s.id();
      t.state.kind = static_cast<msg::ActorKind>(s.kind());
      st[s.id()] = t;
    }
    // Running lights' elapsed time grows by the dt before, unless a record says otherwise.
    for (auto& [id, t] : st) {
      if (t.state.kind == msg::ActorKind::ACTOR_TRAFFIC_LIGHT && !t.state.frozen) t.state.elapsed += prev_dt;
    }
    const auto& p = f.poses();
    uint32_t id = 0;
    std::set<uint32_t> listed;
    for (int i = 0; i < p.id_delta_size(); ++i) {
      id += p.id_delta(i);
      auto it = st.find(id);
      if (it == st.end()) Fail("frame " + std::to_string(f.frame()) + ": a pose of actor " + std::to_string(id) + ", which it does not list");
      Tracked& t = it->second;
      const bool absolute = f.keyframe() || t.n == 0;
      const int64_t d[6] = {p.x(i), p.y(i), p.z(i), p.roll(i), p.pitch(i), p.yaw(i)};
      for (int k = 0; k < 6; ++k) t.q.v[k] = absolute ? d[k] : t.q.v[k] + d[k];
      t.posed = true;
      listed.insert(id);
    }
    // The history of every posed actor moves on by a frame.
    for (auto& [aid, t] : st) {
      if (!t.posed) continue;
      if (t.n == 0 && !listed.count(aid)) continue;
      t.q2 = t.q1;
      t.q1 = t.q;
      t.n = f.keyframe() ? 1 : std::min(t.n + 1, 2);
    }
    const auto& ctl = f.controls();
    uint32_t cid = 0;
    for (int i = 0; i < ctl.id_delta_size(); ++i) {
      cid += ctl.id_delta(i);
      auto it = st.find(cid);
      if (it == st.end()) continue;
      Tracked& t = it->second;
      const bool absolute = f.keyframe() || !t.has_ctl;
      const int32_t d[3] = {ctl.throttle(i), ctl.steer(i), ctl.brake(i)};
      for (int k = 0; k < 3; ++k) t.ctl[k] = absolute ? d[k] : t.ctl[k] + d[k];
      t.has_ctl = true;
      t.state.throttle = static_cast<float>(t.ctl[0] / 1000.0);
      t.state.steer = static_cast<float>(t.ctl[1] / 1000.0);
      t.state.brake = static_cast<float>(t.ctl[2] / 1000.0);
    }
    for (const auto& v : f.vehicles()) {
      if (auto it = st.find(v.id()); it != st.end()) {
        auto& s = it->second.state;
        s.hand_brake = v.hand_brake();
        s.reverse = v.reverse();
        s.gear = v.gear();
        s.light_state = v.light_state();
        s.autopilot = v.autopilot();
      }
    }
    for (const auto& w : f.walkers()) {
      if (auto it = st.find(w.id()); it != st.end()) {
        it->second.state.speed = w.speed();
        it->second.state.ai_controlled = w.ai_controlled();
      }
    }
    for (const auto& l : f.traffic_lights()) {
      if (auto it = st.find(l.id()); it != st.end()) {
        auto& s = it->second.state;
        s.light = static_cast<msg::TrafficLightColor>(l.state());
        s.frozen = l.frozen();
        s.elapsed = l.elapsed();
        s.green_time = l.green_time();
        s.yellow_time = l.yellow_time();
        s.red_time = l.red_time();
      }
    }
    for (const auto& d : f.drones()) {
      if (auto it = st.find(d.id()); it != st.end()) {
        auto& s = it->second.state;
        s.landed = d.landed();
        s.armed = d.armed();
        s.command_id = d.command_id();
        s.command_status = d.command_status();
        s.api_control = d.api_control();
      }
    }
    if (out == nullptr) return;
    out->frame = f.frame();
    out->sim_time = f.sim_time();
    out->dt = f.dt();
    out->elapsed = f.sim_time() - sim_times.front();
    out->keyframe = f.keyframe();
    out->state_frame = f.state_frame();
    try {
      out->tick = FromCdr<msg::Tick>(f.tick_cdr().data(), f.tick_cdr().size());
    } catch (const std::exception& e) {
      Fail("frame " + std::to_string(f.frame()) + ": damaged tick: " + e.what());
    }
    const double pq = header.position_quantum, aq = header.angle_quantum;
    out->actors.clear();
    out->actors.reserve(st.size());
    for (auto& [aid, t] : st) {
      ActorState s = t.state;
      if (t.posed) {
        s.x = t.q.v[0] * pq;
        s.y = t.q.v[1] * pq;
        s.z = t.q.v[2] * pq;
        s.roll = t.q.v[3] * aq;
        s.pitch = t.q.v[4] * aq;
        s.yaw = t.q.v[5] * aq;
        if (t.moved_from_known && f.dt() > 0) {
          s.vx = (t.q.v[0] - t.prev.v[0]) * pq / f.dt();
          s.vy = (t.q.v[1] - t.prev.v[1]) * pq / f.dt();
          s.vz = (t.q.v[2] - t.prev.v[2]) * pq / f.dt();
        }
      }
      out->actors.push_back(s);
    }
    out->spawned.clear();
    for (const auto& s : f.spawned()) out->spawned.push_back(s.id());
    out->destroyed.assign(f.destroyed().begin(), f.destroyed().end());
    out->collisions.clear();
    for (const auto& c : f.collisions()) {
      CollisionRecord r;
      r.actor = c.actor();
      r.other_actor = c.other_actor();
      r.other_kind = static_cast<msg::ObjectKind>(c.other_kind());
      r.impulse[0] = c.impulse_x();
      r.impulse[1] = c.impulse_y();
      r.impulse[2] = c.impulse_z();
      r.location[0] = c.x();
      r.location[1] = c.y();
      r.location[2] = c.z();
      out->collisions.push_back(r);
    }
    out->lane_invasions.clear();
    for (const auto& l : f.lane_invasions()) out->lane_invasions.push_back(LaneInvasionRecord{l.actor(), {l.crossed().begin(), l.crossed().end()}});
    out->infractions.clear();
    for (const auto& i : f.infractions()) out->infractions.push_back(InfractionRecord{i.actor(), static_cast<Infraction>(i.kind()), i.count()});
    out->sensors.clear();
    for (const auto& s : f.sensors()) out->sensors.push_back(SensorRecord{s.sensor(), s.type(), {s.cdr().begin(), s.cdr().end()}, s.frame()});
    out->hashes.reset();
  }

  // The keyframe at or before `frame`.
  uint64_t KeyframeAtOrBefore(uint64_t frame) const {
    auto it = std::upper_bound(keyframes.begin(), keyframes.end(), frame);
    if (it == keyframes.begin()) return first;
    return *(it - 1);
  }

  // Hashes of `frame`: carried by the next record, or by the footer for the last one.
  std::optional<FrameHashes> HashesOf(uint64_t frame, const log::Frame* next) {
    if (next != nullptr) {
      for (const auto& h : next->hashes()) {
        if (h.frame() == frame) return FromProto(h, header.services);
      }
    }
    if (auto it = late_hashes.find(frame); it != late_hashes.end()) return it->second;
    // A FrameDone that came late rides on a later record: look a few ahead.
    for (uint64_t k = frame + 2; k <= last() && k <= frame + 8; ++k) {
      const log::Frame later = FrameRecord(k);
      for (const auto& h : later.hashes()) {
        if (h.frame() == frame) return FromProto(h, header.services);
      }
    }
    return std::nullopt;
  }
};

LogReader::LogReader(const std::string& path) : impl_(std::make_unique<Impl>()) {
  impl_->path = path;
  impl_->Open();
}
LogReader::~LogReader() = default;
LogReader::LogReader(LogReader&&) noexcept = default;
LogReader& LogReader::operator=(LogReader&&) noexcept = default;

const std::string& LogReader::path() const { return impl_->path; }
const LogHeader& LogReader::header() const { return impl_->header; }
const std::map<uint32_t, ActorInfo>& LogReader::actors() const { return impl_->actors; }
bool LogReader::empty() const { return impl_->offsets.empty(); }
uint64_t LogReader::first_frame() const { return impl_->offsets.empty() ? 0 : impl_->first; }
uint64_t LogReader::last_frame() const { return impl_->last(); }
uint64_t LogReader::frame_count() const { return impl_->offsets.size(); }
double LogReader::duration() const {
  return impl_->sim_times.empty() ? 0.0 : impl_->sim_times.back() - impl_->sim_times.front();
}
bool LogReader::truncated() const { return impl_->truncated; }
std::string LogReader::stop_reason() const { return impl_->stop_reason; }
uint64_t LogReader::file_size() const { return impl_->size; }
uint64_t LogReader::header_bytes() const { return impl_->frames_start; }
const std::vector<SensorStats>& LogReader::sensor_stats() const { return impl_->sensor_stats; }

double LogReader::SimTime(uint64_t frame) const {
  if (impl_->offsets.empty() || frame < impl_->first || frame > impl_->last()) {
    impl_->Fail("no frame " + std::to_string(frame) + " (the log has frames " + std::to_string(first_frame()) + ".." +
                std::to_string(last_frame()) + ")");
  }
  return impl_->sim_times[frame - impl_->first];
}

uint64_t LogReader::FrameAtElapsed(double t) const {
  const auto& st = impl_->sim_times;
  if (st.empty()) return 0;
  const double target = st.front() + t;
  auto it = std::upper_bound(st.begin(), st.end(), target + 1e-9);
  if (it == st.begin()) return impl_->first;
  return impl_->first + static_cast<uint64_t>(it - st.begin()) - 1;
}

LogFrame LogReader::Read(uint64_t frame) {
  LogFrame out;
  bool found = false;
  ForEach(frame, frame, [&](const LogFrame& f) {
    out = f;
    found = true;
    return false;
  });
  if (!found) {
    impl_->Fail("no frame " + std::to_string(frame) + " (the log has frames " + std::to_string(first_frame()) + ".." +
                std::to_string(last_frame()) + ")");
  }
  return out;
}

void LogReader::ForEach(uint64_t from, uint64_t to, const std::function<bool(const LogFrame&)>& fn,
                        const std::function<void(uint64_t, uint64_t)>& progress) {
  Impl& m = *impl_;
  if (m.offsets.empty()) return;
  from = std::max(from, m.first);
  to = std::min(to, m.last());
  if (from > to) {
    if (from > m.last()) m.Fail("no frame " + std::to_string(from) + " (the log ends at frame " + std::to_string(m.last()) + ")");
    return;
  }
  // Start at the keyframe before the frame before `from` (velocities need it).
  const uint64_t start = m.KeyframeAtOrBefore(from > m.first ? from - 1 : from);
  std::map<uint32_t, Tracked> state;
  double prev_dt = 0;
  LogFrame frame;
  log::Frame current = m.FrameRecord(start);
  const uint64_t total = to - from + 1;
  for (uint64_t k = start; k <= to; ++k) {
    const bool emit = k >= from;
    m.Apply(current, &state, prev_dt, emit ? &frame : nullptr);
    prev_dt = current.dt();
    log::Frame next;
    const bool have_next = k < m.last();
    if (have_next) next = m.FrameRecord(k + 1);
    if (emit) {
      frame.hashes = m.HashesOf(k, have_next ? &next : nullptr);
      if (!fn(frame)) return;
      if (progress && ((k - from) % 256 == 0 || k == to)) progress(k - from + 1, total);
    }
    if (!have_next) break;
    current = std::move(next);
  }
}

void LogReader::ForEachTick(uint64_t from, uint64_t to,
                            const std::function<bool(uint64_t, const std::string&, const std::optional<FrameHashes>&)>& fn) {
  Impl& m = *impl_;
  if (m.offsets.empty()) return;
  from = std::max(from, m.first);
  to = std::min(to, m.last());
  if (from > to) return;
  log::Frame current = m.FrameRecord(from);
  for (uint64_t k = from; k <= to; ++k) {
    log::Frame next;
    const bool have_next = k < m.last();
    if (have_next) next = m.FrameRecord(k + 1);
    if (!fn(k, current.tick_cdr(), m.HashesOf(k, have_next ? &next : nullptr))) return;
    if (!have_next) break;
    current = std::move(next);
  }
}

}  // namespace lockstep::recorder
