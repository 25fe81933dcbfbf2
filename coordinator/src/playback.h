#pragma once
// Playback of a recorded run (CARLA's replay_file): the coordinator follows the log. Each
// tick carries the commands that put every recorded actor at its recorded state of the
// log's time for that tick: recorded actors are spawned (their log ids mapped to new ids,
// or an existing actor of the same id and blueprint is reused, as CARLA's replayer does),
// vehicles with their physics off, every pose set with set_transform, traffic lights set
// and frozen, destroyed actors destroyed. Nothing is simulated from the log: the services
// see ordinary commands in ordinary ticks, so the tick log, a replacement's recovery and
// the world hashes hold as for any run.
//
// Plain logic: the coordinator hands it the REPLAY_* commands it accepted and, for each
// tick, a function that submits a command like a client's and returns the reply.
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "lockstep/msg/blueprint.h"
#include "lockstep/msg/command.h"

namespace lockstep {

// An actor of the log as its spawn described it.
struct PlaybackActor {
  uint32_t id = 0;          // the id in the log
  msg::ActorKind kind = msg::ActorKind::ACTOR_OTHER;
  msg::SpawnActor spawn;    // blueprint, attributes, transform (parent frame when parent != 0), parent (log id)
};

struct PlaybackPose {
  uint32_t id = 0;          // log id
  msg::Pose pose;           // world ENU, as the state of that frame reported it
};

struct PlaybackVehicleLights {
  uint32_t id = 0;          // log id
  uint32_t light_state = 0; // carla.VehicleLightState bits
};

struct PlaybackLight {
  uint32_t id = 0;          // log id (the map's lights: the same ids on the same map)
  msg::TrafficLightColor state = msg::TrafficLightColor::LIGHT_RED;
};

// One frame of the log.
struct PlaybackFrame {
  double time = 0;                      // s from the log's first frame
  std::vector<PlaybackActor> spawned;   // spawned by this frame's tick
  std::vector<uint32_t> destroyed;      // destroyed by this frame's tick (children go with their parent)
  std::vector<PlaybackPose> poses;      // every vehicle, walker, drone and prop of the frame's state
  std::vector<PlaybackLight> lights;    // every traffic light of the frame's state
  std::vector<PlaybackVehicleLights> vehicle_lights;  // every vehicle's light state
};

// What playback reads of a log (an adapter over the recorder's reader; tests give their own).
class PlaybackLog {
 public:
  virtual ~PlaybackLog() = default;
  virtual std::string Path() const = 0;       // the file, as CARLA prints it
  virtual std::string MapName() const = 0;    // the map it was recorded on
  virtual uint64_t MapHash() const = 0;       // WorldInfo.map_hash of that map (0 = unknown)
  virtual size_t Frames() const = 0;          // whole frames in the log (>= 1)
  virtual double Time(size_t index) const = 0;  // s from the first frame, increasing
  virtual PlaybackFrame Frame(size_t index) const = 0;
  // The actors alive after frame `index` (its spawns in, its destroys out), parents first.
  virtual std::vector<PlaybackActor> ActorsAt(size_t index) const = 0;
};

// Opens a log by the name a client gave (relative names in the recordings folder); throws
// InputError naming the file and the reason.
using PlaybackOpener = std::function<std::unique_ptr<PlaybackLog>(const std::string& name)>;
// The file a name stands for (CARLA prints it when the file cannot be opened).
using PlaybackResolver = std::function<std::string(const std::string& name)>;
// Submits a command as a client's: the reply says whether it was accepted (and the new id).
using PlaybackSubmit = std::function<msg::CommandReply(const msg::CommandBody& body)>;

// The recorder's logs (playback_log.cpp, over lockstep::recorder::LogReader): a name
// resolves as start_recorder's (relative: the recordings folder).
std::unique_ptr<PlaybackLog> OpenRecordedLog(const std::string& name);
std::string RecordedLogPath(const std::string& name);

// The checks of a REPLAY_* command's values (the coordinator's CommandProcessor::Check).
bool IsReplayAction(msg::RecorderAction action);
std::string CheckReplayCommand(const msg::RecorderCommand& command);

class Playback {
 public:
  explicit Playback(PlaybackOpener opener, PlaybackResolver resolver = {});

  // REPLAY_START, before the command is accepted: opens the log and checks it against the
  // current map. Empty when it can start; else the reason, and `text` receives CARLA's
  // answer for that case ("Replaying File: ...\nFile ... not found on server\n").
  std::string Prepare(const msg::RecorderCommand& command, const std::string& map_name, uint64_t map_hash,
                      std::string* text);
  // An accepted REPLAY_* command. REPLAY_START (after Prepare) returns CARLA's text
  // ("Replaying File: ...\nTotal time recorded: ...\nReplaying from ..."); the others "".
  std::string Apply(const msg::RecorderCommand& command);

  // True while a replay runs or its end still has to go out: ticks start on the main loop.
  bool Busy() const { return replay_ != nullptr || next_ != nullptr; }

  // The commands of the tick that advances the world by `dt` (s): submitted through
  // `submit` in order. `blueprint_of` gives an actor's blueprint in this run (null: no such actor).
  void Tick(double dt, const PlaybackSubmit& submit, const std::function<const std::string*(uint32_t)>& blueprint_of);

  // A new run (reset, map load): the replay's actors are gone; the replay ends.
  void NewRun();

  // Settings that outlive one replay (CARLA's replayer keeps them).
  double time_factor() const { return time_factor_; }
  bool ignore_hero() const { return ignore_hero_; }
  bool ignore_spectator() const { return ignore_spectator_; }
  // The current replay's time (s from the log's start) of the last tick; nullopt when none runs.
  std::optional<double> time() const;
  // Log id -> id in this run, of the actors the replay put in the world.
  const std::map<uint32_t, uint32_t>& mapped() const { return mapped_; }

 private:
  struct Replay {
    std::unique_ptr<PlaybackLog> log;
    double total = 0;          // s, time of the last frame
    double start = 0;          // s
    double stop = 0;           // s
    double now = 0;            // s, log time of the next tick
    bool first = true;         // the next tick is the first: spawn what is alive at `start`
    size_t applied = 0;        // last frame whose events are applied
    uint32_t follow_id = 0;
    bool replay_sensors = false;
  };

  using BlueprintOf = std::function<const std::string*(uint32_t)>;
  void SpawnActor(const PlaybackActor& actor, const msg::Pose& at, const PlaybackSubmit& submit, const BlueprintOf& blueprint_of);
  void Destroy(uint32_t log_id, const PlaybackSubmit& submit);
  void Finish(bool keep_actors, bool destroy_spawned, const PlaybackSubmit& submit, const BlueprintOf& blueprint_of);
  void Forget();

  PlaybackOpener opener_;
  PlaybackResolver resolver_;
  std::unique_ptr<PlaybackLog> prepared_;
  std::unique_ptr<Replay> replay_;
  std::unique_ptr<Replay> next_;   // a replay_file while another runs: starts once that one ended
  double time_factor_ = 1.0;
  bool ignore_hero_ = false;
  bool ignore_spectator_ = true;  // CARLA's replayer default
  std::map<uint32_t, uint32_t> mapped_;                     // log id -> run id
  std::set<uint32_t> targets_;                              // run ids of the mapped actors
  std::set<uint32_t> spawned_;                              // run ids playback spawned (not reused)
  std::map<uint32_t, msg::ActorKind> kinds_;                // run id -> kind, of the mapped actors
  std::set<uint32_t> heroes_;                               // log ids with role_name = hero
  std::map<uint32_t, msg::TrafficLightColor> lights_set_;   // run id -> state playback froze it in
  std::map<uint32_t, uint32_t> vehicle_lights_set_;         // run id -> light bits playback set
  bool stop_pending_ = false;                               // REPLAY_STOP accepted, not yet applied
  bool stop_keep_actors_ = false;
  bool natural_end_ = false;                                // the stop time was shown: it ends next tick
};

}  // namespace lockstep
