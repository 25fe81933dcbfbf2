#include "recorder.h"

#include <cstdio>
#include <filesystem>

#include "lockstep/runtime/error.h"
#include "lockstep/runtime/hash.h"
#include "lockstep/runtime/log.h"

namespace lockstep {

Recorder::Recorder(Bus& bus, RecorderOptions options) : options_(std::move(options)), air_(bus, topics::kAirState, 64) {
  if (options_.output_dir.empty()) throw InputError("recorder: no output_dir in the launch config");
  std::filesystem::create_directories(options_.output_dir);
}

void Recorder::BeginRun(const msg::WorldInfo& world) {
  mode_ = world.settings().perception_mode();
  dir_ = options_.output_dir + "/run" + std::to_string(world.run());
  std::filesystem::create_directories(dir_);
  hash_ = Fnv1a64().Add(world.run()).Add(world.seed()).value();
  opened_ = false;
}

// A run recorded from its first frame starts fresh files; a replacement recorder that
// takes over mid-run appends to what the one before it wrote.
void Recorder::Open(uint64_t first_frame) {
  const bool fresh = first_frame <= 1;
  const auto mode = fresh ? std::ios::trunc : std::ios::app;
  air_csv_ = std::ofstream(dir_ + "/air_state.csv", std::ios::out | mode);
  frames_csv_ = std::ofstream(dir_ + "/frames.csv", std::ios::out | mode);
  if (!air_csv_ || !frames_csv_) throw InputError("recorder: cannot write into " + dir_);
  if (fresh) {
    Line(air_csv_, "frame,sim_time,actor,x,y,z,qw,qx,qy,qz,vx,vy,vz,landed,armed,command_id,command_status");
    Line(frames_csv_, "tick,sim_time,commands,shown_frame,air_state_hash");
  }
  opened_ = true;
  spdlog::info("recording run into {} ({})", dir_, fresh ? "new files" : "appending from frame " + std::to_string(first_frame));
}

void Recorder::Line(std::ofstream& out, const std::string& line) {
  out << line << '\n';
  hash_ = Fnv1a64().Add(hash_).Add(std::string_view(line)).value();
}

void Recorder::Step(const msg::Tick& tick) {
  // A replacement recorder cannot rebuild past rows (their inputs are gone): it appends
  // from the frame it takes over, and its state hash starts over from there.
  if (replaying()) return;
  if (!opened_) Open(tick.frame());
  const uint64_t frame = PerceptionFrame(mode_, tick.frame());
  uint64_t air_hash = 0;
  if (options_.air_state && frame >= 1) {
    auto air = air_.WaitFor(tick.run(), frame, std::chrono::milliseconds(static_cast<int>(options_.input_timeout_s * 1000)));
    if (!air) throw InputError("recorder: no AirState of frame " + std::to_string(frame) + " within the timeout");
    air_hash = air->state_hash();
    char buf[512];
    for (const auto& d : air->drones()) {
      const auto& p = d.transform().position();
      const auto& q = d.transform().orientation();
      const auto& v = d.linear_velocity();
      std::snprintf(buf, sizeof buf, "%llu,%.3f,%u,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,%.4f,%.4f,%.4f,%d,%d,%llu,%d",
                    static_cast<unsigned long long>(frame), air->stamp().sim_time(), d.actor(), p.x(), p.y(), p.z(), q.w(), q.x(),
                    q.y(), q.z(), v.x(), v.y(), v.z(), d.landed() == msg::LandedState::LANDED_LANDED ? 1 : 0, d.armed() ? 1 : 0,
                    static_cast<unsigned long long>(d.command_id()), static_cast<int>(d.command_status()));
      Line(air_csv_, buf);
    }
  }
  char buf[128];
  std::snprintf(buf, sizeof buf, "%llu,%.3f,%zu,%llu,%016llx", static_cast<unsigned long long>(tick.frame()), tick.sim_time(),
                tick.commands().size(), static_cast<unsigned long long>(frame), static_cast<unsigned long long>(air_hash));
  Line(frames_csv_, buf);
  air_csv_.flush();
  frames_csv_.flush();
}

}  // namespace lockstep
