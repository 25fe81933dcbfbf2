#pragma once
// The ground_sim service core: maps the tick's commands onto ground::World calls, steps it,
// and publishes GroundState and PhysicsEvents (every tick) stamped with the frame.
#include <condition_variable>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "lockstep/ground/run_log.h"
#include "lockstep/ground/world.h"
#include "lockstep/runtime/declarations.h"
#include "lockstep/runtime/frame_buffer.h"
#include "lockstep/runtime/service.h"

namespace lockstep {

class GroundService final : public ServiceCore {
 public:
  // output_dir: the run's files go to <output_dir>/run<N>/ground/ (vehicles.csv,
  // infractions.json); empty = none.
  explicit GroundService(Bus& bus, std::string name = "ground_sim", std::string output_dir = "");
  void BeginRun(const msg::WorldInfo& world) override;
  void Step(const msg::Tick& tick) override;
  std::vector<msg::BlueprintDeclaration> Blueprints() const override;
  std::string CheckSpawn(const msg::SpawnActor& spawn) const override;
  uint64_t StateHash() const override { return world_ ? world_->StateHash() : 0; }
  std::vector<uint8_t> SaveState() const override;
  void RestoreState(const std::vector<uint8_t>& state) override;
  // With a required member that declares drones the step waits for their AirState of
  // frame k-1 (at most the run's service_timeout; then it throws InputError: the run faults).
  bool StepNeverWaits() const override { return !wait_for_air_; }
  // The required members whose AirState the step waits for (this run).
  const std::vector<std::string>& drone_sources() const { return drone_sources_; }

  const ground::World* world() const { return world_.get(); }

 private:
  void Apply(const msg::Command& c);
  void Spawn(const msg::SpawnActor& s);
  // Another service's prop with a declared bounding box becomes a static box here.
  void SpawnProp(const msg::SpawnActor& s, const std::string& bp);
  void Fail(uint32_t actor, const std::string& why);
  void LoadTown(const msg::WorldInfo& world);
  // CARLA's collision check at spawn (docs/architecture.md, "Spawns the owner refuses"): the
  // footprint a vehicle or walker spawn would take, "" when it takes none.
  std::optional<std::pair<ground::Pose, ground::Vec3>> Footprint(const msg::SpawnActor& s) const;
  // The input of the step: the drones of frame k-1 (Jacobi coupling), when a member declares drones.
  std::vector<ground::ExternalBody> Drones(const msg::Tick& tick);
  msg::GroundState PublishState(const msg::FrameStamp& stamp) const;
  msg::PhysicsEvents PublishEvents(const msg::FrameStamp& stamp) const;

  std::string name_;
  std::string output_dir_;
  std::unique_ptr<ground::RunLog> log_;
  Writer<msg::GroundState> state_writer_;
  Writer<msg::PhysicsEvents> events_writer_;
  Writer<msg::SimEvent> event_writer_;
  FrameBuffer<msg::AirState> air_;
  Declarations declarations_;  // every service's blueprints: the props' bounding boxes
  std::mutex map_mu_;
  std::condition_variable map_cv_;
  std::optional<msg::MapData> map_;
  uint64_t town_hash_ = 0;
  std::shared_ptr<const ground::Town> town_;
  std::unique_ptr<ground::World> world_;
  ground::PhysicsSettings physics_;
  uint64_t seed_ = 0;
  bool wait_for_air_ = false;
  std::vector<std::string> drone_sources_;  // required members declaring drones
  double input_timeout_s_ = 10;             // s, the run's service_timeout
  std::vector<msg::SimEvent> pending_events_;
  // Spawns this service accepted in a SpawnCheck that no tick has carried yet: a later check
  // collides with them as with the actors. Each expires after kReservationSteps steps
  // without its spawn (a coordinator that did not send it after all). Checks run between
  // steps (ServiceRunner), never during one.
  struct Reservation {
    std::string blueprint;
    ground::Pose pose;
    ground::Vec3 half_extents;
    int steps_left = 0;
  };
  static constexpr int kReservationSteps = 3;
  mutable std::mutex reservations_mu_;
  mutable std::vector<Reservation> reservations_;
  Reader<msg::MapData> map_reader_;  // last: its callback uses the members above
};

}  // namespace lockstep
