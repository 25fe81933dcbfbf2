#pragma once
// The recorder service: a perception-phase member of the barrier that writes the world
// state of every frame to files. Because it acks frame k only after writing frame k,
// a finished run has a complete, frame-aligned record (no dropped or shifted frames).
#include <fstream>
#include <memory>
#include <string>

#include "lockstep/runtime/frame_buffer.h"
#include "lockstep/runtime/service.h"

namespace lockstep {

struct RecorderOptions {
  std::string output_dir;        // created if missing
  bool air_state = true;         // wait for and record AirState of each frame
  double input_timeout_s = 10;   // s, how long to wait for a frame's inputs
};

class Recorder final : public ServiceCore {
 public:
  Recorder(Bus& bus, RecorderOptions options);
  void BeginRun(const msg::WorldInfo& world) override;
  void Step(const msg::Tick& tick) override;
  uint64_t StateHash() const override { return hash_; }

 private:
  void Line(std::ofstream& out, const std::string& line);
  void Open(uint64_t first_frame);
  RecorderOptions options_;
  msg::PerceptionMode mode_ = msg::PerceptionMode::PERCEPTION_STRICT;
  FrameBuffer<msg::AirState> air_;
  std::ofstream air_csv_;
  std::ofstream frames_csv_;
  std::string dir_;      // output folder of the current run
  bool opened_ = false;  // files are opened at the first live step of a run
  uint64_t hash_ = 0;
};

}  // namespace lockstep
