#pragma once
// A headless OpenGL 3.3 core context through EGL, no window system. At start it picks
// the platform: an EGL device with a hardware driver (EGL_EXT_device_enumeration +
// EGL_EXT_platform_device, e.g. NVIDIA's) when one is present, else Mesa's surfaceless
// platform (llvmpipe on the CPU). The choice is reported by device().
#include <memory>
#include <string>

namespace lockstep::render {

enum class DevicePreference {
  kAuto,  // a hardware EGL device if there is one, else Mesa surfaceless
  kGpu,   // a hardware EGL device or fail
  kCpu,   // Mesa surfaceless (llvmpipe)
};
// "auto" | "gpu" | "cpu"; throws std::invalid_argument otherwise.
DevicePreference ParseDevicePreference(const std::string& s);

struct DeviceInfo {
  std::string platform;     // "device" (EGL_PLATFORM_DEVICE_EXT) or "surfaceless" (EGL_PLATFORM_SURFACELESS_MESA)
  std::string name;         // short: "llvmpipe", "nvidia", or the GL renderer string
  std::string gl_renderer;  // GL_RENDERER
  std::string gl_version;   // GL_VERSION
  bool hardware = false;
};

class GlContext {
 public:
  // Creates the context and makes it current on the calling thread. Throws
  // std::runtime_error saying what failed (no EGL display, no GL 3.3 core context, ...).
  explicit GlContext(DevicePreference preference = DevicePreference::kAuto);
  ~GlContext();
  GlContext(const GlContext&) = delete;
  GlContext& operator=(const GlContext&) = delete;
  void MakeCurrent();
  const DeviceInfo& device() const { return device_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  DeviceInfo device_;
};

}  // namespace lockstep::render
