#pragma once
// The renderer: a static town (map meshes, culled per grid cell, with levels of detail),
// dynamic actors drawn from procedural or imported models, and cameras. One pass per
// camera writes all of its outputs (multiple render targets); read-back goes through
// pixel buffer objects so the next camera draws while the last one is copied out.
#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "lockstep/map/mesh.h"
#include "lockstep/map/scene.h"
#include "lockstep/render/camera.h"
#include "lockstep/render/debug_draw.h"
#include "lockstep/render/gl_context.h"
#include "lockstep/render/models.h"
#include "lockstep/render/weather.h"

namespace lockstep::render {

// Static objects' instance ids are offset so they never equal an actor id.
inline constexpr std::uint32_t kStaticInstanceBase = 0x8000;

struct StaticSceneOptions {
  double cell_size = 64;          // m, culling grid
  double detail_distance = 140;   // m: buildings and trees beyond it are drawn as boxes
  double small_distance = 90;     // m: poles, signs, fences beyond it are left out
  double marking_distance = 70;   // m: lane markings beyond it are left out
};

struct ActorDraw {
  std::uint32_t id = 0;           // instance id written to the labels (actor id)
  std::string model;              // key given to Renderer::AddModel
  Pose pose;                      // world, centre of the bounding box
  std::optional<Pose> previous_pose;  // for optical flow
  std::array<std::uint8_t, 3> paint{200, 200, 200};
  std::uint32_t light_state = 0;  // vehicles: carla.VehicleLightState bits (light:: below); 0 = all off
  std::vector<double> rotor_angles;  // rad, one per rotor of the model
  bool cull_faces = true;         // false for imported assets of unknown winding
};

// carla.VehicleLightState bits the vehicle models show.
namespace light {
inline constexpr std::uint32_t kPosition = 0x1, kLowBeam = 0x2, kHighBeam = 0x4, kBrake = 0x8;
}

struct TrafficLightDraw {
  std::uint32_t id = 0;           // traffic light actor id (instance id of its lamps)
  Pose pose;                      // pole base; the lamps face body +x
  double height = 3.0;            // m, bottom of the head
  int state = 0;                  // 0 red, 1 yellow, 2 green, 3 off
};

struct WorldView {
  Weather weather;
  std::vector<ActorDraw> actors;
  std::vector<TrafficLightDraw> traffic_lights;
  DebugDrawList debug;  // world.debug shapes: drawn into the colour output only
  // What a cosmos_visualization camera (Camera::lines_only) draws besides `debug`: the actors'
  // boxes, traffic light heads, lanes and crosswalks (CARLA's CosmosControlSensor colours).
  DebugDrawList cosmos;
};

// Read-back outputs of one camera. Pointers are valid only during the sink call; those
// not requested are null. Rows are top first.
struct CameraImages {
  int width = 0, height = 0;
  const std::uint8_t* color = nullptr;    // BGRA8
  const float* depth = nullptr;           // planar metres (sky: 1000)
  const std::uint8_t* labels = nullptr;   // RGBA8: R tag, G instance low byte, B instance high byte, A bits 16-23
  const std::uint8_t* normals = nullptr;  // BGRA8: camera-frame normal (x right, y up, z to the camera) * 0.5 + 0.5
  const float* flow = nullptr;            // 2 floats: image-plane motion since the previous pose, [-2, 2] = image size
};

// An owning copy, for tests and tools.
struct CameraFrame {
  int width = 0, height = 0;
  std::vector<std::uint8_t> color, labels, normals;
  std::vector<float> depth, flow;
  static CameraFrame Copy(const CameraImages& images);
  std::uint8_t Tag(int u, int v) const { return labels[(static_cast<std::size_t>(v) * width + u) * 4]; }
  std::uint32_t Instance(int u, int v) const;
  float Depth(int u, int v) const { return depth[static_cast<std::size_t>(v) * width + u]; }
};

struct RenderStats {
  std::uint64_t triangles = 0;         // in the cameras' views after culling and LOD, last Render call, all cameras
  std::uint64_t shadow_triangles = 0;  // drawn into the sun's shadow map in the last Render call
  std::uint64_t draw_calls = 0;        // all passes
  std::uint64_t static_triangles = 0;  // of the whole static scene at full detail
};

// Speed-ups of the render path. None changes what a camera sees (tests compare the images
// with each off); all are on by default, the benchmark turns them off to measure them.
struct RenderTuning {
  bool output_variants = true;      // shaders compute normals and flow only where a camera outputs them
  bool depth_prepass = true;        // depth and labels first, then colour shades each visible pixel once
  bool front_to_back = true;        // town cells drawn nearest first, so hidden fragments fail the depth test early
  bool static_shadow_cache = true;  // the town's sun shadows kept while sun and shadow box stay; only actors redrawn
  bool sky_by_clear = true;         // a pass without colour and flow clears to the sky's labels and depth instead of drawing it
};

class Renderer {
 public:
  explicit Renderer(DevicePreference preference = DevicePreference::kAuto);
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  const DeviceInfo& device() const;
  // Replaces the static scene. lamps: street lamp bulbs, lit at night.
  void SetStaticScene(const std::vector<map::Mesh>& meshes, const std::vector<Vec3>& lamps = {},
                      const StaticSceneOptions& options = {});
  void AddModel(const std::string& key, const Model& model);
  bool HasModel(const std::string& key) const;
  const Model* FindModel(const std::string& key) const;

  using Sink = std::function<void(std::size_t camera_index, const CameraImages& images)>;
  // Renders the cameras in order; sink(i, images) is called once per camera, in order.
  void Render(const std::vector<Camera>& cameras, const WorldView& world, const Sink& sink);
  std::vector<CameraFrame> RenderFrames(const std::vector<Camera>& cameras, const WorldView& world);
  const RenderStats& stats() const;
  void SetTuning(const RenderTuning& tuning);
  const RenderTuning& tuning() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Street lamp bulb positions of a scene's props (kind street_light), as the map builds them.
std::vector<Vec3> StreetLamps(const map::Scene& scene);

}  // namespace lockstep::render
