#include "lockstep/recorder/sensor_export.h"

#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <set>

#include "lockstep/msg/sensor.h"
#include "lockstep/recorder/log_writer.h"

namespace lockstep::recorder {
namespace {

void Put32(std::vector<uint8_t>* out, uint32_t v) {
  for (int i = 3; i >= 0; --i) out->push_back(static_cast<uint8_t>(v >> (8 * i)));
}

void Chunk(std::vector<uint8_t>* out, const char* type, const uint8_t* data, size_t size) {
  Put32(out, static_cast<uint32_t>(size));
  const size_t at = out->size();
  out->insert(out->end(), type, type + 4);
  if (size > 0) out->insert(out->end(), data, data + size);
  Put32(out, static_cast<uint32_t>(crc32(0, out->data() + at, static_cast<uInt>(size + 4))));
}

void WriteFile(const std::string& path, const void* data, size_t size) {
  FILE* f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) throw LogError("cannot write " + path + ": " + std::strerror(errno));
  const bool ok = std::fwrite(data, 1, size, f) == size;
  if (std::fclose(f) != 0 || !ok) throw LogError("cannot write " + path + ": " + std::strerror(errno));
}

std::string Frame6(uint64_t frame) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%06llu", static_cast<unsigned long long>(frame));
  return buf;
}

// Pixel rows of `row_bytes` each out of rows `step` apart, checked against the data's size.
std::vector<uint8_t> Rows(const std::vector<uint8_t>& data, uint32_t height, size_t row_bytes, uint32_t step, const std::string& what) {
  if (step < row_bytes || (height > 0 && static_cast<size_t>(step) * (height - 1) + row_bytes > data.size())) {
    throw LogError(what + ": " + std::to_string(data.size()) + " bytes do not hold " + std::to_string(height) + " rows of " +
                   std::to_string(row_bytes) + " bytes (step " + std::to_string(step) + ")");
  }
  std::vector<uint8_t> out(row_bytes * height);
  for (uint32_t y = 0; y < height; ++y) std::memcpy(out.data() + y * row_bytes, data.data() + static_cast<size_t>(y) * step, row_bytes);
  return out;
}

class CsvFiles {
 public:
  explicit CsvFiles(std::string dir) : dir_(std::move(dir)) {}
  ~CsvFiles() {
    for (auto& [name, f] : files_) std::fclose(f);
  }
  FILE* Get(const std::string& name, const char* header) {
    auto it = files_.find(name);
    if (it != files_.end()) return it->second;
    const std::string path = dir_ + "/" + name;
    FILE* f = std::fopen(path.c_str(), "w");
    if (f == nullptr) throw LogError("cannot write " + path + ": " + std::strerror(errno));
    std::fprintf(f, "%s\n", header);
    files_[name] = f;
    return f;
  }
  size_t count() const { return files_.size(); }

 private:
  std::string dir_;
  std::map<std::string, FILE*> files_;
};

}  // namespace

std::vector<uint8_t> EncodePng(const uint8_t* pixels, uint32_t width, uint32_t height, uint32_t channels, uint32_t step) {
  std::vector<uint8_t> raw;  // each row: filter 0, then the row
  const size_t row = static_cast<size_t>(width) * channels;
  raw.reserve((row + 1) * height);
  for (uint32_t y = 0; y < height; ++y) {
    raw.push_back(0);
    raw.insert(raw.end(), pixels + static_cast<size_t>(y) * step, pixels + static_cast<size_t>(y) * step + row);
  }
  uLongf packed_size = compressBound(static_cast<uLong>(raw.size()));
  std::vector<uint8_t> packed(packed_size);
  if (compress2(packed.data(), &packed_size, raw.data(), static_cast<uLong>(raw.size()), 6) != Z_OK) throw LogError("PNG: zlib failed");
  packed.resize(packed_size);
  std::vector<uint8_t> png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  std::vector<uint8_t> ihdr;
  Put32(&ihdr, width);
  Put32(&ihdr, height);
  ihdr.push_back(8);                         // bit depth
  ihdr.push_back(channels == 4 ? 6 : 0);     // colour type: RGBA or gray
  ihdr.push_back(0);                         // deflate
  ihdr.push_back(0);                         // filters per row
  ihdr.push_back(0);                         // no interlace
  Chunk(&png, "IHDR", ihdr.data(), ihdr.size());
  Chunk(&png, "IDAT", packed.data(), packed.size());
  Chunk(&png, "IEND", nullptr, 0);
  return png;
}

std::vector<uint8_t> EncodeNpy(const std::string& descr, const std::vector<uint64_t>& shape, const uint8_t* data, size_t bytes) {
  std::string dims;  // "n," for one dimension, "h, w" for more (Python's tuples)
  for (size_t i = 0; i < shape.size(); ++i) {
    if (i > 0) dims += ", ";
    dims += std::to_string(shape[i]);
  }
  if (shape.size() == 1) dims += ",";
  std::string header = "{'descr': " + descr + ", 'fortran_order': False, 'shape': (" + dims + "), }";
  // magic (6) + version (2) + length (2) + header + '\n', a multiple of 64.
  const size_t total = 10 + header.size() + 1;
  header.append((64 - total % 64) % 64, ' ');
  header += '\n';
  std::vector<uint8_t> out = {0x93, 'N', 'U', 'M', 'P', 'Y', 1, 0};
  out.push_back(static_cast<uint8_t>(header.size() & 0xff));
  out.push_back(static_cast<uint8_t>(header.size() >> 8));
  out.insert(out.end(), header.begin(), header.end());
  out.insert(out.end(), data, data + bytes);
  return out;
}

SensorExportResult ExportSensors(LogReader& log, const std::string& dir, const SensorExportOptions& options,
                                 const std::function<void(uint64_t, uint64_t)>& progress) {
  if (options.points != "ply" && options.points != "npy") throw LogError("point cloud format '" + options.points + "': ply or npy");
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw LogError("cannot create " + dir + ": " + ec.message());
  const std::set<uint32_t> only(options.sensors.begin(), options.sensors.end());
  SensorExportResult result;
  CsvFiles csv(dir);
  std::set<std::string> folders;
  auto folder = [&](const std::string& name) {
    const std::string path = dir + "/" + name;
    if (folders.insert(name).second) {
      std::filesystem::create_directories(path, ec);
      if (ec) throw LogError("cannot create " + path + ": " + ec.message());
    }
    return path;
  };
  if (log.sensor_stats().empty()) return result;
  auto image = [&](uint32_t sensor, uint64_t frame, uint32_t width, uint32_t height, uint32_t step, uint32_t encoding,
                   const std::vector<uint8_t>& data) {
    const std::string base = folder("camera_" + std::to_string(sensor)) + "/" + Frame6(frame);
    const std::string what = "camera " + std::to_string(sensor) + " frame " + std::to_string(frame);
    using E = msg::ImageEncoding;
    switch (static_cast<E>(encoding)) {
      case E::IMAGE_BGRA8:
      case E::IMAGE_DEPTH_CARLA_BGRA8:
      case E::IMAGE_SEMANTIC_BGRA8:
      case E::IMAGE_INSTANCE_BGRA8:
      case E::IMAGE_NORMALS_BGRA8:
      case E::IMAGE_SEGMENTATION_BGRA8: {
        std::vector<uint8_t> rgba = Rows(data, height, static_cast<size_t>(width) * 4, step, what);
        for (size_t i = 0; i + 3 < rgba.size(); i += 4) std::swap(rgba[i], rgba[i + 2]);
        const auto png = EncodePng(rgba.data(), width, height, 4, width * 4);
        WriteFile(base + ".png", png.data(), png.size());
        return;
      }
      case E::IMAGE_GRAY8: {
        const std::vector<uint8_t> gray = Rows(data, height, width, step, what);
        const auto png = EncodePng(gray.data(), width, height, 1, width);
        WriteFile(base + ".png", png.data(), png.size());
        return;
      }
      case E::IMAGE_DEPTH_F32:
      case E::IMAGE_DEPTH_PERSPECTIVE_F32:
      case E::IMAGE_DISPARITY_F32: {
        const std::vector<uint8_t> f = Rows(data, height, static_cast<size_t>(width) * 4, step, what);
        const auto npy = EncodeNpy("'<f4'", {height, width}, f.data(), f.size());
        WriteFile(base + ".npy", npy.data(), npy.size());
        return;
      }
      case E::IMAGE_FLOW_F32X2: {
        const std::vector<uint8_t> f = Rows(data, height, static_cast<size_t>(width) * 8, step, what);
        const auto npy = EncodeNpy("'<f4'", {height, width, 2}, f.data(), f.size());
        WriteFile(base + ".npy", npy.data(), npy.size());
        return;
      }
      case E::IMAGE_DVS_EVENTS: {
        const size_t bytes = std::min(data.size(), static_cast<size_t>(width) * 16);
        const auto npy = EncodeNpy("[('x', '<u2'), ('y', '<u2'), ('pol', 'u1'), ('pad', 'V3'), ('t', '<i8')]", {bytes / 16}, data.data(),
                                   bytes / 16 * 16);
        WriteFile(base + ".npy", npy.data(), npy.size());
        return;
      }
    }
    throw LogError(what + ": unknown image encoding " + std::to_string(encoding));
  };
  log.ForEach(
      0, UINT64_MAX,
      [&](const LogFrame& f) {
        for (const auto& s : f.sensors) {
          if (!only.empty() && !only.count(s.sensor)) continue;
          const auto id = std::to_string(s.sensor);
          const auto frame = static_cast<unsigned long long>(s.frame);
          try {
            if (s.type == "Image") {
              const auto m = FromCdr<msg::Image>(s.cdr);
              image(s.sensor, s.frame, m.width(), m.height(), m.step(), m.encoding(), m.data());
            } else if (s.type == "LargeImage") {
              const auto m = FromCdr<msg::LargeImage>(s.cdr);
              image(s.sensor, s.frame, m.width(), m.height(), m.step(), m.encoding(), m.data());
            } else if (s.type == "PointCloud") {
              const auto m = FromCdr<msg::PointCloud>(s.cdr);
              const bool semantic = m.format() == msg::PointFormat::POINTS_SEMANTIC;
              const size_t bytes = std::min(m.data().size(), static_cast<size_t>(m.point_count()) * m.point_step());
              const std::string base = folder("lidar_" + id) + "/" + Frame6(s.frame);
              if (options.points == "npy") {
                const auto npy = semantic ? EncodeNpy("[('x', '<f4'), ('y', '<f4'), ('z', '<f4'), ('cos_inc', '<f4'), ('object', '<u4'), "
                                                      "('tag', '<u4')]",
                                                      {m.point_count()}, m.data().data(), bytes)
                                          : EncodeNpy("'<f4'", {m.point_count(), 4}, m.data().data(), bytes);
                WriteFile(base + ".npy", npy.data(), npy.size());
              } else {
                std::string h = "ply\nformat binary_little_endian 1.0\ncomment lockstep log export, sensor frame FLU, metres\n";
                h += "element vertex " + std::to_string(m.point_count()) + "\n";
                h += "property float x\nproperty float y\nproperty float z\n";
                h += semantic ? "property float cos_inc\nproperty uint object\nproperty uint tag\n" : "property float intensity\n";
                h += "end_header\n";
                std::vector<uint8_t> ply(h.begin(), h.end());
                ply.insert(ply.end(), m.data().begin(), m.data().begin() + static_cast<std::ptrdiff_t>(bytes));
                WriteFile(base + ".ply", ply.data(), ply.size());
              }
            } else if (s.type == "Imu") {
              const auto d = FromCdr<msg::Imu>(s.cdr);
              std::fprintf(csv.Get("imu_" + id + ".csv", "frame,sim_time,ax,ay,az,gx,gy,gz,compass"), "%llu,%.3f,%.6f,%.6f,%.6f,%.7f,%.7f,%.7f,%.6f\n",
                           frame, d.stamp().sim_time(), d.accelerometer().x(), d.accelerometer().y(), d.accelerometer().z(),
                           d.gyroscope().x(), d.gyroscope().y(), d.gyroscope().z(), d.compass());
            } else if (s.type == "Gnss") {
              const auto d = FromCdr<msg::Gnss>(s.cdr);
              std::fprintf(csv.Get("gnss_" + id + ".csv", "frame,sim_time,latitude,longitude,altitude,eph,epv,fix"),
                           "%llu,%.3f,%.10f,%.10f,%.4f,%.3f,%.3f,%d\n", frame, d.stamp().sim_time(), d.latitude(), d.longitude(), d.altitude(),
                           d.eph(), d.epv(), d.fix() ? 1 : 0);
            } else if (s.type == "Barometer") {
              const auto d = FromCdr<msg::Barometer>(s.cdr);
              std::fprintf(csv.Get("barometer_" + id + ".csv", "frame,sim_time,altitude,pressure,qnh"), "%llu,%.3f,%.4f,%.3f,%.2f\n", frame,
                           d.stamp().sim_time(), d.altitude(), d.pressure(), d.qnh());
            } else if (s.type == "Magnetometer") {
              const auto d = FromCdr<msg::Magnetometer>(s.cdr);
              std::fprintf(csv.Get("magnetometer_" + id + ".csv", "frame,sim_time,bx,by,bz"), "%llu,%.3f,%.6f,%.6f,%.6f\n", frame,
                           d.stamp().sim_time(), d.magnetic_field().x(), d.magnetic_field().y(), d.magnetic_field().z());
            } else if (s.type == "RadarScan") {
              const auto d = FromCdr<msg::RadarScan>(s.cdr);
              FILE* out = csv.Get("radar_" + id + ".csv", "frame,sim_time,velocity,azimuth,altitude,depth");
              for (const auto& r : d.detections()) {
                std::fprintf(out, "%llu,%.3f,%.4f,%.6f,%.6f,%.4f\n", frame, d.stamp().sim_time(), r.velocity(), r.azimuth(), r.altitude(), r.depth());
              }
            } else if (s.type == "CollisionEvent") {
              const auto d = FromCdr<msg::CollisionEvent>(s.cdr);
              std::fprintf(csv.Get("collision_" + id + ".csv", "frame,sim_time,actor,other_actor,impulse_x,impulse_y,impulse_z"),
                           "%llu,%.3f,%u,%u,%.4f,%.4f,%.4f\n", frame, d.stamp().sim_time(), d.actor(), d.other_actor(), d.normal_impulse().x(),
                           d.normal_impulse().y(), d.normal_impulse().z());
            } else if (s.type == "LaneInvasionEvent") {
              const auto d = FromCdr<msg::LaneInvasionEvent>(s.cdr);
              std::string types;
              for (const auto& c : d.crossed()) {
                if (!types.empty()) types += ' ';
                types += std::to_string(static_cast<int>(c.type()));
              }
              std::fprintf(csv.Get("lane_invasion_" + id + ".csv", "frame,sim_time,actor,crossed"), "%llu,%.3f,%u,%s\n", frame,
                           d.stamp().sim_time(), d.actor(), types.c_str());
            } else if (s.type == "ObstacleDetection") {
              const auto d = FromCdr<msg::ObstacleDetection>(s.cdr);
              std::fprintf(csv.Get("obstacle_" + id + ".csv", "frame,sim_time,actor,other_actor,distance"), "%llu,%.3f,%u,%u,%.4f\n", frame,
                           d.stamp().sim_time(), d.actor(), d.other_actor(), d.distance());
            } else if (s.type == "DistanceMeasurement") {
              const auto d = FromCdr<msg::DistanceMeasurement>(s.cdr);
              std::fprintf(csv.Get("distance_" + id + ".csv", "frame,sim_time,distance,min_distance,max_distance"), "%llu,%.3f,%.4f,%.4f,%.4f\n",
                           frame, d.stamp().sim_time(), d.distance(), d.min_distance(), d.max_distance());
            } else if (s.type == "V2XData") {
              const auto d = FromCdr<msg::V2XData>(s.cdr);
              FILE* out = csv.Get("v2x_" + id + ".csv", "frame,sim_time,sender,power_dbm,payload_bytes");
              for (const auto& m : d.messages()) {
                std::fprintf(out, "%llu,%.3f,%u,%.3f,%zu\n", frame, d.stamp().sim_time(), m.sender(), m.power_dbm(), m.payload().size());
              }
            } else {
              continue;  // a type this build does not know: left out
            }
          } catch (const LogError&) {
            throw;
          } catch (const std::exception& e) {
            throw LogError("sensor " + id + " frame " + std::to_string(s.frame) + " (" + s.type + "): " + e.what());
          }
          if (s.type == "Image" || s.type == "LargeImage" || s.type == "PointCloud") ++result.files;
          ++result.samples;
          ++result.by_type[s.type];
        }
        return true;
      },
      progress);
  result.files += csv.count();
  return result;
}

}  // namespace lockstep::recorder
