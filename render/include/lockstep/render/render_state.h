#pragma once
// The state of a render service: everything that changes its future images, with the
// camera rig that moves it from frame to frame. The service (render/service/) feeds it the
// tick's commands and each frame's actor poses and publishes what the renderer draws; a
// replacement render process restores a snapshot of it (Save/Restore) and the state hash
// (Hash: FNV-1a 64 of the very bytes Save writes) checks its replay like the other
// services' hashes. No DDS, no wall clock.
//
//   weather          CARLA's WeatherParameters (the run's, then set_weather)
//   spawned          every actor spawned in the run: blueprint and attributes choose its
//                    model and paint; custom props are placed by transform and parent
//   cameras          the cameras this process renders: spawn blueprint and attributes
//                    (their settings), parent and mount, sensor_tick schedule, pose at the
//                    last image (motion blur, optical flow), world pose (kept when the
//                    parent is destroyed), auto-exposure adaptation, DVS reference image
//   previous_poses   each actor's pose in the last rendered frame (motion blur, flow)
//   debug            world.debug shapes with their first frame and end of life
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "lockstep/render/camera_config.h"
#include "lockstep/render/debug_draw.h"
#include "lockstep/render/dvs.h"
#include "lockstep/render/exposure.h"
#include "lockstep/render/renderer.h"
#include "lockstep/render/state_io.h"
#include "lockstep/render/weather.h"

namespace lockstep::render {

struct SpawnedActor {
  std::string blueprint;
  std::map<std::string, std::string> attributes;
  std::uint32_t parent = 0;
  Pose transform;  // relative to the parent's mount (the world if none)
};

struct RigCamera {
  std::uint32_t id = 0;
  std::string blueprint;
  std::map<std::string, std::string> attributes;  // the spawn's
  CameraSettings settings;                        // ParseCamera(blueprint, attributes)
  std::uint32_t parent = 0;
  Pose relative;                                  // mount: relative to the parent's mount (the world if none)
  double last_capture = -1e300;                   // sim time of its last image
  std::optional<Pose> last_pose;                  // world pose at its last image
  std::optional<Pose> world_pose;                 // at the last frame that found its parent
  AutoExposure exposure;                          // colour cameras: adapts from image to image
  std::optional<DvsSensor> dvs;                   // event cameras

  std::string role() const;  // role_name
  // True when its images change its state (histogram auto-exposure of a colour image, DVS
  // reference image): a replay must render it.
  bool ImagesChangeState() const;
};

// Cameras with one pose and one lens share a pass; the pass renders `camera` (all of its
// members' outputs) and each member takes its image from it.
struct CameraPass {
  Camera camera;
  std::vector<std::uint32_t> members;
  std::vector<double> exposure_dt;  // per member: s of sim time since its previous image (0: first)
};

struct RenderState {
  Weather weather;
  std::map<std::uint32_t, SpawnedActor> spawned;
  std::map<std::uint32_t, RigCamera> cameras;
  std::map<std::uint32_t, Pose> previous_poses;
  DebugShapes debug;

  // Records a spawn; when `mine` and a camera blueprint, the camera joins the rig and is
  // returned. Throws std::invalid_argument naming the attribute (ParseCamera); the actor is
  // then recorded without a camera. seed: the run's (DVS threshold noise).
  const RigCamera* Spawn(std::uint32_t id, SpawnedActor actor, bool mine, std::uint64_t seed);
  // CARLA destroys only the actor; Unreal detaches its cameras keeping their world
  // transform: they stay and draw from where they were.
  void Destroy(std::uint32_t id);
  void SetTransform(std::uint32_t id, const Pose& transform);
  // The cameras due at frame k (sim time t), in passes; advances their schedule and poses.
  // mounts: the frame each actor's children are mounted in, this frame.
  std::vector<CameraPass> Plan(std::uint64_t k, double t, const std::map<std::uint32_t, Pose>& mounts, std::uint64_t seed);
  // Member i of `pass` takes its image: auto-exposure adapts; a DVS camera returns its events
  // (t: sim time of the image).
  std::vector<DvsEvent> Take(const CameraPass& pass, std::size_t i, const CameraImages& images, double t);
  // True when a member's images change its state (see RigCamera::ImagesChangeState).
  bool NeedsImages(const CameraPass& pass) const;

  // Snapshot; Restore replaces the whole state and throws std::invalid_argument on bytes
  // that are not one (truncated, another version, trailing bytes, a bad camera).
  void Save(StateOut& out) const;
  std::vector<std::uint8_t> Save() const;
  void Restore(const std::vector<std::uint8_t>& bytes);
  // FNV-1a 64 of the snapshot's bytes.
  std::uint64_t Hash() const;
};

}  // namespace lockstep::render
