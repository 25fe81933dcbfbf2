#include "lockstep/render/images.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <stdexcept>

namespace lockstep::render {

// The encoders below write B, G, R, A as one 32-bit word.
static_assert(std::endian::native == std::endian::little, "images.cpp assumes a little-endian host");

ImageKind AirSimImageKind(const std::string& n) {
  static const std::pair<const char*, ImageKind> names[] = {
      {"Scene", ImageKind::kAirSimScene},
      {"DepthPlanar", ImageKind::kAirSimDepthPlanar},
      {"DepthPerspective", ImageKind::kAirSimDepthPerspective},
      {"DepthVis", ImageKind::kAirSimDepthVis},
      {"DisparityNormalized", ImageKind::kAirSimDisparityNormalized},
      {"Segmentation", ImageKind::kAirSimSegmentation},
      {"SurfaceNormals", ImageKind::kAirSimSurfaceNormals},
      {"Infrared", ImageKind::kAirSimInfrared}};
  for (const auto& [name, kind] : names) {
    if (n == name) return kind;
  }
  throw std::invalid_argument("image_type '" + n +
                              "': expected Scene, DepthPlanar, DepthPerspective, DepthVis, DisparityNormalized, Segmentation, "
                              "SurfaceNormals or Infrared");
}

const char* ImageKindName(ImageKind k) {
  switch (k) {
    case ImageKind::kRgb: return "rgb";
    case ImageKind::kDepth: return "depth";
    case ImageKind::kDepthFloat: return "depth_float";
    case ImageKind::kSemantic: return "semantic_segmentation";
    case ImageKind::kInstance: return "instance_segmentation";
    case ImageKind::kNormals: return "normals";
    case ImageKind::kFlow: return "optical_flow";
    case ImageKind::kDvs: return "dvs";
    case ImageKind::kAirSimScene: return "Scene";
    case ImageKind::kAirSimDepthPlanar: return "DepthPlanar";
    case ImageKind::kAirSimDepthPerspective: return "DepthPerspective";
    case ImageKind::kAirSimDepthVis: return "DepthVis";
    case ImageKind::kAirSimDisparityNormalized: return "DisparityNormalized";
    case ImageKind::kAirSimSegmentation: return "Segmentation";
    case ImageKind::kAirSimSurfaceNormals: return "SurfaceNormals";
    case ImageKind::kAirSimInfrared: return "Infrared";
  }
  return "?";
}

std::uint32_t OutputsFor(ImageKind k) {
  switch (k) {
    case ImageKind::kRgb:
    case ImageKind::kDvs:
    case ImageKind::kAirSimScene: return kOutColor;
    case ImageKind::kDepth:
    case ImageKind::kDepthFloat:
    case ImageKind::kAirSimDepthPlanar:
    case ImageKind::kAirSimDepthPerspective:
    case ImageKind::kAirSimDepthVis:
    case ImageKind::kAirSimDisparityNormalized: return kOutDepth;
    case ImageKind::kSemantic:
    case ImageKind::kInstance:
    case ImageKind::kAirSimSegmentation:
    case ImageKind::kAirSimInfrared: return kOutLabels;
    case ImageKind::kNormals:
    case ImageKind::kAirSimSurfaceNormals: return kOutNormals;
    case ImageKind::kFlow: return kOutFlow;
  }
  return 0;
}

int BytesPerPixel(ImageKind k) {
  switch (k) {
    case ImageKind::kDvs: return 0;
    case ImageKind::kFlow: return 8;
    case ImageKind::kAirSimDepthVis: return 1;
    default: return 4;
  }
}

void EncodeImage(ImageKind k, const Camera& cam, const CameraImages& im, std::uint8_t* dst) {
  const std::size_t n = static_cast<std::size_t>(im.width) * im.height;
  auto need = [&](const void* p, const char* what) {
    if (!p) throw std::invalid_argument(std::string("EncodeImage(") + ImageKindName(k) + "): the pass has no " + what + " output");
  };
  switch (k) {
    case ImageKind::kRgb:
    case ImageKind::kAirSimScene:
      need(im.color, "colour");
      std::memcpy(dst, im.color, n * 4);
      return;
    case ImageKind::kNormals:
    case ImageKind::kAirSimSurfaceNormals:
      need(im.normals, "normals");
      std::memcpy(dst, im.normals, n * 4);
      return;
    case ImageKind::kFlow:
      need(im.flow, "flow");
      // Image rows top first and y down: the pass already writes it that way.
      std::memcpy(dst, im.flow, n * 8);
      return;
    case ImageKind::kDepth: {
      need(im.depth, "depth");
      // EncodeCarlaDepth on 32-bit words, so the compiler can vectorize the loop.
      constexpr double kScale = (256.0 * 256.0 * 256.0 - 1.0) / kFarPlane;
      for (std::size_t i = 0; i < n; ++i) {
        const double d = std::clamp(static_cast<double>(im.depth[i]) * kScale, 0.0, 256.0 * 256.0 * 256.0 - 1.0);
        const auto v = static_cast<std::uint32_t>(d + 0.5);
        const std::uint32_t word = 0xff000000u | ((v & 0xffu) << 16) | (v & 0xff00u) | ((v >> 16) & 0xffu);  // B G R A
        std::memcpy(dst + i * 4, &word, 4);
      }
      return;
    }
    case ImageKind::kDepthFloat:
    case ImageKind::kAirSimDepthPlanar:
      need(im.depth, "depth");
      std::memcpy(dst, im.depth, n * 4);
      return;
    case ImageKind::kAirSimDepthPerspective: {
      need(im.depth, "depth");
      const double f = cam.Focal(), cx = im.width / 2.0, cy = im.height / 2.0;
      float* out = reinterpret_cast<float*>(dst);
      for (int v = 0; v < im.height; ++v) {
        const double dy = (v + 0.5 - cy) / f;
        for (int u = 0; u < im.width; ++u) {
          const double dx = (u + 0.5 - cx) / f;
          const std::size_t i = static_cast<std::size_t>(v) * im.width + u;
          out[i] = static_cast<float>(im.depth[i] * std::sqrt(1 + dx * dx + dy * dy));
        }
      }
      return;
    }
    case ImageKind::kAirSimDepthVis:
      need(im.depth, "depth");
      for (std::size_t i = 0; i < n; ++i) dst[i] = static_cast<std::uint8_t>(std::lround(std::clamp(im.depth[i] / 100.0f, 0.0f, 1.0f) * 255));
      return;
    case ImageKind::kAirSimDisparityNormalized: {
      need(im.depth, "depth");
      const double k_ = cam.Focal() * 0.25 / im.width;
      float* out = reinterpret_cast<float*>(dst);
      for (std::size_t i = 0; i < n; ++i) out[i] = static_cast<float>(std::clamp(k_ / std::max(1e-3f, im.depth[i]), 0.0, 1.0));
      return;
    }
    case ImageKind::kSemantic:
      need(im.labels, "labels");
      for (std::size_t i = 0; i < n; ++i) {
        std::uint32_t label;
        std::memcpy(&label, im.labels + i * 4, 4);
        const std::uint32_t word = 0xff000000u | ((label & 0xffu) << 16);  // B 0, G 0, R tag, A 255
        std::memcpy(dst + i * 4, &word, 4);
      }
      return;
    case ImageKind::kInstance:
    // AirSim's segmentation and infrared colour AirSim's object ids, which are the airsim
    // client's state (simSetSegmentationObjectID): the image carries the instances it maps.
    case ImageKind::kAirSimSegmentation:
    case ImageKind::kAirSimInfrared:
      need(im.labels, "labels");
      for (std::size_t i = 0; i < n; ++i) {
        dst[i * 4 + 0] = im.labels[i * 4 + 2];  // B: instance high byte
        dst[i * 4 + 1] = im.labels[i * 4 + 1];  // G: instance low byte
        dst[i * 4 + 2] = im.labels[i * 4];      // R: tag
        dst[i * 4 + 3] = 255;
      }
      return;
    case ImageKind::kDvs: throw std::invalid_argument("EncodeImage: DVS gives events, see DvsSensor");
  }
}

std::vector<std::uint8_t> EncodeImage(ImageKind k, const Camera& cam, const CameraImages& im) {
  std::vector<std::uint8_t> out(static_cast<std::size_t>(im.width) * im.height * BytesPerPixel(k));
  EncodeImage(k, cam, im, out.data());
  return out;
}

std::vector<std::uint8_t> SemanticToPalette(const std::uint8_t* labels, int w, int h) {
  std::vector<std::uint8_t> out(static_cast<std::size_t>(w) * h * 4);
  for (std::size_t i = 0; i < out.size() / 4; ++i) {
    const auto c = PaletteRgb(labels[i * 4]);
    out[i * 4] = c[2];
    out[i * 4 + 1] = c[1];
    out[i * 4 + 2] = c[0];
    out[i * 4 + 3] = 255;
  }
  return out;
}

std::vector<std::uint8_t> DepthToGray(const float* depth, int w, int h, float max_m) {
  std::vector<std::uint8_t> out(static_cast<std::size_t>(w) * h * 4);
  for (std::size_t i = 0; i < out.size() / 4; ++i) {
    const float t = std::log1p(std::clamp(depth[i], 0.0f, max_m)) / std::log1p(max_m);
    const auto g = static_cast<std::uint8_t>(std::lround(255 * t));
    out[i * 4] = out[i * 4 + 1] = out[i * 4 + 2] = g;
    out[i * 4 + 3] = 255;
  }
  return out;
}

std::vector<std::uint8_t> FlowToColor(const float* flow, int w, int h) {
  std::vector<std::uint8_t> out(static_cast<std::size_t>(w) * h * 4);
  for (std::size_t i = 0; i < out.size() / 4; ++i) {
    const float fx = flow[i * 2] * w / 2, fy = flow[i * 2 + 1] * h / 2;  // px
    const float mag = std::min(1.0f, std::sqrt(fx * fx + fy * fy) / 20.0f);
    const float a = std::atan2(fy, fx);
    for (int c = 0; c < 3; ++c) {
      const float phase = a + static_cast<float>(c) * 2.0944f;
      out[i * 4 + c] = static_cast<std::uint8_t>(std::lround(255 * (1 - mag + mag * (0.5f + 0.5f * std::cos(phase)))));
    }
    out[i * 4 + 3] = 255;
  }
  return out;
}

}  // namespace lockstep::render
