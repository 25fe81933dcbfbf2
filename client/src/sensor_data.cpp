#include "lockstep/client/sensor_data.h"

namespace lockstep::client {

namespace {
bool StartsWith(const std::string& s, const std::string& prefix) { return s.rfind(prefix, 0) == 0; }
}  // namespace

bool SensorTypeOf(const std::string& blueprint, SensorType* type) {
  struct Entry {
    const char* prefix;
    SensorType type;
  };
  static const Entry kTable[] = {
      {"sensor.camera.", SensorType::kImage},
      {"sensor.lidar.", SensorType::kPointCloud},
      {"sensor.other.radar", SensorType::kRadar},
      {"sensor.other.imu", SensorType::kImu},
      {"sensor.other.gnss", SensorType::kGnss},
      {"sensor.other.barometer", SensorType::kBarometer},
      {"sensor.other.magnetometer", SensorType::kMagnetometer},
      {"sensor.other.collision", SensorType::kCollision},
      {"sensor.other.lane_invasion", SensorType::kLaneInvasion},
      {"sensor.other.obstacle", SensorType::kObstacle},
      {"sensor.other.distance", SensorType::kDistance},
      {"sensor.other.v2x", SensorType::kV2X},  // and sensor.other.v2x_custom
  };
  for (const auto& e : kTable) {
    if (StartsWith(blueprint, e.prefix)) {
      *type = e.type;
      return true;
    }
  }
  return false;
}

const char* SensorTypeName(SensorType type) {
  switch (type) {
    case SensorType::kImage: return "image";
    case SensorType::kPointCloud: return "point_cloud";
    case SensorType::kRadar: return "radar";
    case SensorType::kImu: return "imu";
    case SensorType::kGnss: return "gnss";
    case SensorType::kBarometer: return "barometer";
    case SensorType::kMagnetometer: return "magnetometer";
    case SensorType::kCollision: return "collision";
    case SensorType::kLaneInvasion: return "lane_invasion";
    case SensorType::kObstacle: return "obstacle";
    case SensorType::kDistance: return "distance";
    case SensorType::kV2X: return "v2x";
  }
  return "?";
}

bool IsPerFrame(SensorType type) {
  return type != SensorType::kCollision && type != SensorType::kLaneInvasion && type != SensorType::kObstacle &&
         type != SensorType::kV2X;
}

const uint8_t* SensorSample::Bytes() const {
  if (type == SensorType::kImage) return As<msg::Image>().data().data();
  if (type == SensorType::kPointCloud) return As<msg::PointCloud>().data().data();
  return nullptr;
}

size_t SensorSample::ByteCount() const {
  if (type == SensorType::kImage) return As<msg::Image>().data().size();
  if (type == SensorType::kPointCloud) return As<msg::PointCloud>().data().size();
  return 0;
}

}  // namespace lockstep::client
