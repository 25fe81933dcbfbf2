#pragma once
// The sensors service: a perception-phase member of the barrier. In tick k it reads the
// physics outputs of PerceptionFrame(mode, k) (GroundState, AirState and, for event
// sensors, PhysicsEvents), steps the sensors it owns (sensors::SensorWorld) and
// publishes every sample stamped with that frame. Several sensors services can share a
// world: each simulates the spawns whose SpawnActor.owner names it.
#include <condition_variable>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>

#include "lockstep/runtime/declarations.h"
#include "lockstep/runtime/frame_buffer.h"
#include "lockstep/runtime/service.h"
#include "lockstep/runtime/town_source.h"
#include "frame_actors.h"
#include "lockstep/sensors/sensor_world.h"
#include "sample_writer.h"

namespace lockstep {

struct SensorsOptions {
  std::string output_dir;        // PLY and CSV files under <output_dir>/run<N>/sensors/; empty = none
  double input_timeout_s = 10;   // s, how long to wait for a frame's physics outputs
};

// PhysicsEvents of each frame, one batch per publishing service.
class PhysicsEventsBuffer {
 public:
  PhysicsEventsBuffer(Bus& bus, size_t capacity = 32);
  // The batches of (run, frame) from every service in `from`; nullopt on timeout.
  std::optional<std::vector<msg::PhysicsEvents>> WaitFor(uint32_t run, uint64_t frame, const std::set<std::string>& from,
                                                         std::chrono::milliseconds timeout);

 private:
  using Key = std::pair<uint32_t, uint64_t>;
  size_t capacity_;
  std::mutex mu_;
  std::condition_variable cv_;
  std::map<Key, std::map<std::string, msg::PhysicsEvents>> batches_;
  Reader<msg::PhysicsEvents> reader_;  // last: its callback uses the members above
};

class SensorsService final : public ServiceCore {
 public:
  SensorsService(Bus& bus, std::string name = "sensors", SensorsOptions options = {});
  ~SensorsService() override;
  void BeginRun(const msg::WorldInfo& world) override;
  void Step(const msg::Tick& tick) override;
  std::vector<msg::BlueprintDeclaration> Blueprints() const override;
  std::string CheckSpawn(const msg::SpawnActor& spawn) const override;
  uint64_t StateHash() const override { return world_ ? world_->StateHash() : 0; }
  // The sensors, their noise streams and schedules, custom props and weather: a replacement
  // restores them, then replays the frames after with the kept inputs.
  std::vector<uint8_t> SaveState() const override;
  void RestoreState(const std::vector<uint8_t>& state) override;

  const sensors::SensorWorld* world() const { return world_.get(); }
  // True if this service simulates `spawn` (its owner, or no owner named and ours).
  bool Owns(const msg::SpawnActor& spawn) const;

 private:
  void Apply(const msg::Command& c, const msg::FrameStamp& stamp);
  void LoadTown(const msg::WorldInfo& world);
  sensors::WorldFrame Gather(const msg::Tick& tick, uint64_t frame, sensors::FrameEvents* events);
  void Publish(const sensors::StepOutput& out, const msg::FrameStamp& stamp);
  void Fail(const msg::FrameStamp& stamp, uint32_t actor, const std::string& why);
  // A spawn of a custom.<name> prop another service declared (the render service's
  // imported assets): kept as a box with the declared extents and semantic class.
  void AddCustomProp(const msg::SpawnActor& spawn, const msg::FrameStamp& stamp);
  const std::string& SpecialType(const std::string& vehicle_blueprint);

  std::string name_;
  SensorsOptions options_;
  msg::PerceptionMode mode_ = msg::PerceptionMode::PERCEPTION_STRICT;
  bool ground_in_run_ = false;
  bool air_in_run_ = false;
  std::set<std::string> event_publishers_;   // physics services whose PhysicsEvents we wait for
  uint64_t seed_ = 0;
  uint32_t run_ = 0;
  sensors::Weather weather_;
  std::unique_ptr<sensors::SensorWorld> world_;
  std::unique_ptr<SampleWriter> files_;
  std::map<uint32_t, sensors::CustomProp> props_;  // custom props spawned in this run, by actor id
  std::map<std::string, std::string> special_types_;  // vehicle blueprint -> special_type

  // The town: meshes and geo reference of the current map, kept across runs.
  uint64_t town_hash_ = 0;
  std::shared_ptr<const std::vector<map::Mesh>> town_meshes_;
  sensors::GeoReference geo_;

  Writer<msg::PointCloud> point_cloud_writer_;
  Writer<msg::RadarScan> radar_writer_;
  Writer<msg::Imu> imu_writer_;
  Writer<msg::Gnss> gnss_writer_;
  Writer<msg::Barometer> barometer_writer_;
  Writer<msg::Magnetometer> magnetometer_writer_;
  Writer<msg::DistanceMeasurement> distance_writer_;
  Writer<msg::ObstacleDetection> obstacle_writer_;
  Writer<msg::CollisionEvent> collision_writer_;
  Writer<msg::LaneInvasionEvent> lane_invasion_writer_;
  Writer<msg::V2XData> v2x_writer_;
  Writer<msg::SimEvent> event_writer_;
  Declarations declarations_;  // which required services simulate vehicles, walkers, drones
  FrameBuffer<msg::GroundState> ground_;
  FrameBuffer<msg::AirState> air_;
  PhysicsEventsBuffer events_;
  TownSource town_source_;  // the map the coordinator publishes
};

}  // namespace lockstep
