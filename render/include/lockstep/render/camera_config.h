#pragma once
// Camera blueprints (CARLA's ids and attributes, plus AirSim's image types) and the
// parsing of a spawn's attributes into camera settings. The service turns the table into
// blueprint declarations; parsing names the attribute that is wrong.
#include <map>
#include <string>
#include <vector>

#include "lockstep/render/camera.h"
#include "lockstep/render/dvs.h"
#include "lockstep/render/exposure.h"
#include "lockstep/render/images.h"

namespace lockstep::render {

// An attribute's type, as blueprint.idl's AttributeDeclaration types it.
enum class AttributeType { kBool, kInt, kFloat, kString };

struct AttributeSpec {
  std::string id;
  AttributeType type = AttributeType::kFloat;
  std::string def;  // the default as CARLA writes it (exact: the declaration carries this text)
  double min = -1e300, max = 1e300;
  std::vector<std::string> choices;  // restricted values for strings
};

struct CameraBlueprintSpec {
  std::string id;  // e.g. "sensor.camera.rgb"
  ImageKind kind;
  std::vector<AttributeSpec> attributes;
};

const std::vector<CameraBlueprintSpec>& CameraBlueprints();
bool IsCameraBlueprint(const std::string& id);

struct CameraSettings {
  std::string blueprint;
  ImageKind kind = ImageKind::kRgb;
  Camera camera;              // size, fov, exposure, lens; pose set per frame
  double sensor_tick = 0;     // s between images; 0 = every frame
  bool paper_classes = false; // semantic: the 2017 paper's 12 classes instead of CARLA's 29
  DvsParams dvs;
  ExposureSettings exposure;  // colour cameras; camera.exposure is its first image's multiplier
};

// Largest image payload (bytes) one msg::Image carries: 1920 x 1080 x 4. A larger image goes
// as a msg::LargeImage (unbounded) on the camera's large_image topic.
inline constexpr std::size_t kMaxImageBytes = 8294400;
// Largest camera: 8K, 7680 x 4320 pixels (AirSim's settings cameras go up to it).
inline constexpr std::size_t kMaxCameraPixels = std::size_t{7680} * 4320;

// Attributes not given take their defaults; unknown ones are ignored (role_name, ...).
// Throws std::invalid_argument naming the attribute and the value.
CameraSettings ParseCamera(const std::string& blueprint, const std::map<std::string, std::string>& attributes);

}  // namespace lockstep::render
