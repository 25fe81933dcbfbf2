// Playback's view of a recorder log (lockstep::recorder::LogReader): frames by index, the
// actors alive at a frame, and each frame's poses and light states. Frames are read in
// windows (one ForEach from a keyframe per window), so a replay reads the log about once.
#include <algorithm>
#include <deque>

#include "lockstep/recorder/log_reader.h"
#include "lockstep/runtime/error.h"
#include "playback.h"

namespace lockstep {
namespace {

constexpr uint64_t kWindow = 256;  // frames read at once

bool HasPose(msg::ActorKind k) {
  return k == msg::ActorKind::ACTOR_VEHICLE || k == msg::ActorKind::ACTOR_WALKER || k == msg::ActorKind::ACTOR_DRONE ||
         k == msg::ActorKind::ACTOR_PROP || k == msg::ActorKind::ACTOR_OTHER;
}

class RecordedLog final : public PlaybackLog {
 public:
  explicit RecordedLog(const std::string& path) : reader_(path) {
    first_ = reader_.first_frame();
    t0_ = reader_.empty() ? 0 : reader_.SimTime(first_);
  }

  std::string Path() const override { return reader_.path(); }
  std::string MapName() const override { return reader_.header().map_name; }
  uint64_t MapHash() const override { return reader_.header().map_digest; }
  size_t Frames() const override { return reader_.empty() ? 0 : static_cast<size_t>(reader_.frame_count()); }
  double Time(size_t index) const override { return reader_.SimTime(first_ + index) - t0_; }

  PlaybackFrame Frame(size_t index) const override {
    const recorder::LogFrame& f = Read(first_ + index);
    PlaybackFrame out;
    out.time = Time(index);
    for (uint32_t id : f.spawned) {
      if (auto a = Actor(id)) out.spawned.push_back(*a);
    }
    out.destroyed = f.destroyed;
    for (const auto& s : f.actors) {
      if (s.kind == msg::ActorKind::ACTOR_TRAFFIC_LIGHT) {
        out.lights.push_back({s.id, s.light});
      } else if (HasPose(s.kind)) {
        out.poses.push_back({s.id, s.pose()});
        if (s.kind == msg::ActorKind::ACTOR_VEHICLE) out.vehicle_lights.push_back({s.id, s.light_state});
      }
    }
    return out;
  }

  std::vector<PlaybackActor> ActorsAt(size_t index) const override {
    const uint64_t frame = first_ + index;
    std::vector<PlaybackActor> out;
    for (const auto& [id, info] : reader_.actors()) {  // id order: a parent before its children
      if (info.first_frame <= frame && info.last_frame >= frame) {
        if (auto a = Actor(id)) out.push_back(*a);
      }
    }
    return out;
  }

 private:
  std::optional<PlaybackActor> Actor(uint32_t id) const {
    auto it = reader_.actors().find(id);
    if (it == reader_.actors().end()) return std::nullopt;
    const recorder::ActorInfo& info = it->second;
    PlaybackActor a;
    a.id = id;
    a.kind = info.kind;
    a.spawn.actor(id);
    a.spawn.blueprint(info.blueprint);
    std::vector<msg::BlueprintAttribute> attrs;
    for (const auto& [k, v] : info.attributes) {
      msg::BlueprintAttribute b;
      b.key(k);
      b.value(v);
      attrs.push_back(b);
    }
    a.spawn.attributes(attrs);
    a.spawn.transform(info.spawn_pose);
    a.spawn.parent(info.parent);
    a.spawn.owner(info.owner);
    return a;
  }

  // The frame, from the window of frames read last (refilled from `frame` when outside).
  const recorder::LogFrame& Read(uint64_t frame) const {
    if (window_.empty() || frame < window_.front().frame || frame > window_.back().frame) {
      window_.clear();
      reader_.ForEach(frame, frame + kWindow - 1, [this](const recorder::LogFrame& f) {
        window_.push_back(f);
        return true;
      });
      if (window_.empty() || window_.front().frame != frame) {
        throw InputError("log '" + reader_.path() + "': frame " + std::to_string(frame) + " could not be read");
      }
    }
    return window_[frame - window_.front().frame];
  }

  mutable recorder::LogReader reader_;
  uint64_t first_ = 0;
  double t0_ = 0;
  mutable std::deque<recorder::LogFrame> window_;
};

}  // namespace

std::string RecordedLogPath(const std::string& name) { return recorder::ResolveLogPath(name); }

std::unique_ptr<PlaybackLog> OpenRecordedLog(const std::string& name) {
  const std::string path = RecordedLogPath(name);
  try {
    return std::make_unique<RecordedLog>(path);
  } catch (const recorder::LogError& e) {
    throw InputError(e.what());
  }
}

}  // namespace lockstep
