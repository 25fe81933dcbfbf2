#pragma once
// Which sensors' outputs a log holds (docs/recorder.md, "Sensor outputs"). A selection is a
// comma-separated list of terms; a sensor is chosen when any term matches it:
//   all                  every sensor
//   42                   the sensor actor with that id
//   role_name=front      the sensors spawned with that role_name
//   sensor.camera.*      a blueprint id, with the wildcards * and ? (fnmatch)
// Plain C++ (no DDS).
#include <cstdint>
#include <string>
#include <vector>

namespace lockstep::recorder {

class SensorSelection {
 public:
  SensorSelection() = default;  // chooses none
  // Throws std::invalid_argument naming the term that is none of the above.
  static SensorSelection Parse(const std::string& spec);
  static SensorSelection All() { return Parse("all"); }

  bool empty() const { return !all_ && ids_.empty() && roles_.empty() && patterns_.empty(); }
  const std::string& spec() const { return spec_; }
  // Chooses a sensor actor with this id, blueprint and role_name attribute.
  bool Chooses(uint32_t id, const std::string& blueprint, const std::string& role_name) const;
  // True when a sensor of this blueprint may be chosen (whatever its id or role): the
  // recorder subscribes to the topics such sensors publish on.
  bool MayChoose(const std::string& blueprint) const;

 private:
  std::string spec_;
  bool all_ = false;
  std::vector<uint32_t> ids_;
  std::vector<std::string> roles_;
  std::vector<std::string> patterns_;
};

// The message type a sensor blueprint publishes ("Image" for cameras, which also publish
// "LargeImage" over Image's bound; "PointCloud" for LiDARs, "Imu", ...), "" when unknown.
std::string SensorMessageType(const std::string& blueprint);

}  // namespace lockstep::recorder
