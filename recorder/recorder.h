#pragma once
// The recorder service: a perception-phase member of the barrier that writes Lockstep logs
// (docs/recorder.md). It records when a tick carries CMD_RECORDER RECORDER_START (CARLA's
// start_recorder) until RECORDER_STOP or the end of the run, and, with `record_run`, every
// run from its first frame. Frame k of a log holds tick k (bit for bit), the states of
// PerceptionFrame(mode, k), the frame's events and the hashes of the frame before; it acks
// k once the frame is queued for its writer thread (at most 8 frames behind; a stop, the
// run's end and the service's end write what is queued), so a log has every frame while
// the serialisation stays off the barrier. While not recording it reads no state
// topic and its step does nearly nothing. Its state hash is 0: a log is not world state,
// so recording or not never changes a run's world hash.
#include <atomic>
#include <condition_variable>
#include <deque>
#include <exception>
#include <thread>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include "lockstep/recorder/log_writer.h"
#include "lockstep/recorder/sensor_selection.h"
#include "lockstep/runtime/declarations.h"
#include "lockstep/runtime/service.h"

namespace lockstep {

struct RecorderOptions {
  std::string output_dir;        // record_run: the logs go to <output_dir>/run<N>/<run_log_name>
  bool record_run = false;       // record every run from its first frame (the main job)
  std::string run_log_name = "recording.lslog";
  bool read_only = false;        // never write (re-simulation: the recorder of the log's config)
  double input_timeout_s = 10;   // s, how long to wait for a frame's inputs while recording
  std::string config_text;       // the launch config, for the log header
  std::string config_source;
  std::map<std::string, std::pair<std::string, bool>> service_kinds;  // name -> (kind, perception), from the config
  uint32_t keyframe_period = 200;
  size_t prelude_limit_bytes = 64u << 20;  // earlier ticks kept for a mid-run start (CDR bytes)
  // Sensors whose outputs every log of this recorder holds (recorder/sensor_selection.h:
  // "all", ids, role_name=NAME, blueprint patterns); "" = none, unless a start_recorder
  // asks for additional_data, which records every sensor.
  std::string record_sensors;
};

class Recorder final : public ServiceCore {
 public:
  Recorder(Bus& bus, RecorderOptions options);
  ~Recorder() override;
  void BeginRun(const msg::WorldInfo& world) override;
  void Step(const msg::Tick& tick) override;
  uint64_t StateHash() const override { return 0; }

  // The log being written ("" when not recording), for tests and status.
  std::string recording() const;
  // Frames written and the wall time spent writing them (after their inputs arrived), us.
  uint64_t frames_written() const { return frames_written_; }
  double write_us() const { return write_us_; }

 private:
  struct Inputs;
  struct Hashes;
  struct SensorTaps;
  // One frame for the writer thread.
  struct Job {
    msg::Tick tick;
    uint64_t state_frame = 0;
    std::vector<msg::GroundState> ground;
    std::vector<msg::AirState> air;
    std::vector<msg::PhysicsEvents> events;
    std::vector<std::pair<uint64_t, recorder::FrameHashes>> hashes;
    std::vector<uint32_t> stateless;
    std::map<uint32_t, recorder::ActorInfo> described;  // first seen in this frame
    std::shared_ptr<SensorTaps> sensors;  // the chosen sensors' outputs (null: none recorded)
  };
  static constexpr size_t kQueue = 8;  // frames the writer may lag behind
  void Enqueue(Job job);
  void Drain();
  void WriterLoop();
  void Start(const msg::Tick& tick, const std::string& path, bool additional_data);
  void Stop(const std::string& reason);
  void Track(const msg::Tick& tick);
  void WriteFrame(const msg::Tick& tick);
  // Sorts the sensors of the run into chosen and not (cameras chosen get their readers).
  void ChooseSensors(SensorTaps& taps, uint64_t state_frame);

  Bus& bus_;
  RecorderOptions options_;
  Declarations declarations_;
  msg::WorldInfo world_;
  msg::PerceptionMode mode_ = msg::PerceptionMode::PERCEPTION_STRICT;
  std::unique_ptr<recorder::LogWriter> writer_;
  std::unique_ptr<Inputs> inputs_;  // the state readers, only while recording
  std::unique_ptr<Hashes> hashes_;  // FrameDone and acks (kept only while recording)
  recorder::SensorSelection sensor_selection_;  // options_.record_sensors
  std::shared_ptr<SensorTaps> taps_;  // the chosen sensors' readers, while a log records any
  // What every tick of the run said, kept while not recording (cheap: spawns and commands).
  std::map<uint32_t, msg::SpawnActor> alive_;     // live spawned actors by id
  std::vector<msg::Tick> prelude_;                // ticks with commands or a new dt
  size_t prelude_bytes_ = 0;
  bool prelude_complete_ = true;                  // false once the limit dropped ticks
  uint64_t prelude_frames_ = 0;
  double last_dt_ = -1;
  uint64_t last_frame_ = 0;
  std::set<uint32_t> described_;                  // actors described in the current log
  uint64_t queued_ = 0;                           // frames of the current log handed to the writer
  std::mutex queue_mu_;
  std::condition_variable queue_cv_;
  std::deque<Job> queue_;
  bool writing_ = false;
  bool quit_ = false;
  std::exception_ptr writer_error_;
  std::thread writer_thread_;
  std::atomic<uint64_t> frames_written_{0};
  std::atomic<double> write_us_{0};
  std::atomic<bool> closing_{false};  // the service ends: no more waiting for FrameDone
  mutable std::mutex announce_mu_;
  std::map<std::string, std::pair<std::string, bool>> announced_;  // name -> (kind, perception)
  Reader<msg::ServiceAnnounce> announce_reader_;
};

}  // namespace lockstep
