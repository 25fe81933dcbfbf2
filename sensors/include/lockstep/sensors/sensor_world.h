#pragma once
// The sensors core: the sensors this process owns, stepped once per frame over the
// actors and events of that frame. A plain step (no DDS): the service feeds it.
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <variant>
#include <vector>

#include "lockstep/sensors/blueprints.h"
#include "lockstep/sensors/geo.h"
#include "lockstep/sensors/models.h"
#include "lockstep/sensors/ray_scene.h"
#include "lockstep/sensors/types.h"
#include "lockstep/sensors/v2x.h"

namespace lockstep::sensors {

struct SensorSpawn {
  uint32_t id = 0;                 // the sensor's actor id
  std::string blueprint;           // e.g. "sensor.lidar.ray_cast"
  std::map<std::string, std::string> attributes;
  uint32_t parent = 0;             // actor it is attached to; 0 = stands in the world
  Pose transform;                  // relative to the parent (world if parent == 0)
};

// Every sample of one step, each tagged with its sensor and the sensor's world pose.
template <class T>
struct Tagged {
  uint32_t sensor = 0;
  uint32_t parent = 0;
  Pose pose;   // sensor, world
  T data;
};

struct CollisionSample {
  CollisionEvent event;
};
struct LaneInvasionSample {
  std::vector<LaneMarking> crossed;
};

struct StepOutput {
  std::vector<Tagged<PointCloudSample>> point_clouds;
  std::vector<Tagged<std::vector<RadarDetection>>> radar;
  std::vector<Tagged<ImuSample>> imu;
  std::vector<Tagged<GnssSample>> gnss;
  std::vector<Tagged<BarometerSample>> barometer;
  std::vector<Tagged<Vec3>> magnetometer;  // gauss, sensor frame
  std::vector<Tagged<DistanceSample>> distance;
  std::vector<Tagged<ObstacleSample>> obstacle;
  std::vector<Tagged<CollisionSample>> collision;
  std::vector<Tagged<LaneInvasionSample>> lane_invasion;
  // V2X sensors: what each received this step (only sensors that received something).
  std::vector<Tagged<std::vector<V2XMessage>>> v2x;
  size_t size() const;
};

// Parses and checks a spawn without adding it: empty, or why it cannot be simulated.
std::string CheckSensorSpawn(const SensorSpawn& spawn);

class SensorWorld {
 public:
  explicit SensorWorld(uint64_t run_seed = 0, GeoReference geo = {});
  ~SensorWorld();
  SensorWorld(const SensorWorld&) = delete;
  SensorWorld& operator=(const SensorWorld&) = delete;

  RayScene& scene() { return scene_; }
  const RayScene& scene() const { return scene_; }
  void set_weather(const Weather& w) { weather_ = w; }
  const GeoReference& geo() const { return geo_; }

  // Adds a sensor: empty on success, else the reason (bad blueprint or attribute).
  std::string Add(const SensorSpawn& spawn);
  bool Remove(uint32_t id);
  // The actor `parent` was destroyed: as CARLA's (only the actor goes; Unreal detaches what
  // was attached, keeping its world transform) its sensors stay, unattached, at their world
  // pose of the last step that found the parent.
  void Detach(uint32_t parent);
  bool Has(uint32_t id) const { return sensors_.count(id) > 0; }
  size_t size() const { return sensors_.size(); }
  bool HasEventSensors() const;
  bool HasRaySensors() const;
  // sensor.other.v2x_custom's send(text): the text goes out at the sensor's next step (the
  // last text sent before it, as CARLA's). Empty on success, else why not.
  std::string V2XSend(uint32_t sensor, const std::string& text);

  // Samples every sensor due at `frame` (dt: the step length). Sensors whose parent is
  // not in the frame produce nothing this frame.
  StepOutput Step(const WorldFrame& frame, double dt, const FrameEvents& events = {});

  uint64_t StateHash() const;
  // Everything a later step depends on besides the run seed, the geo reference and the
  // static scene (BeginRun's): weather, the sensors with their spawns and model states.
  // Restore replaces the sensors of this world with the saved ones.
  void Save(StateOut& out) const;
  void Restore(StateIn& in);

 private:
  struct Sensor;
  uint64_t run_seed_;
  GeoReference geo_;
  Weather weather_;
  RayScene scene_;
  std::map<uint32_t, std::unique_ptr<Sensor>> sensors_;
};

}  // namespace lockstep::sensors
