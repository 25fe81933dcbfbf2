#pragma once
// The recorded sensor outputs of a log as files (`lockstep log export LOG --sensors DIR`,
// docs/recorder.md), the layout of the sensors service's own files (docs/sensors.md):
//   camera_<id>/<frame>.png   cameras with 8-bit pixels: BGRA as RGBA, gray as gray (lossless)
//   camera_<id>/<frame>.npy   cameras with float pixels (depth, optical flow, disparity:
//                             float32 height x width [x 2]) and DVS events (a record array)
//   lidar_<id>/<frame>.ply    point clouds, binary little-endian PLY (x, y, z, intensity, or
//                             x, y, z, cos_inc, object, tag), or <frame>.npy with points "npy"
//   <kind>_<id>.csv           the other sensors, one row per sample (imu, gnss, barometer,
//                             magnetometer, radar, collision, lane_invasion, obstacle,
//                             distance, v2x)
// Frames are the frames the samples show, 6 digits. Plain C++ (no DDS).
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "lockstep/recorder/log_reader.h"

namespace lockstep::recorder {

struct SensorExportOptions {
  std::string points = "ply";      // LiDAR files: "ply" or "npy"
  std::vector<uint32_t> sensors;   // only these sensors (empty: every recorded one)
};

struct SensorExportResult {
  uint64_t samples = 0;
  uint64_t files = 0;                        // images, point clouds and CSV files written
  std::map<std::string, uint64_t> by_type;   // samples per message type
};

// Throws LogError when a folder or file cannot be written or a sample does not decode.
SensorExportResult ExportSensors(LogReader& log, const std::string& dir, const SensorExportOptions& options,
                                 const std::function<void(uint64_t, uint64_t)>& progress = {});

// A PNG (8-bit, no interlace) of rows of `channels` bytes per pixel (1 gray, 4 RGBA).
std::vector<uint8_t> EncodePng(const uint8_t* pixels, uint32_t width, uint32_t height, uint32_t channels, uint32_t step);
// An .npy file (format 1.0) of raw little-endian data: descr such as "<f4", shape as given.
std::vector<uint8_t> EncodeNpy(const std::string& descr, const std::vector<uint64_t>& shape, const uint8_t* data, size_t bytes);

}  // namespace lockstep::recorder
