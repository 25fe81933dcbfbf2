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
#include "lockstep/render/render_state.h"
#include "lockstep/render/renderer.h"
#include "lockstep/runtime/declarations.h"
#include "lockstep/runtime/frame_buffer.h"
#include "lockstep/runtime/service.h"
#include "lockstep/runtime/town_source.h"

namespace CLI {
class App;
}

namespace lockstep {

struct RenderOptions {
  std::string device = "auto";          // auto | gpu | cpu
  bool claim_unowned = false;           // also render cameras spawned with no owner named
  std::string save_dir;                 // write PNGs of every image here (empty: none)
  uint64_t save_every = 1;              // frames between saved images
  std::vector<render::AssetSpec> assets;  // custom.<name> blueprints
  double input_timeout_s = 30;          // s to wait for the physics state of a frame
};

// The render options on a service's command line (CLI11, beside RunServiceMain's own):
// --device auto|gpu|cpu, --claim-unowned, --save-dir DIR, --save-every N (N > 0),
// --asset name=path[,class[,scale]] (repeatable). A bad value fails the parse naming the
// option and the value.
void AddRenderOptions(CLI::App& app, RenderOptions& options);
// One --asset value: name=path[,class[,scale]]. Throws std::invalid_argument naming it.
render::AssetSpec ParseAssetOption(const std::string& value);

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
  // The render state (render::RenderState: camera rig, exposure and DVS state, debug
  // shapes, weather, spawns, last poses): its hash with every ack, its snapshot for a
  // replacement process.
  uint64_t StateHash() const override { return state_.Hash(); }
  std::vector<uint8_t> SaveState() const override;
  void RestoreState(const std::vector<uint8_t>& state) override;

  const render::DeviceInfo* device() const { return renderer_ ? &renderer_->device() : nullptr; }
  std::size_t camera_count() const { return state_.cameras.size(); }
  const render::RenderState& state() const { return state_; }

 private:
  // A camera's way out: its topic and writer (the rig keeps its state).
  struct CameraOutput {
    std::string topic;
    bool large = false;
    Writer<msg::Image> writer;             // images within msg::Image's bound ...
    Writer<msg::LargeImage> large_writer;  // ... or over it (render::kMaxImageBytes): lockstep/sensor/large_image/<id>
    msg::Image image;  // reused: its buffer keeps its capacity from frame to frame
    msg::LargeImage large_image;
  };

  void Apply(const msg::Command& c, const msg::FrameStamp& stamp);
  void OpenOutput(const render::RigCamera& cam);
  render::DebugDrawList CosmosLines(const msg::GroundState* ground, const render::WorldView& world) const;
  void LoadTown(const msg::WorldInfo& world);
  bool Mine(const msg::SpawnActor& s) const;
  void Fail(const msg::FrameStamp& stamp, uint32_t actor, const std::string& why);
  // poses: each actor's drawn pose (bounding box centre); mounts: the frame a camera's
  // relative transform is given in (as CARLA: vehicles and walkers at the bottom of their
  // box, drones at their centre).
  render::WorldView BuildWorld(const msg::GroundState* ground, const msg::AirState* air, double sim_time,
                               std::map<uint32_t, render::Pose>* poses, std::map<uint32_t, render::Pose>* mounts);
  std::string ModelFor(const render::SpawnedActor& s, const render::Vec3& half_extents);
  void Publish(const render::RigCamera& cam, const render::Camera& view, const render::CameraImages& images,
               std::vector<render::DvsEvent> events, const msg::FrameStamp& stamp);
  void Save(const render::RigCamera& cam, const render::CameraImages& images, uint64_t frame);

  Bus& bus_;
  std::string name_;
  RenderOptions options_;
  std::unique_ptr<render::Renderer> renderer_;
  Writer<msg::SimEvent> event_writer_;
  Declarations declarations_;  // which required services simulate vehicles, walkers, drones
  FrameBuffer<msg::GroundState> ground_;
  FrameBuffer<msg::AirState> air_;
  TownSource town_source_;  // the coordinator's map, parsed
  uint64_t town_hash_ = 0;
  std::map<std::string, std::pair<double, double>> light_heads_;  // traffic light opendrive id -> (height, yaw)

  msg::WorldInfo world_;
  bool wait_ground_ = false, wait_air_ = false;
  render::RenderState state_;                       // everything that changes future images
  std::map<uint32_t, CameraOutput> outputs_;        // one per camera of the rig
  render::DebugDrawList cosmos_map_;                // the map's lines for cosmos cameras
};

}  // namespace lockstep
