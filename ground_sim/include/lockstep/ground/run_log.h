#pragma once
// The run's ground output files: a per-tick vehicle log (vehicles.csv, one row per
// vehicle and tick) and an infraction summary (infractions.json, per vehicle and in
// total, rewritten every second of simulated time and when the log closes).
#include <cstdint>
#include <fstream>
#include <map>
#include <set>
#include <string>
#include <utility>

#include "lockstep/ground/world.h"

namespace lockstep::ground {

class RunLog {
 public:
  // dir: created if missing. fresh: start new files; false appends (a replacement
  // ground_sim taking over the run). Throws std::runtime_error if it cannot write there.
  RunLog(std::string dir, bool fresh);
  ~RunLog();
  RunLog(const RunLog&) = delete;
  RunLog& operator=(const RunLog&) = delete;

  // After World::Step: the vehicles of this frame and the step's collisions.
  void Write(const World& world, uint64_t frame, double sim_time);
  void WriteSummary() const;

  const std::string& dir() const { return dir_; }

 private:
  struct PerVehicle {
    std::string blueprint, role_name;
    Infractions infractions;
    double distance = 0;          // m driven
    double time = 0;              // s in the log
    bool autopilot = false;
    Vec3 last = Vec3::Zero();
    bool has_last = false;
  };
  std::string dir_;
  std::ofstream csv_;
  std::map<uint32_t, PerVehicle> vehicles_;
  std::set<std::pair<uint32_t, uint32_t>> vehicle_pairs_;  // vehicles that touched each other
  uint64_t frames_ = 0;
  double last_time_ = 0;
  double summary_due_ = 0;
};

}  // namespace lockstep::ground
