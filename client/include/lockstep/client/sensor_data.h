#pragma once
// One sensor sample of any type as a listen() callback receives it. The sample is
// shared, never copied again after it leaves DDS: the Python layer gives numpy a view
// of `Bytes()` that keeps the sample alive.
#include <cstdint>
#include <memory>
#include <string>

#include "lockstep/runtime/messages.h"

namespace lockstep::client {

enum class SensorType {
  kImage,         // lockstep/sensor/image/<sensor id> (cameras, one topic each)
  kPointCloud,    // lockstep/sensor/point_cloud (LiDAR, semantic LiDAR)
  kRadar,
  kImu,
  kGnss,
  kBarometer,
  kMagnetometer,
  kCollision,     // event sensors: a sample only when something happens
  kLaneInvasion,
  kObstacle,
  kDistance,     // lockstep/sensor/distance (AirSim's distance sensor)
  kV2X,          // lockstep/sensor/v2x (CARLA's sensor.other.v2x, v2x_custom): steps with messages only
};

// Which topic a sensor blueprint publishes on; false if `blueprint` is not a sensor we know.
bool SensorTypeOf(const std::string& blueprint, SensorType* type);
const char* SensorTypeName(SensorType type);
// True for sensors that publish every frame (not event sensors).
bool IsPerFrame(SensorType type);

struct SensorSample {
  SensorType type = SensorType::kImage;
  uint32_t sensor = 0;
  msg::FrameStamp stamp;
  std::shared_ptr<const void> message;  // the msg:: type matching `type`

  template <class T>
  const T& As() const {
    return *static_cast<const T*>(message.get());
  }
  // The raw payload of an image or point cloud (empty for the others).
  const uint8_t* Bytes() const;
  size_t ByteCount() const;
};

}  // namespace lockstep::client
