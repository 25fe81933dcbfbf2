#include "sample_writer.h"

#include <cstdio>
#include <filesystem>

#include "lockstep/runtime/error.h"

namespace lockstep {

void WritePly(const std::string& path, const sensors::PointCloudSample& pc) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) throw InputError("sensors: cannot write " + path);
  out << "ply\nformat binary_little_endian 1.0\ncomment lockstep sensors, sensor frame FLU, metres\n";
  out << "element vertex " << pc.point_count << "\n";
  out << "property float x\nproperty float y\nproperty float z\n";
  if (pc.semantic) {
    out << "property float cos_inc\nproperty uint object\nproperty uint tag\n";
  } else {
    out << "property float intensity\n";
  }
  out << "end_header\n";
  out.write(reinterpret_cast<const char*>(pc.data.data()), static_cast<std::streamsize>(pc.data.size()));
}

SampleWriter::SampleWriter(std::string dir, bool fresh) : dir_(std::move(dir)), fresh_(fresh) {
  std::filesystem::create_directories(dir_);
}

std::ofstream& SampleWriter::Csv(const std::string& name, const char* header) {
  auto& f = csv_[name];
  if (!f) {
    const std::string path = dir_ + "/" + name;
    const bool exists = std::filesystem::exists(path);
    f = std::make_unique<std::ofstream>(path, fresh_ ? std::ios::trunc : std::ios::app);
    if (!*f) throw InputError("sensors: cannot write " + path);
    if (fresh_ || !exists) *f << header << '\n';
  }
  return *f;
}

void SampleWriter::Write(const sensors::StepOutput& out, uint64_t frame, double sim_time) {
  char buf[512];
  const auto f = static_cast<unsigned long long>(frame);
  for (const auto& s : out.point_clouds) {
    const std::string folder = dir_ + "/lidar_" + std::to_string(s.sensor);
    std::filesystem::create_directories(folder);
    std::snprintf(buf, sizeof buf, "%s/%06llu.ply", folder.c_str(), f);
    WritePly(buf, s.data);
  }
  for (const auto& s : out.imu) {
    auto& csv = Csv("imu_" + std::to_string(s.sensor) + ".csv", "frame,sim_time,ax,ay,az,gx,gy,gz,compass");
    const auto& d = s.data;
    std::snprintf(buf, sizeof buf, "%llu,%.3f,%.6f,%.6f,%.6f,%.7f,%.7f,%.7f,%.6f", f, sim_time, d.accelerometer.x(), d.accelerometer.y(),
                  d.accelerometer.z(), d.gyroscope.x(), d.gyroscope.y(), d.gyroscope.z(), d.compass);
    csv << buf << '\n';
  }
  for (const auto& s : out.gnss) {
    auto& csv = Csv("gnss_" + std::to_string(s.sensor) + ".csv", "frame,sim_time,latitude,longitude,altitude,eph,epv,fix");
    const auto& d = s.data;
    std::snprintf(buf, sizeof buf, "%llu,%.3f,%.10f,%.10f,%.4f,%.3f,%.3f,%d", f, sim_time, d.latitude, d.longitude, d.altitude, d.eph, d.epv,
                  d.fix ? 1 : 0);
    csv << buf << '\n';
  }
  for (const auto& s : out.barometer) {
    auto& csv = Csv("barometer_" + std::to_string(s.sensor) + ".csv", "frame,sim_time,altitude,pressure,qnh");
    std::snprintf(buf, sizeof buf, "%llu,%.3f,%.4f,%.3f,%.2f", f, sim_time, s.data.altitude, s.data.pressure, s.data.qnh);
    csv << buf << '\n';
  }
  for (const auto& s : out.magnetometer) {
    auto& csv = Csv("magnetometer_" + std::to_string(s.sensor) + ".csv", "frame,sim_time,x,y,z");
    std::snprintf(buf, sizeof buf, "%llu,%.3f,%.6f,%.6f,%.6f", f, sim_time, s.data.x(), s.data.y(), s.data.z());
    csv << buf << '\n';
  }
  for (auto& [name, file] : csv_) file->flush();
}

}  // namespace lockstep
