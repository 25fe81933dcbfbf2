#pragma once
// What each camera blueprint delivers, encoded from the outputs of the shared pass:
// CARLA's cameras (rgb, depth, semantic and instance segmentation, normals, optical
// flow) and AirSim's image types for drone cameras.
#include <cstdint>
#include <string>
#include <vector>

#include "lockstep/render/camera.h"
#include "lockstep/render/renderer.h"

namespace lockstep::render {

enum class ImageKind {
  kRgb,                 // BGRA8
  kDepth,               // BGRA8, CARLA's 24-bit depth encoding
  kDepthFloat,          // float32 planar metres
  kSemantic,            // BGRA8, CARLA tag in R (G = B = 0)
  kInstance,            // BGRA8, tag in R, instance id in G (low byte) and B (high byte)
  kNormals,             // BGRA8, camera-frame normal (n + 1) / 2 * 255, R = x
  kFlow,                // 2 x float32, CARLA's optical flow in [-2, 2] (x right, y down)
  kDvs,                 // events, see dvs.h
  // AirSim ImageType, same pass.
  kAirSimScene,                // BGRA8
  kAirSimDepthPlanar,          // float32 m, along the optical axis
  kAirSimDepthPerspective,     // float32 m, to the camera centre
  kAirSimDepthVis,             // gray8: 0 at the camera, 255 at 100 m or more
  kAirSimDisparityNormalized,  // float32 0..1: f * 0.25 m / depth / width (AirSim's stereo baseline)
  kAirSimSegmentation,         // BGRA8 as kInstance (tag in R, instance id in G and B): the airsim client
  kAirSimSurfaceNormals,       // BGRA8 as kNormals                    turns instances into AirSim's object
  kAirSimInfrared,             // BGRA8 as kInstance                   ids (its state) and their colours
};

// "rgb", "depth", ... / AirSim's names "Scene", "DepthPlanar", ...; throws std::invalid_argument.
ImageKind AirSimImageKind(const std::string& name);
const char* ImageKindName(ImageKind kind);
std::uint32_t OutputsFor(ImageKind kind);  // which pass outputs it needs
int BytesPerPixel(ImageKind kind);         // 0 for events
// Encodes one image (not DVS) into dst (width * height * BytesPerPixel bytes).
void EncodeImage(ImageKind kind, const Camera& cam, const CameraImages& im, std::uint8_t* dst);
std::vector<std::uint8_t> EncodeImage(ImageKind kind, const Camera& cam, const CameraImages& im);

// Colour images of any output for viewing (PNG samples): BGRA8.
std::vector<std::uint8_t> SemanticToPalette(const std::uint8_t* labels, int width, int height);
std::vector<std::uint8_t> DepthToGray(const float* depth, int width, int height, float max_m = 100.0f);  // log scale, BGRA8
std::vector<std::uint8_t> FlowToColor(const float* flow, int width, int height);  // hue = direction, BGRA8

}  // namespace lockstep::render
