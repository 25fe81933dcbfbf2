#pragma once
// Files of the sensor streams: each point cloud as a binary PLY, the inertial and
// navigation streams as one CSV per sensor, under <output_dir>/run<N>/sensors/.
#include <cstdint>
#include <fstream>
#include <map>
#include <memory>
#include <string>

#include "lockstep/sensors/sensor_world.h"

namespace lockstep {

class SampleWriter {
 public:
  // dir: the run's folder (created); fresh: start new files (false: append, a takeover).
  SampleWriter(std::string dir, bool fresh);
  void Write(const sensors::StepOutput& out, uint64_t frame, double sim_time);

 private:
  std::ofstream& Csv(const std::string& name, const char* header);
  std::string dir_;
  bool fresh_;
  std::map<std::string, std::unique_ptr<std::ofstream>> csv_;
};

// A point cloud as binary little-endian PLY: x, y, z (m, sensor frame) and intensity, or
// for semantic clouds cos_inc, object and tag.
void WritePly(const std::string& path, const sensors::PointCloudSample& pc);

}  // namespace lockstep
