#pragma once
// Reads a Lockstep log (idl/proto/lockstep_log.proto, docs/recorder.md): the header, and
// any frame's full state in O(keyframe period) through the index (frame -> offset). A log
// cut short by a crash (no footer) is scanned on open and reads up to its last whole frame.
// Plain C++ (no DDS, no protobuf in this header); thread-compatible (one reader per thread).
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "lockstep/msg/blueprint.h"
#include "lockstep/msg/clock.h"
#include "lockstep/msg/world.h"
#include "lockstep/recorder/recordings.h"  // RecordingsDir, ResolveLogPath

namespace lockstep::recorder {

// A file that is not a Lockstep log, unreadable, or a frame outside the log; the message
// names the file and what is wrong.
class LogError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct ServiceInfo {
  std::string name;
  std::string kind;
  bool required = true;
  bool perception = false;
  std::vector<std::pair<std::string, msg::ActorKind>> blueprints;  // (id, kind) it declared
  std::vector<uint8_t> blueprint_set_cdr;  // its whole msg::BlueprintSet, CDR (empty if unknown)
};

struct LogHeader {
  uint32_t format_version = 1;
  std::string name;             // absolute path the recorder wrote
  std::string config_text;      // the run's launch config (YAML)
  std::string config_source;    // the file it came from
  std::string map_name;
  uint64_t map_digest = 0;      // WorldInfo.map_hash
  uint64_t seed = 0;
  uint32_t run = 0;
  msg::WorldInfo world;         // as the coordinator published it
  std::vector<ServiceInfo> services;
  uint64_t first_frame = 0;
  double first_sim_time = 0;    // s
  int64_t start_unix_time = 0;  // s, wall clock at the start (information only)
  bool additional_data = false;
  uint32_t keyframe_period = 0;
  double position_quantum = 0.001;  // m
  double angle_quantum = 1e-4;      // rad
  std::vector<uint32_t> sensors;    // chosen sensors alive at the first frame (sensor_stats(): all)
  std::string sensor_selection;     // what chose them: --record-sensors, "all" (additional_data), "" none
  std::vector<msg::Tick> prelude;   // the run's earlier ticks with commands (mid-run start)
  uint64_t prelude_frames = 0;      // frames 1..prelude_frames precede the log's first frame
};

// An actor of the log: spawned while recording, or alive when it started.
struct ActorInfo {
  uint32_t id = 0;
  std::string blueprint;
  msg::ActorKind kind = msg::ActorKind::ACTOR_OTHER;
  uint32_t parent = 0;
  std::string owner;
  std::vector<std::pair<std::string, std::string>> attributes;  // (id, value)
  double half_extents[3] = {0, 0, 0};  // m
  msg::Pose spawn_pose;                // as spawned (sensors: relative to the parent)
  uint64_t first_frame = 0;            // first frame of the log it is in
  uint64_t last_frame = 0;             // last frame it is in (the log's last if never destroyed)
  std::string Attribute(const std::string& key) const;  // "" if it has none
};

// One actor in one frame. Poses are quantised (docs/recorder.md): position to
// LogHeader::position_quantum, angles to angle_quantum; velocity is the pose change over
// the frame before divided by dt (0 in an actor's first frame).
struct ActorState {
  uint32_t id = 0;
  msg::ActorKind kind = msg::ActorKind::ACTOR_OTHER;
  double x = 0, y = 0, z = 0;           // m, world ENU, box centre (drones: centre of mass)
  double roll = 0, pitch = 0, yaw = 0;  // rad, ENU, ZYX
  double vx = 0, vy = 0, vz = 0;        // m/s, world
  // vehicles
  float throttle = 0, steer = 0, brake = 0;
  bool hand_brake = false, reverse = false, autopilot = false;
  int32_t gear = 0;
  uint32_t light_state = 0;
  // walkers
  float speed = 0;
  bool ai_controlled = false;
  // traffic lights
  msg::TrafficLightColor light = msg::TrafficLightColor::LIGHT_UNKNOWN;
  bool frozen = false;
  double elapsed = 0;
  double green_time = 0, yellow_time = 0, red_time = 0;
  // drones
  bool landed = true, armed = false, api_control = false;
  uint64_t command_id = 0;
  uint32_t command_status = 0;
  msg::Pose pose() const;  // the quantised pose as a quaternion
};

struct CollisionRecord {
  uint32_t actor = 0;
  uint32_t other_actor = 0;  // 0 = static geometry
  msg::ObjectKind other_kind = msg::ObjectKind::OBJECT_NONE;
  double impulse[3] = {0, 0, 0};   // N s
  double location[3] = {0, 0, 0};  // m
};

struct LaneInvasionRecord {
  uint32_t actor = 0;
  std::vector<uint32_t> crossed;  // msg::LaneMarkingType values
};

enum class Infraction { kRedLight, kStopSign, kCollision, kOppositeLane, kOffroad };
struct InfractionRecord {
  uint32_t actor = 0;
  Infraction kind = Infraction::kCollision;
  uint32_t count = 1;
};

struct FrameHashes {
  uint64_t world_hash = 0;
  bool diverged = false;
  std::vector<std::pair<std::string, uint64_t>> services;  // (service, state hash), name order
};

// One output of a recorded sensor, as published: the message bit for bit as CDR
// (lockstep::recorder::FromCdr<msg::Image> etc., log_writer.h).
struct SensorRecord {
  uint32_t sensor = 0;
  std::string type;           // message type name: "Image", "LargeImage", "PointCloud", "Imu", ...
  std::vector<uint8_t> cdr;   // the sample, CDR
  uint64_t frame = 0;         // the frame it shows (its stamp)
};

// What a log holds of one sensor.
struct SensorStats {
  uint32_t sensor = 0;
  std::string type;
  uint64_t samples = 0;
  uint64_t bytes = 0;         // CDR bytes
  uint64_t first_frame = 0;   // frames its first and last samples show
  uint64_t last_frame = 0;
};

// A frame with the full state of every actor (deltas applied).
struct LogFrame {
  uint64_t frame = 0;
  double sim_time = 0;     // s
  double dt = 0;           // s
  double elapsed = 0;      // s since the log's first frame (CARLA's "Frame N at T seconds")
  bool keyframe = false;
  uint64_t state_frame = 0;  // the frame the states show (frame, or frame - 1 when pipelined)
  msg::Tick tick;            // the tick, bit for bit: its commands in acceptance order
  std::vector<ActorState> actors;  // every actor of this frame, by id
  std::vector<uint32_t> spawned;   // actors new in this frame
  std::vector<uint32_t> destroyed; // actors gone since the frame before
  std::vector<CollisionRecord> collisions;
  std::vector<LaneInvasionRecord> lane_invasions;
  std::vector<InfractionRecord> infractions;
  std::optional<FrameHashes> hashes;  // FrameDone of this frame (none if the run stopped first)
  // The chosen sensors' outputs that show this frame's state frame (and any that reached the
  // recorder after their own frame was written: see SensorRecord::frame).
  std::vector<SensorRecord> sensors;
  const ActorState* Find(uint32_t id) const;
};

class LogReader {
 public:
  // Opens and indexes `path` (a name as given: ResolveLogPath is the caller's). Throws
  // LogError naming the file and the problem (missing, not a log, no header).
  explicit LogReader(const std::string& path);
  ~LogReader();
  LogReader(LogReader&&) noexcept;
  LogReader& operator=(LogReader&&) noexcept;

  const std::string& path() const;
  const LogHeader& header() const;
  // The actors of the whole log by id (spawn descriptions, first and last frames).
  const std::map<uint32_t, ActorInfo>& actors() const;

  bool empty() const;            // no whole frame
  uint64_t first_frame() const;  // 0 when empty
  uint64_t last_frame() const;   // the last whole frame
  uint64_t frame_count() const;
  double duration() const;       // s, sim time from the first to the last frame
  // True when the log has no footer (the recorder did not close it: a crash, or still
  // recording); it was read up to its last whole frame.
  bool truncated() const;
  std::string stop_reason() const;  // the footer's ("stopped", "run ended", ...); "" if truncated
  uint64_t file_size() const;       // bytes
  uint64_t header_bytes() const;    // bytes before the first frame (magic and header)
  // Every sensor with recorded outputs, by id (from the footer; a truncated log: its scan).
  const std::vector<SensorStats>& sensor_stats() const;

  // Frame `frame` (first_frame() .. last_frame()) with every actor's state: reads from the
  // keyframe at or before it (at most keyframe_period records). Throws LogError outside.
  LogFrame Read(uint64_t frame);
  // Sim time of `frame` from the index (no read). Throws LogError outside the log.
  double SimTime(uint64_t frame) const;
  // The last frame whose elapsed time (s since the first frame) is <= t (clamped to the log).
  uint64_t FrameAtElapsed(double t) const;
  // Frames from..to (inclusive, clamped) in order, each with full state; cheaper than Read
  // per frame. `fn` returns false to stop. `progress(done, total)` is called now and then.
  void ForEach(uint64_t from, uint64_t to, const std::function<bool(const LogFrame&)>& fn,
               const std::function<void(uint64_t, uint64_t)>& progress = {});
  void ForEach(const std::function<bool(const LogFrame&)>& fn) { ForEach(0, UINT64_MAX, fn); }
  // Only the ticks (as CDR bytes, bit for bit) and the hashes, frame by frame, without the
  // states: for re-simulation and diff. `fn(frame, tick_cdr, hashes)` returns false to stop.
  void ForEachTick(uint64_t from, uint64_t to,
                   const std::function<bool(uint64_t, const std::string&, const std::optional<FrameHashes>&)>& fn);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// msg::ActorKind as CARLA's recorder types it (0 other, 1 vehicle, 2 walker, 3 traffic
// light, 4 traffic sign, 5 sensor).
int CarlaActorType(msg::ActorKind kind);

}  // namespace lockstep::recorder
