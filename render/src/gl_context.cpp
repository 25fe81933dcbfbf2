#include "lockstep/render/gl_context.h"

#include <EGL/egl.h>
#include <EGL/eglext.h>
#define GL_GLEXT_PROTOTYPES 1
#include <GL/gl.h>

#include <cstring>
#include <stdexcept>
#include <vector>

namespace lockstep::render {

DevicePreference ParseDevicePreference(const std::string& s) {
  if (s == "auto" || s.empty()) return DevicePreference::kAuto;
  if (s == "gpu") return DevicePreference::kGpu;
  if (s == "cpu") return DevicePreference::kCpu;
  throw std::invalid_argument("render device '" + s + "': expected auto, gpu or cpu");
}

struct GlContext::Impl {
  EGLDisplay display = EGL_NO_DISPLAY;
  EGLContext context = EGL_NO_CONTEXT;
  std::string platform;
};

namespace {

bool HasExtension(const char* list, const char* name) {
  if (!list) return false;
  const std::size_t n = std::strlen(name);
  for (const char* p = list; (p = std::strstr(p, name)) != nullptr; p += n) {
    if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0')) return true;
  }
  return false;
}

// A context on `display`, or EGL_NO_CONTEXT (the display is then terminated).
EGLContext TryContext(EGLDisplay display) {
  EGLint major = 0, minor = 0;
  if (display == EGL_NO_DISPLAY || !eglInitialize(display, &major, &minor)) return EGL_NO_CONTEXT;
  if (!eglBindAPI(EGL_OPENGL_API)) {
    eglTerminate(display);
    return EGL_NO_CONTEXT;
  }
  const char* ext = eglQueryString(display, EGL_EXTENSIONS);
  EGLConfig config = nullptr;
  if (!HasExtension(ext, "EGL_KHR_no_config_context") && !HasExtension(ext, "EGL_MESA_configless_context")) {
    const EGLint attrs[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
    EGLint n = 0;
    if (!eglChooseConfig(display, attrs, &config, 1, &n) || n < 1) {
      eglTerminate(display);
      return EGL_NO_CONTEXT;
    }
  }
  const EGLint ctx_attrs[] = {EGL_CONTEXT_MAJOR_VERSION, 3, EGL_CONTEXT_MINOR_VERSION, 3, EGL_CONTEXT_OPENGL_PROFILE_MASK,
                              EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
  EGLContext ctx = eglCreateContext(display, config, EGL_NO_CONTEXT, ctx_attrs);
  if (ctx == EGL_NO_CONTEXT || !eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx)) {
    if (ctx != EGL_NO_CONTEXT) eglDestroyContext(display, ctx);
    eglTerminate(display);
    return EGL_NO_CONTEXT;
  }
  return ctx;
}

std::string ShortName(const std::string& renderer) {
  if (renderer.find("llvmpipe") != std::string::npos) return "llvmpipe";
  if (renderer.find("softpipe") != std::string::npos) return "softpipe";
  if (renderer.find("NVIDIA") != std::string::npos || renderer.find("nvidia") != std::string::npos) return "nvidia";
  return renderer;
}

bool IsSoftware(const std::string& renderer) {
  return renderer.find("llvmpipe") != std::string::npos || renderer.find("softpipe") != std::string::npos ||
         renderer.find("Software") != std::string::npos;
}

}  // namespace

GlContext::GlContext(DevicePreference preference) : impl_(std::make_unique<Impl>()) {
  auto get_platform_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(eglGetProcAddress("eglGetPlatformDisplayEXT"));
  if (!get_platform_display) throw std::runtime_error("EGL: eglGetPlatformDisplayEXT is missing (need EGL_EXT_platform_base)");
  std::string tried;
  // 1. Hardware EGL devices (NVIDIA's EGL through glvnd; Mesa lists its software device too).
  if (preference != DevicePreference::kCpu) {
    auto query_devices = reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
    auto query_device_string = reinterpret_cast<PFNEGLQUERYDEVICESTRINGEXTPROC>(eglGetProcAddress("eglQueryDeviceStringEXT"));
    EGLint count = 0;
    if (query_devices && query_devices(0, nullptr, &count) && count > 0) {
      std::vector<EGLDeviceEXT> devices(static_cast<std::size_t>(count));
      query_devices(count, devices.data(), &count);
      for (EGLint i = 0; i < count && impl_->context == EGL_NO_CONTEXT; ++i) {
        const char* dext = query_device_string ? query_device_string(devices[i], EGL_EXTENSIONS) : nullptr;
        if (HasExtension(dext, "EGL_MESA_device_software")) continue;  // that is llvmpipe: the surfaceless path below
        EGLDisplay d = get_platform_display(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr);
        EGLContext c = TryContext(d);
        if (c == EGL_NO_CONTEXT) {
          tried += " device " + std::to_string(i) + " (no GL 3.3 core context);";
          continue;
        }
        const std::string renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
        if (IsSoftware(renderer)) {  // a software device listed as a device: keep looking
          eglMakeCurrent(d, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
          eglDestroyContext(d, c);
          eglTerminate(d);
          tried += " device " + std::to_string(i) + " (software);";
          continue;
        }
        impl_->display = d;
        impl_->context = c;
        impl_->platform = "device";
      }
    } else {
      tried += " no EGL devices (EGL_EXT_device_enumeration);";
    }
    if (impl_->context == EGL_NO_CONTEXT && preference == DevicePreference::kGpu) {
      throw std::runtime_error("EGL: no hardware EGL device gives a GL 3.3 core context:" + tried);
    }
  }
  // 2. Mesa's surfaceless platform.
  if (impl_->context == EGL_NO_CONTEXT) {
    EGLDisplay d = get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    EGLContext c = TryContext(d);
    if (c == EGL_NO_CONTEXT) {
      throw std::runtime_error("EGL: no GL 3.3 core context on Mesa's surfaceless platform either (" + tried +
                               " EGL error 0x" + std::to_string(eglGetError()) + ")");
    }
    impl_->display = d;
    impl_->context = c;
    impl_->platform = "surfaceless";
  }
  device_.platform = impl_->platform;
  device_.gl_renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  device_.gl_version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  device_.name = ShortName(device_.gl_renderer);
  device_.hardware = !IsSoftware(device_.gl_renderer);
}

GlContext::~GlContext() {
  if (impl_->display != EGL_NO_DISPLAY) {
    eglMakeCurrent(impl_->display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    // The display stays initialised: EGL displays are shared by the whole process.
    if (impl_->context != EGL_NO_CONTEXT) eglDestroyContext(impl_->display, impl_->context);
  }
}

void GlContext::MakeCurrent() {
  if (!eglMakeCurrent(impl_->display, EGL_NO_SURFACE, EGL_NO_SURFACE, impl_->context)) {
    throw std::runtime_error("EGL: eglMakeCurrent failed");
  }
}

}  // namespace lockstep::render
