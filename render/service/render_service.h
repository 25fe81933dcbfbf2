#pragma once
// The render service: owns the cameras spawned for it (SpawnActor.owner = its name),
// renders each of them when due from the world state of the perception frame
// (GroundState, AirState, the map's static town, WorldInfo weather) and publishes every
// image on its camera's topic, stamped with the frame it shows.
#include <condition_variable>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "lockstep/render/asset_import.h"
#include "lockstep/render/camera_config.h"
#include "lockstep/render/renderer.h"
#include "lockstep/runtime/declarations.h"
#include "lockstep/runtime/frame_buffer.h"
#include "lockstep/runtime/service.h"

namespace lockstep {

struct RenderOptions {
  std::string device = "auto";          // auto | gpu | cpu
  bool claim_unowned = false;           // also render cameras spawned with no owner named
  std::string save_dir;                 // write PNGs of every image here (empty: none)
  uint64_t save_every = 1;              // frames between saved images
  std::vector<render::AssetSpec> assets;  // custom.<name> blueprints
  double input_timeout_s = 30;          // s to wait for the physics state of a frame
};

// Parses the render options out of argv (--device, --claim-unowned, --save-dir,
// --save-every, --asset name=path[,class[,scale]]) and removes them; throws
// std::invalid_argument naming the option.
RenderOptions ParseRenderOptions(int* argc, char** argv);

// One DebugDraw command (CARLA's world.debug, AirSim's plotting calls) into `shapes`: its
// world shapes from `first_frame` on, issued at sim time `issued`; flush_persistent first
// erases every shape drawn so far (AirSim's simFlushPersistentMarkers).
void AddDebugDraw(render::DebugShapes& shapes, const msg::DebugDraw& d, uint64_t first_frame, double issued);

class RenderService final : public ServiceCore {
 public:
  RenderService(Bus& bus, std::string name, RenderOptions options);
  ~RenderService() override;
  void BeginRun(const msg::WorldInfo& world) override;
  void Step(const msg::Tick& tick) override;
  std::vector<msg::BlueprintDeclaration> Blueprints() const override;
  std::string CheckSpawn(const msg::SpawnActor& spawn) const override;

  const render::DeviceInfo* device() const { return renderer_ ? &renderer_->device() : nullptr; }
  std::size_t camera_count() const { return cameras_.size(); }

 private:
  struct Spawned {
    std::string blueprint;
    std::map<std::string, std::string> attributes;
    uint32_t parent = 0;
    render::Pose transform;  // relative to the parent (world if none)
  };
  struct CameraRecord;

  void Apply(const msg::Command& c, const msg::FrameStamp& stamp);
  void AddDebugShapes(const msg::DebugDraw& d, uint64_t first_frame, double issued);
  render::DebugDrawList CosmosLines(const msg::GroundState* ground, const render::WorldView& world) const;
  void LoadTown(const msg::WorldInfo& world);
  bool Mine(const msg::SpawnActor& s) const;
  void Fail(const msg::FrameStamp& stamp, uint32_t actor, const std::string& why);
  // poses: each actor's drawn pose (bounding box centre); mounts: the frame a camera's
  // relative transform is given in (as CARLA: vehicles and walkers at the bottom of their
  // box, drones at their centre).
  render::WorldView BuildWorld(const msg::GroundState* ground, const msg::AirState* air, double sim_time,
                               std::map<uint32_t, render::Pose>* poses, std::map<uint32_t, render::Pose>* mounts);
  std::string ModelFor(uint32_t id, const Spawned& s, const render::Vec3& half_extents);
  void Publish(CameraRecord& cam, const render::Camera& view, const render::CameraImages& images, const msg::FrameStamp& stamp);
  void Save(const CameraRecord& cam, const render::CameraImages& images, uint64_t frame);

  Bus& bus_;
  std::string name_;
  RenderOptions options_;
  std::unique_ptr<render::Renderer> renderer_;
  Writer<msg::SimEvent> event_writer_;
  Declarations declarations_;  // which required services simulate vehicles, walkers, drones
  FrameBuffer<msg::GroundState> ground_;
  FrameBuffer<msg::AirState> air_;
  std::mutex map_mu_;
  std::condition_variable map_cv_;
  std::optional<msg::MapData> map_;
  uint64_t town_hash_ = 0;
  std::map<std::string, std::pair<double, double>> light_heads_;  // traffic light opendrive id -> (height, yaw)

  msg::WorldInfo world_;
  render::Weather weather_;
  bool wait_ground_ = false, wait_air_ = false;
  std::map<uint32_t, Spawned> spawned_;                      // every actor spawned in the run
  std::map<uint32_t, std::unique_ptr<CameraRecord>> cameras_;  // the cameras this process owns
  std::map<uint32_t, render::Pose> previous_poses_;         // actor poses of the last rendered frame
  render::DebugShapes debug_;                               // world.debug shapes of the run
  render::DebugDrawList cosmos_map_;                        // the map's lines for cosmos cameras
  Reader<msg::MapData> map_reader_;  // last: its callback uses the members above
};

}  // namespace lockstep
