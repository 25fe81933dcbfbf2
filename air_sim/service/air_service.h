#pragma once
// The air_sim service core: turns the tick's commands into air::Commands, steps the
// multirotor world (air::Step) and publishes AirState and events stamped with the frame.
#include <atomic>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>

#include "lockstep/air/air.h"
#include "lockstep/runtime/declarations.h"
#include "lockstep/runtime/frame_buffer.h"
#include "lockstep/runtime/service.h"
#include "lockstep/runtime/town_source.h"
#include "air_blueprints.h"

namespace lockstep {

class AirService final : public ServiceCore {
 public:
  explicit AirService(Bus& bus, std::string name = "air_sim");
  void BeginRun(const msg::WorldInfo& world) override;
  void Step(const msg::Tick& tick) override;
  uint64_t StateHash() const override;
  std::vector<uint8_t> SaveState() const override;
  void RestoreState(const std::vector<uint8_t>& state) override;
  std::vector<msg::BlueprintDeclaration> Blueprints() const override { return AirBlueprints(); }
  std::string CheckSpawn(const msg::SpawnActor& spawn) const override { return CheckAirSpawn(spawn); }
  // Without a vehicle/walker simulator in the run the step reads only the tick: it may run on the
  // receive thread. With one, it waits for the vehicles of frame k-1.
  bool StepNeverWaits() const override { return !wait_for_ground_; }

  const air::World& model() const { return model_; }
  const air::WorldState& state() const { return state_; }

 private:
  void Apply(const msg::Command& c, uint64_t frame, air::Commands* out);
  void Fail(const msg::FrameStamp& stamp, uint32_t actor, const std::string& why);
  // The vehicles of frame k-1 (Jacobi coupling); throws InputError when they do not come.
  std::vector<air::VehicleBox> Vehicles(const msg::Tick& tick);
  air::Environment Environment(std::vector<air::VehicleBox> vehicles) const;
  void PublishPhysicsEvents(const msg::FrameStamp& stamp);
  msg::AirState Publish(const msg::FrameStamp& stamp) const;
  void LoadTown(const msg::WorldInfo& world);

  std::string name_;
  Writer<msg::AirState> state_writer_;
  Writer<msg::SimEvent> event_writer_;
  FrameBuffer<msg::GroundState> ground_;
  uint64_t town_hash_ = 0;                                // map whose mesh is in model_.statics
  std::shared_ptr<const air::StaticMesh> town_mesh_;
  // A required member declares vehicle or walker blueprints (lockstep/blueprints): use its
  // GroundState of frame k-1 (Jacobi). Decided at BeginRun from the declarations, never by name.
  std::atomic<bool> wait_for_ground_{false};
  Declarations declarations_;
  air::World model_;
  air::WorldState state_;
  std::map<uint32_t, std::string> blueprints_;
  std::map<uint32_t, std::map<std::string, std::string>> spawn_attributes_;  // per drone: rebuilds its model on restore
  std::map<uint32_t, std::pair<uint64_t, msg::DroneCommandStatus>> last_command_;  // per drone
  std::vector<msg::SimEvent> pending_events_;
  Writer<msg::PhysicsEvents> physics_writer_;
  map::GeoReference geo_;                 // the map's geo-reference (GPS, moveToGPS)
  air::Vec3 api_wind_ = air::Vec3::Zero();  // m/s ENU, simSetWind (all drones)
  float wind_intensity_ = 0;              // weather's wind_intensity (0..100)
  double input_timeout_s_ = 10;           // s, world settings' service_timeout: no inputs -> fault
  TownSource town_source_;  // the map the coordinator publishes
};

// DroneCommand (wire) -> air command body; empty optional with `why` set if it cannot map.
std::optional<air::CommandBody> ToAirCommand(const msg::DroneCommand& d, std::string* why);

}  // namespace lockstep
