#include "lockstep/render/renderer.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <stdexcept>

#include "gl_util.h"
#include "lockstep/render/motion_blur.h"
#include "lockstep/render/wide_angle_cube.h"
#include "shaders.h"
#include "static_scene.h"

namespace lockstep::render {
namespace {

constexpr int kOutputs = 5;
enum : std::uint32_t {
  kFeatureColor = 1,
  kFeatureShadows = 2,
  kFeatureNight = 4,
  kFeatureWet = 8,
  kFeaturePuddles = 16,
  kFeatureRain = 32,
  kFeatureClouds = 64,
  kFeatureVignette = 128,
  kFeatureNormals = 256,  // OUT_NORMALS: the normals output is computed
  kFeatureFlow = 512,     // OUT_FLOW: the optical flow output is computed
  kFeatureGamma22 = 1024, // GAMMA_22: the default gamma 2.2 by a polynomial instead of pow
};
constexpr int kNoiseSize = 256;  // lattice of the shaders' value noise (clouds, puddles)
constexpr int kSlots = 2;  // read-back double buffer: draw camera i+1 while camera i is copied out
constexpr int kShadowSize = 1024;
constexpr double kShadowExtent = 60;  // m, half width of the sun's shadow box around the first camera
// The shadow box centre moves in steps of this (m), so the town's shadow map can be kept
// while the cameras move inside one step.
constexpr double kShadowSnap = 8;

struct OutputFormat {
  std::uint32_t bit;
  GLenum internal, format, type;
  int bytes;  // per pixel
};
const OutputFormat kFormats[kOutputs] = {
    // Colour and normals are written B, G, R, A by the shader and read back as they are:
    // a swizzle in glReadPixels takes llvmpipe's slow conversion path.
    {kOutColor, GL_RGBA8, GL_RGBA, GL_UNSIGNED_BYTE, 4},
    {kOutLabels, GL_RGBA8UI, GL_RGBA_INTEGER, GL_UNSIGNED_BYTE, 4},
    {kOutDepth, GL_R32F, GL_RED, GL_FLOAT, 4},
    {kOutNormals, GL_RGBA8, GL_RGBA, GL_UNSIGNED_BYTE, 4},
    {kOutFlow, GL_RG32F, GL_RG, GL_FLOAT, 8},
};

Eigen::Matrix4f ModelMatrix(const Pose& p) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topLeftCorner<3, 3>() = p.orientation.normalized().toRotationMatrix();
  m.topRightCorner<3, 1>() = p.position;
  return m.cast<float>();
}

Eigen::Matrix4f RotorMatrix(const Vec3& hub, double angle) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topLeftCorner<3, 3>() = Eigen::AngleAxisd(angle, Vec3::UnitZ()).toRotationMatrix();
  m.topRightCorner<3, 1>() = hub;
  return m.cast<float>();
}

// Blade angle of rotor r of a drawn actor (clockwise rotors turn the other way).
double RotorAngle(const ActorDraw& a, const Model& m, std::size_t r) {
  const double angle = r < a.rotor_angles.size() ? a.rotor_angles[r] : 0.0;
  return m.rotors[r].clockwise ? -angle : angle;
}

struct Target {
  GLuint fbo = 0, depth = 0;
  GLuint tex[kOutputs] = {};
};

struct Pbo {
  GLuint buffer = 0;
  std::size_t size = 0;
};

}  // namespace

std::uint32_t CameraFrame::Instance(int u, int v) const {
  const std::uint8_t* p = &labels[(static_cast<std::size_t>(v) * width + u) * 4];
  return p[1] | (p[2] << 8) | (p[3] << 16);
}

CameraFrame CameraFrame::Copy(const CameraImages& im) {
  CameraFrame f;
  f.width = im.width;
  f.height = im.height;
  const std::size_t n = static_cast<std::size_t>(im.width) * im.height;
  if (im.color) f.color.assign(im.color, im.color + n * 4);
  if (im.labels) f.labels.assign(im.labels, im.labels + n * 4);
  if (im.normals) f.normals.assign(im.normals, im.normals + n * 4);
  if (im.depth) f.depth.assign(im.depth, im.depth + n);
  if (im.flow) f.flow.assign(im.flow, im.flow + n * 2);
  return f;
}

std::vector<Vec3> StreetLamps(const map::Scene& scene) {
  std::vector<Vec3> out;
  for (const auto& p : scene.props) {
    if (p.kind != "street_light") continue;
    const double h = p.height > 0 ? p.height : 3.0;
    // As map::BuildSceneMeshes: the lamp head box ends 0.25 m below the top, 1.7 m out.
    out.push_back(Vec3(p.x, p.y, p.z) + Vec3(0, 0, h - 0.25) + 1.7 * Vec3(std::cos(p.yaw), std::sin(p.yaw), 0));
  }
  return out;
}

struct Renderer::Impl {
  GlContext context;
  // Scene and sky programs per feature set (FEATURE_* defines), compiled on first use.
  std::map<std::uint32_t, std::pair<gl::Program, gl::Program>> programs;
  gl::Program shadow;
  gl::Program debug;  // world.debug shapes
  GLuint debug_vao = 0, debug_vbo = 0;
  gl::Program* scene_ptr = nullptr;
  GLuint sky_vao = 0;
  StaticScene statics;
  // Models share one buffer, re-uploaded when one is added.
  GLuint model_vao = 0, model_vbo = 0;
  std::vector<Vertex> model_vertices;
  struct Entry {
    Model model;
    GLint first = 0;
  };
  std::map<std::string, Entry> models;
  bool models_dirty = false;
  std::map<std::pair<int, int>, Target> targets;
  Pbo pbos[kSlots][kOutputs];
  GLsync fences[kSlots] = {};
  GLuint shadow_fbo = 0, shadow_tex = 0;
  GLuint noise_tex = 0;
  // The static town's shadow map (RenderTuning::static_shadow_cache) and what it was drawn for.
  GLuint static_shadow_fbo = 0, static_shadow_tex = 0;
  struct {
    bool valid = false;
    Eigen::Vector3f centre, sun;
  } static_shadow;
  RenderStats stats;
  RenderTuning tuning;
  // Lens distortion: per camera lens, the source pixel of every output pixel (-1: outside);
  // the distorted outputs are gathered from the read-back into these buffers.
  std::map<std::string, std::vector<std::int32_t>> remaps;
  std::vector<std::uint8_t> lens_out[kOutputs];
  std::vector<std::uint8_t> blurred;  // the colour output after motion blur
  bool blur_only_flow = false;        // the pass draws flow for its motion blur only (not an output)

  explicit Impl(DevicePreference pref) : context(pref) {
    Programs(0);  // labels only
    Programs(kFeatureColor);
    shadow = gl::Program(gl::BuildProgram(shaders::kShadowVertex, shaders::kShadowFragment, "shadow"));
    debug = gl::Program(gl::BuildProgram(shaders::kDebugVertex, shaders::kDebugFragment, "debug"));
    glGenVertexArrays(1, &debug_vao);
    glGenBuffers(1, &debug_vbo);
    glBindVertexArray(debug_vao);
    glBindBuffer(GL_ARRAY_BUFFER, debug_vbo);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(DebugVertex), reinterpret_cast<void*>(0));
    glEnableVertexAttribArray(1);
    glVertexAttribPointer(1, 4, GL_FLOAT, GL_FALSE, sizeof(DebugVertex), reinterpret_cast<void*>(3 * sizeof(float)));
    glBindVertexArray(0);
    glGenVertexArrays(1, &sky_vao);
    glGenVertexArrays(1, &model_vao);
    glGenBuffers(1, &model_vbo);
    glBindVertexArray(model_vao);
    glBindBuffer(GL_ARRAY_BUFFER, model_vbo);
    SetupVertexLayout();
    glBindVertexArray(0);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    // Shadow map of the sun, and the static town's part of it.
    MakeShadowMap(&shadow_tex, &shadow_fbo);
    MakeShadowMap(&static_shadow_tex, &static_shadow_fbo);
    MakeNoise();
    AddTrafficLightModel();
  }

  static void MakeShadowMap(GLuint* tex, GLuint* fbo) {
    glGenTextures(1, tex);
    glBindTexture(GL_TEXTURE_2D, *tex);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_DEPTH_COMPONENT24, kShadowSize, kShadowSize, 0, GL_DEPTH_COMPONENT, GL_FLOAT, nullptr);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
    glGenFramebuffers(1, fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, *fbo);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, *tex, 0);
    glDrawBuffer(GL_NONE);
    glReadBuffer(GL_NONE);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
  }

  // Lattice values in [0, 1) from an integer hash of the lattice point (fixed, no seed).
  void MakeNoise() {
    std::vector<float> v(static_cast<std::size_t>(kNoiseSize) * kNoiseSize);
    for (std::size_t i = 0; i < v.size(); ++i) {
      std::uint32_t x = static_cast<std::uint32_t>(i) * 0x9e3779b9u + 0x7f4a7c15u;
      x ^= x >> 16;
      x *= 0x7feb352du;
      x ^= x >> 15;
      x *= 0x846ca68bu;
      x ^= x >> 16;
      v[i] = static_cast<float>(x >> 8) / 16777216.0f;
    }
    glGenTextures(1, &noise_tex);
    glBindTexture(GL_TEXTURE_2D, noise_tex);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_R32F, kNoiseSize, kNoiseSize, 0, GL_RED, GL_FLOAT, v.data());
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_REPEAT);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_REPEAT);
  }

  ~Impl() {
    statics.Release();
    for (auto& [size, t] : targets) {
      glDeleteFramebuffers(1, &t.fbo);
      glDeleteRenderbuffers(1, &t.depth);
      glDeleteTextures(kOutputs, t.tex);
    }
    for (auto& slot : pbos) {
      for (auto& p : slot) {
        if (p.buffer) glDeleteBuffers(1, &p.buffer);
      }
    }
    for (auto& f : fences) {
      if (f) glDeleteSync(f);
    }
    glDeleteFramebuffers(1, &shadow_fbo);
    glDeleteTextures(1, &shadow_tex);
    glDeleteTextures(1, &noise_tex);
    glDeleteFramebuffers(1, &static_shadow_fbo);
    glDeleteTextures(1, &static_shadow_tex);
    glDeleteBuffers(1, &model_vbo);
    glDeleteVertexArrays(1, &model_vao);
    glDeleteBuffers(1, &debug_vbo);
    glDeleteVertexArrays(1, &debug_vao);
    glDeleteProgram(debug.id());
    glDeleteVertexArrays(1, &sky_vao);
    for (auto& [mask, p] : programs) {
      glDeleteProgram(p.first.id());
      glDeleteProgram(p.second.id());
    }
    glDeleteProgram(shadow.id());
  }

  std::pair<gl::Program, gl::Program>& Programs(std::uint32_t mask) {
    auto it = programs.find(mask);
    if (it != programs.end()) return it->second;
    static const std::pair<std::uint32_t, const char*> defines[] = {
        {kFeatureColor, "LOCKSTEP_COLOR"}, {kFeatureShadows, "FEATURE_SHADOWS"}, {kFeatureNight, "FEATURE_NIGHT"},
        {kFeatureWet, "FEATURE_WET"},      {kFeaturePuddles, "FEATURE_PUDDLES"}, {kFeatureRain, "FEATURE_RAIN"},
        {kFeatureClouds, "FEATURE_CLOUDS"}, {kFeatureVignette, "FEATURE_VIGNETTE"}, {kFeatureNormals, "OUT_NORMALS"},
        {kFeatureFlow, "OUT_FLOW"}, {kFeatureGamma22, "GAMMA_22"}};
    const std::string common = shaders::kCommon;
    std::string head = "#version 330 core\n";
    for (const auto& [bit, name] : defines) {
      if (mask & bit) head += std::string("#define ") + name + " 1\n";
    }
    head += common.substr(common.find('\n') + 1);
    auto& p = programs[mask];
    p.first = gl::Program(gl::BuildProgram(head + shaders::kSceneVertex, head + shaders::kSceneFragment, "scene"));
    p.second = gl::Program(gl::BuildProgram(head + shaders::kSkyVertex, head + shaders::kSkyFragment, "sky"));
    return p;
  }

  // Shader features of the outputs other than colour.
  std::uint32_t OutputFeatures(std::uint32_t outputs) const {
    if (!tuning.output_variants) return kFeatureNormals | kFeatureFlow;
    return ((outputs & kOutNormals) ? kFeatureNormals : 0u) | ((outputs & kOutFlow) ? kFeatureFlow : 0u);
  }

  // Shader features of the colour output under this weather.
  static std::uint32_t ColourFeatures(const Camera& cam, const Lighting& l, bool shadows) {
    std::uint32_t m = kFeatureColor;
    if (shadows) m |= kFeatureShadows;
    if (l.night) m |= kFeatureNight;
    if (l.wetness > 0) m |= kFeatureWet;
    if (l.puddles > 0) m |= kFeaturePuddles;
    if (l.rain > 0 && cam.post_process) m |= kFeatureRain;
    if (l.clouds > 0.02f) m |= kFeatureClouds;
    if (cam.lens_circle_multiplier > 0) m |= kFeatureVignette;
    if (cam.gamma == 2.2 || cam.gamma <= 0.1) m |= kFeatureGamma22;  // SetLighting reads gamma <= 0.1 as 2.2
    return m;
  }

  void AddTrafficLightModel() {
    Model m;
    const Material mats[3] = {kMatLightRed, kMatLightYellow, kMatLightGreen};
    for (int i = 0; i < 3; ++i) {
      map::Mesh lamp;
      // Head: 0.35 m square, 1 m tall, from `height` up (map::BuildSceneMeshes); red on top.
      map::AddBox(lamp, Eigen::Vector3d(0.18, 0, 0.72 - 0.3 * i), 0.04, 0.2, 0.2, 0, true);
      AppendMesh(&m.vertices, lamp, {40, 40, 40}, mats[i], tag::kTrafficLight);
    }
    m.half_extents = Vec3(0.2, 0.2, 0.5);
    AddModel("__traffic_light_lamps", m);
  }

  void AddModel(const std::string& key, const Model& m) {
    Entry e;
    e.model = m;
    e.first = static_cast<GLint>(model_vertices.size());
    model_vertices.insert(model_vertices.end(), m.vertices.begin(), m.vertices.end());
    models[key] = std::move(e);
    models_dirty = true;
  }

  void UploadModels() {
    if (!models_dirty) return;
    glBindBuffer(GL_ARRAY_BUFFER, model_vbo);
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(model_vertices.size() * sizeof(Vertex)), model_vertices.data(),
                 GL_STATIC_DRAW);
    models_dirty = false;
  }

  Target& TargetFor(int w, int h) {
    auto it = targets.find({w, h});
    if (it != targets.end()) return it->second;
    Target t;
    glGenFramebuffers(1, &t.fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, t.fbo);
    glGenTextures(kOutputs, t.tex);
    for (int i = 0; i < kOutputs; ++i) {
      glBindTexture(GL_TEXTURE_2D, t.tex[i]);
      const GLenum fmt = kFormats[i].internal == GL_RGBA8UI ? GL_RGBA_INTEGER : (i == 2 ? GL_RED : (i == 4 ? GL_RG : GL_RGBA));
      const GLenum type = (i == 2 || i == 4) ? GL_FLOAT : GL_UNSIGNED_BYTE;
      glTexImage2D(GL_TEXTURE_2D, 0, static_cast<GLint>(kFormats[i].internal), w, h, 0, fmt, type, nullptr);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
      glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0 + static_cast<GLenum>(i), GL_TEXTURE_2D, t.tex[i], 0);
    }
    glGenRenderbuffers(1, &t.depth);
    glBindRenderbuffer(GL_RENDERBUFFER, t.depth);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, w, h);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, t.depth);
    const GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
    if (status != GL_FRAMEBUFFER_COMPLETE) {
      throw std::runtime_error("render: framebuffer " + std::to_string(w) + "x" + std::to_string(h) + " incomplete (0x" +
                               std::to_string(status) + ")");
    }
    return targets.emplace(std::make_pair(w, h), t).first->second;
  }

  void SetLighting(gl::Program& p, const Lighting& l, const Camera& cam) {
    p.Set("u_sun_dir", l.sun_direction);
    p.Set("u_sun_color", l.sun_color);
    p.Set("u_ambient", l.ambient);
    p.Set("u_sky_zenith", l.sky_zenith);
    p.Set("u_sky_horizon", l.sky_horizon);
    p.Set("u_fog_color", l.fog_color);
    p.Set("u_fog_extinction", l.fog_extinction);
    p.Set("u_fog_start", l.fog_start);
    p.Set("u_fog_falloff", l.fog_height_falloff);
    p.Set("u_rain", l.rain);
    p.Set("u_rain_slant", l.rain_slant);
    p.Set("u_clouds", l.clouds);
    p.Set("u_exposure", static_cast<float>(cam.exposure * std::exp2(cam.exposure_compensation)));
    p.Set("u_gamma", static_cast<float>(cam.gamma > 0.1 ? cam.gamma : 2.2));
    p.Set("u_vignette", static_cast<float>(cam.lens_circle_multiplier));
    p.Set("u_vignette_falloff", static_cast<float>(cam.lens_circle_falloff));
    p.Set("u_size", Eigen::Vector2f(static_cast<float>(cam.width), static_cast<float>(cam.height)));
    p.SetUint("u_seed", static_cast<unsigned>(cam.noise_seed ^ (cam.noise_seed >> 32)));
    p.SetInt("u_post", cam.post_process ? 1 : 0);
    p.Set("u_camera", cam.pose.position.cast<float>().eval());
  }

  // The sun's shadow map around `centre` (snapped to kShadowSnap); returns the matrix from
  // world to shadow clip.
  std::optional<Eigen::Matrix4f> DrawShadows(const Lighting& l, const WorldView& world, const Vec3& centre) {
    if (l.sun_color.maxCoeff() <= 0.01f || l.sun_direction.z() <= 0.02f) return std::nullopt;
    const Eigen::Vector3f dir = l.sun_direction;
    const Eigen::Vector3f c = (centre / kShadowSnap).array().round().matrix().cast<float>() * static_cast<float>(kShadowSnap);
    const Eigen::Vector3f eye = c + dir * 300.0f;
    Eigen::Vector3f up = std::abs(dir.z()) > 0.95f ? Eigen::Vector3f::UnitX() : Eigen::Vector3f::UnitZ();
    const Eigen::Vector3f f = (c - eye).normalized(), s = f.cross(up).normalized(), u = s.cross(f);
    Eigen::Matrix4f view = Eigen::Matrix4f::Identity();
    view.row(0).head<3>() = s;
    view.row(1).head<3>() = u;
    view.row(2).head<3>() = -f;
    view(0, 3) = -s.dot(eye);
    view(1, 3) = -u.dot(eye);
    view(2, 3) = f.dot(eye);
    const float e = static_cast<float>(kShadowExtent), n = 1.0f, fa = 700.0f;
    Eigen::Matrix4f proj = Eigen::Matrix4f::Identity();
    proj(0, 0) = 1 / e;
    proj(1, 1) = 1 / e;
    proj(2, 2) = -2 / (fa - n);
    proj(2, 3) = -(fa + n) / (fa - n);
    const Eigen::Matrix4f vp = proj * view;
    const Frustum fr(vp);
    glViewport(0, 0, kShadowSize, kShadowSize);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_TRUE);
    glDisable(GL_CULL_FACE);
    shadow.Use();
    shadow.Set("u_light_view_proj", vp);
    shadow.Set("u_model", Eigen::Matrix4f::Identity().eval());
    auto draw_town = [&] {
      glClear(GL_DEPTH_BUFFER_BIT);
      stats.shadow_triangles += statics.Draw(fr, c, true, false, &stats.draw_calls);
    };
    if (tuning.static_shadow_cache) {
      // The town's depth is drawn when the box or the sun moved; each frame starts from a copy.
      if (!static_shadow.valid || static_shadow.centre != c || static_shadow.sun != dir) {
        glBindFramebuffer(GL_FRAMEBUFFER, static_shadow_fbo);
        draw_town();
        static_shadow = {true, c, dir};
      }
      glBindFramebuffer(GL_READ_FRAMEBUFFER, static_shadow_fbo);
      glBindFramebuffer(GL_DRAW_FRAMEBUFFER, shadow_fbo);
      glBlitFramebuffer(0, 0, kShadowSize, kShadowSize, 0, 0, kShadowSize, kShadowSize, GL_DEPTH_BUFFER_BIT, GL_NEAREST);
      glBindFramebuffer(GL_FRAMEBUFFER, shadow_fbo);
    } else {
      glBindFramebuffer(GL_FRAMEBUFFER, shadow_fbo);
      draw_town();
    }
    glBindVertexArray(model_vao);
    for (const ActorDraw& a : world.actors) {
      auto it = models.find(a.model);
      if (it == models.end()) continue;
      const Model& m = it->second.model;
      if (!fr.Visible(a.pose.position.cast<float>(), static_cast<float>(m.half_extents.norm()))) continue;
      const Eigen::Matrix4f model = ModelMatrix(a.pose);
      shadow.Set("u_model", model);
      const GLsizei body = static_cast<GLsizei>(m.rotors.empty() ? m.vertices.size() : m.rotors.front().first);
      glDrawArrays(GL_TRIANGLES, it->second.first, body);
      stats.shadow_triangles += static_cast<std::uint64_t>(body) / 3;
      ++stats.draw_calls;
      // Rotor blades cast their shadows at the angle they are drawn.
      for (std::size_t r = 0; r < m.rotors.size(); ++r) {
        const auto& rotor = m.rotors[r];
        shadow.Set("u_model", (model * RotorMatrix(rotor.hub, RotorAngle(a, m, r))).eval());
        glDrawArrays(GL_TRIANGLES, it->second.first + static_cast<GLint>(rotor.first), static_cast<GLsizei>(rotor.count));
        stats.shadow_triangles += rotor.count / 3;
        ++stats.draw_calls;
      }
    }
    return vp;
  }

  void SetDrawBuffers(std::uint32_t outputs) {
    GLenum bufs[kOutputs];
    for (int i = 0; i < kOutputs; ++i) {
      bufs[i] = (outputs & kFormats[i].bit) ? GL_COLOR_ATTACHMENT0 + static_cast<GLenum>(i) : GL_NONE;
    }
    glDrawBuffers(kOutputs, bufs);
  }

  void DrawCamera(const Camera& cam, const WorldView& world, const Lighting& l, const std::optional<Eigen::Matrix4f>& shadow_vp) {
    Target& t = TargetFor(cam.width, cam.height);
    glBindFramebuffer(GL_FRAMEBUFFER, t.fbo);
    glViewport(0, 0, cam.width, cam.height);
    if (cam.lines_only) {
      // CARLA's CosmosControlSensor shows only the line batchers, unlit, on black.
      SetDrawBuffers(cam.outputs);
      glDepthMask(GL_TRUE);
      glClearColor(0, 0, 0, 1);
      glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
      DebugDrawList lines = world.cosmos;
      lines.lines.insert(lines.lines.end(), world.debug.lines.begin(), world.debug.lines.end());
      lines.points.insert(lines.points.end(), world.debug.points.begin(), world.debug.points.end());
      if (cam.outputs & kOutColor) DrawDebug(cam, lines);
      return;
    }
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LEQUAL);
    glDepthMask(GL_TRUE);
    glClear(GL_DEPTH_BUFFER_BIT);
    const std::uint32_t outputs = OutputFeatures(cam.outputs);
    if (!(cam.outputs & kOutColor)) {
      SetDrawBuffers(cam.outputs);
      DrawPass(cam, world, l, shadow_vp, Programs(outputs), true, !ClearToSky(cam.outputs));
    } else if (tuning.depth_prepass) {
      // Depth and the cheap outputs first; then the colour pass, depth test only, shades
      // each visible fragment once (llvmpipe tests depth before running the shader).
      SetDrawBuffers(cam.outputs & ~kOutColor);
      DrawPass(cam, world, l, shadow_vp, Programs(outputs), true, !ClearToSky(cam.outputs & ~kOutColor));
      SetDrawBuffers(kOutColor);
      glDepthMask(GL_FALSE);
      DrawPass(cam, world, l, shadow_vp, Programs(ColourFeatures(cam, l, shadow_vp.has_value())), false);
      glDepthMask(GL_TRUE);
    } else {
      SetDrawBuffers(cam.outputs);
      DrawPass(cam, world, l, shadow_vp, Programs(ColourFeatures(cam, l, shadow_vp.has_value()) | outputs), true);
    }
    if ((cam.outputs & kOutColor) && !world.debug.empty()) DrawDebug(cam, world.debug);
  }

  // world.debug shapes over the colour output, hidden where the scene is nearer.
  void DrawDebug(const Camera& cam, const DebugDrawList& list) {
    const std::vector<DebugVertex> v = DebugTriangles(list, cam);
    if (v.empty()) return;
    SetDrawBuffers(kOutColor);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LEQUAL);
    glDepthMask(GL_FALSE);
    glDisable(GL_CULL_FACE);
    debug.Use();
    debug.Set("u_view_proj", (ProjectionMatrix(cam) * ViewMatrix(cam.pose)).eval());
    glBindVertexArray(debug_vao);
    glBindBuffer(GL_ARRAY_BUFFER, debug_vbo);
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(v.size() * sizeof(DebugVertex)), v.data(), GL_STREAM_DRAW);
    glDrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(v.size()));
    ++stats.draw_calls;
    glBindVertexArray(0);
    glDepthMask(GL_TRUE);
    glEnable(GL_CULL_FACE);
  }

  // For a pass without colour and flow (whose sky values are constants): clears the bound
  // draw buffers to what the sky shader writes (labels: class Sky; depth: the far plane;
  // normals: 0), so the pass need not draw the sky, a full-screen triangle. True if done.
  bool ClearToSky(std::uint32_t outputs) const {
    if (!tuning.sky_by_clear || (outputs & (kOutColor | kOutFlow))) return false;
    const GLuint sky_label[4] = {11u, 0u, 0u, 0u};
    const GLfloat far_depth[4] = {static_cast<GLfloat>(kFarPlane), 0, 0, 0}, zero[4] = {0, 0, 0, 0};
    if (outputs & kOutLabels) glClearBufferuiv(GL_COLOR, 1, sky_label);
    if (outputs & kOutDepth) glClearBufferfv(GL_COLOR, 2, far_depth);
    if (outputs & kOutNormals) glClearBufferfv(GL_COLOR, 3, zero);
    return true;
  }

  // Draws the town, the actors and the sky with one program variant into the bound target.
  // count: this pass's triangles go into the stats (one pass per camera counts); draw_sky:
  // false where ClearToSky already wrote the sky.
  void DrawPass(const Camera& cam, const WorldView& world, const Lighting& l, const std::optional<Eigen::Matrix4f>& shadow_vp,
                std::pair<gl::Program, gl::Program>& variant, bool count, bool draw_sky = true) {
    const Eigen::Matrix4f proj = ProjectionMatrix(cam), view = ViewMatrix(cam.pose);
    const Pose prev_pose = cam.previous_pose.value_or(cam.pose);
    const Eigen::Matrix4f vp = proj * view, prev_vp = proj * ViewMatrix(prev_pose);
    // Rows flipped by the projection: front faces wind clockwise on screen.
    glEnable(GL_CULL_FACE);
    glCullFace(GL_BACK);
    glFrontFace(GL_CW);
    gl::Program& scene = variant.first;
    gl::Program& sky = variant.second;
    scene_ptr = &scene;
    scene.Use();
    SetLighting(scene, l, cam);
    scene.Set("u_view_proj", vp);
    scene.Set("u_prev_view_proj", prev_vp);
    scene.Set("u_view", view);
    scene.Set("u_wetness", l.wetness);
    scene.Set("u_puddles", l.puddles);
    if (shadow_vp) {
      glActiveTexture(GL_TEXTURE0);
      glBindTexture(GL_TEXTURE_2D, shadow_tex);
      scene.SetInt("u_shadow_map", 0);
      scene.Set("u_shadow_matrix", *shadow_vp);
    }
    glActiveTexture(GL_TEXTURE1);
    glBindTexture(GL_TEXTURE_2D, noise_tex);
    glActiveTexture(GL_TEXTURE0);
    scene.SetInt("u_noise", 1);
    SetNightLights(cam, world, l);
    scene.Set("u_model", Eigen::Matrix4f::Identity().eval());
    scene.Set("u_prev_model", Eigen::Matrix4f::Identity().eval());
    scene.SetUint("u_instance", 0);
    scene.SetInt("u_lights", 0);
    scene.SetInt("u_light_state", 3);
    const Frustum fr(vp);
    const Eigen::Vector3f eye = cam.pose.position.cast<float>();
    const std::uint64_t before = stats.triangles;
    stats.triangles += statics.Draw(fr, eye, false, tuning.front_to_back, &stats.draw_calls);
    DrawActors(world, fr, &cam);
    if (!count) stats.triangles = before;
    if (!draw_sky) return;
    // Sky where nothing was drawn.
    glDisable(GL_CULL_FACE);
    sky.Use();
    SetLighting(sky, l, cam);
    sky.SetInt("u_noise", 1);
    Eigen::Matrix4f view_rot = view, prev_rot = ViewMatrix(prev_pose);
    view_rot.topRightCorner<3, 1>().setZero();
    prev_rot.topRightCorner<3, 1>().setZero();
    sky.Set("u_inv_view_proj_rot", (proj * view_rot).inverse().eval());
    sky.Set("u_prev_view_proj_rot", (proj * prev_rot).eval());
    glBindVertexArray(sky_vao);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    ++stats.draw_calls;
  }

  void SetNightLights(const Camera& cam, const WorldView& world, const Lighting& l) {
    gl::Program& scene = *scene_ptr;
    int lamps = 0, spots = 0;
    if (l.night) {
      // The nearest street lamps and vehicle headlights light the scene.
      std::vector<std::pair<double, Vec3>> near;
      for (const Vec3& p : statics.lamps) {
        const double d = (p - cam.pose.position).squaredNorm();
        if (d < 120.0 * 120.0) near.emplace_back(d, p);
      }
      std::sort(near.begin(), near.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
      for (; lamps < 16 && lamps < static_cast<int>(near.size()); ++lamps) {
        const std::string n = "u_lamps[" + std::to_string(lamps) + "]";
        scene.Set(n.c_str(), near[static_cast<std::size_t>(lamps)].second.cast<float>().eval());
      }
      std::vector<std::pair<double, const ActorDraw*>> cars;
      for (const ActorDraw& a : world.actors) {
        if (!(a.light_state & (light::kLowBeam | light::kHighBeam))) continue;
        cars.emplace_back((a.pose.position - cam.pose.position).squaredNorm(), &a);
      }
      std::sort(cars.begin(), cars.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
      for (; spots < 16 && spots < static_cast<int>(cars.size()); ++spots) {
        const ActorDraw& a = *cars[static_cast<std::size_t>(spots)].second;
        auto it = models.find(a.model);
        const double hx = it != models.end() ? it->second.model.half_extents.x() : 2.0;
        const Vec3 pos = a.pose.Apply(Vec3(hx + 0.1, 0, 0));
        const Vec3 dir = (a.pose.orientation * Vec3(1, 0, -0.12)).normalized();
        const std::string i = std::to_string(spots);
        scene.Set(("u_spot_pos[" + i + "]").c_str(), pos.cast<float>().eval());
        scene.Set(("u_spot_dir[" + i + "]").c_str(), dir.cast<float>().eval());
      }
    }
    scene.SetInt("u_lamp_count", lamps);
    scene.SetInt("u_spot_count", spots);
  }

  // cam: the camera of the pass; where its flow only feeds its motion blur, actors smaller
  // on screen than motion_blur_min_object_screen_size get no motion of their own.
  void DrawActors(const WorldView& world, const Frustum& fr, const Camera* cam) {
    gl::Program& scene = *scene_ptr;
    const bool blur_only = cam && blur_only_flow;
    glBindVertexArray(model_vao);
    for (const ActorDraw& a : world.actors) {
      auto it = models.find(a.model);
      if (it == models.end()) throw std::runtime_error("render: actor " + std::to_string(a.id) + " uses unknown model '" + a.model + "'");
      const Model& m = it->second.model;
      if (!fr.Visible(a.pose.position.cast<float>(), static_cast<float>(m.half_extents.norm()))) continue;
      if (a.cull_faces) glEnable(GL_CULL_FACE);
      else glDisable(GL_CULL_FACE);
      const Eigen::Matrix4f model = ModelMatrix(a.pose);
      Eigen::Matrix4f prev = ModelMatrix(a.previous_pose.value_or(a.pose));
      if (blur_only) {
        const double depth = (a.pose.position - cam->pose.position).dot(cam->pose.orientation * Vec3::UnitX());
        const double width = depth > kNearPlane ? 2 * m.half_extents.norm() * cam->Focal() / depth : 1e30;  // px
        if (width < cam->motion_blur_min_object_screen_size * cam->width) prev = model;
      }
      scene.Set("u_model", model);
      scene.Set("u_prev_model", prev);
      scene.Set("u_paint", Eigen::Vector3f(a.paint[0] / 255.0f, a.paint[1] / 255.0f, a.paint[2] / 255.0f));
      scene.SetUint("u_instance", a.id);
      scene.SetInt("u_lights", static_cast<int>(a.light_state & 0x7fffffffu));
      const GLsizei body = static_cast<GLsizei>(m.rotors.empty() ? m.vertices.size() : m.rotors.front().first);
      glDrawArrays(GL_TRIANGLES, it->second.first, body);
      stats.triangles += static_cast<std::uint64_t>(body) / 3;
      ++stats.draw_calls;
      for (std::size_t r = 0; r < m.rotors.size(); ++r) {
        const auto& rotor = m.rotors[r];
        scene.Set("u_model", (model * RotorMatrix(rotor.hub, RotorAngle(a, m, r))).eval());
        scene.Set("u_prev_model", (prev * RotorMatrix(rotor.hub, RotorAngle(a, m, r))).eval());
        glDrawArrays(GL_TRIANGLES, it->second.first + static_cast<GLint>(rotor.first), static_cast<GLsizei>(rotor.count));
        stats.triangles += rotor.count / 3;
        ++stats.draw_calls;
      }
    }
    glEnable(GL_CULL_FACE);
    auto tl = models.find("__traffic_light_lamps");
    scene.Set("u_prev_model", Eigen::Matrix4f::Identity().eval());
    for (const TrafficLightDraw& t : world.traffic_lights) {
      Pose p = t.pose;
      p.position += p.orientation * Vec3(0, 0, t.height);
      if (!fr.Visible(p.position.cast<float>(), 1.0f)) continue;
      const Eigen::Matrix4f m = ModelMatrix(p);
      scene.Set("u_model", m);
      scene.Set("u_prev_model", m);
      scene.SetUint("u_instance", t.id);
      scene.SetInt("u_light_state", t.state);
      glDrawArrays(GL_TRIANGLES, tl->second.first, static_cast<GLsizei>(tl->second.model.vertices.size()));
      ++stats.draw_calls;
    }
    scene.SetInt("u_light_state", 3);
  }

  const std::vector<std::int32_t>& Remap(const Camera& cam) {
    char key[256];
    std::snprintf(key, sizeof key, "%dx%d %.17g %.17g %.17g %.17g %.17g", cam.width, cam.height, cam.lens_circle_multiplier, cam.lens_k,
                  cam.lens_kcube, cam.lens_x_size, cam.lens_y_size);
    auto [it, fresh] = remaps.try_emplace(key);
    if (!fresh) return it->second;
    if (remaps.size() > 16) {  // lenses that change every frame: keep memory bounded
      remaps.clear();
      it = remaps.try_emplace(key).first;
    }
    auto& table = it->second;
    table.resize(static_cast<std::size_t>(cam.width) * cam.height);
    for (int v = 0; v < cam.height; ++v) {
      for (int u = 0; u < cam.width; ++u) {
        const Eigen::Vector2d s = DistortedSource(cam, u + 0.5, v + 0.5);
        const int su = static_cast<int>(std::floor(s.x())), sv = static_cast<int>(std::floor(s.y()));
        table[static_cast<std::size_t>(v) * cam.width + u] =
            su < 0 || sv < 0 || su >= cam.width || sv >= cam.height ? -1 : sv * cam.width + su;
      }
    }
    return table;
  }

  // Replaces the mapped outputs by their distorted images (nearest pixel; outside: zero).
  void Distort(const Camera& cam, const void* mapped[kOutputs]) {
    const auto& table = Remap(cam);
    for (int i = 0; i < kOutputs; ++i) {
      if (!mapped[i]) continue;
      const std::size_t b = static_cast<std::size_t>(kFormats[i].bytes);
      auto& out = lens_out[i];
      out.resize(table.size() * b);
      const auto* src = static_cast<const std::uint8_t*>(mapped[i]);
      for (std::size_t p = 0; p < table.size(); ++p) {
        if (table[p] < 0) std::memset(&out[p * b], 0, b);
        else std::memcpy(&out[p * b], src + static_cast<std::size_t>(table[p]) * b, b);
      }
      mapped[i] = out.data();
    }
  }

  void StartReadback(const Camera& cam, int slot) {
    for (int i = 0; i < kOutputs; ++i) {
      if (!(cam.outputs & kFormats[i].bit)) continue;
      Pbo& p = pbos[slot][i];
      const std::size_t size = static_cast<std::size_t>(cam.width) * cam.height * kFormats[i].bytes;
      if (!p.buffer) glGenBuffers(1, &p.buffer);
      glBindBuffer(GL_PIXEL_PACK_BUFFER, p.buffer);
      if (p.size < size) {
        glBufferData(GL_PIXEL_PACK_BUFFER, static_cast<GLsizeiptr>(size), nullptr, GL_STREAM_READ);
        p.size = size;
      }
      glReadBuffer(GL_COLOR_ATTACHMENT0 + static_cast<GLenum>(i));
      glReadPixels(0, 0, cam.width, cam.height, kFormats[i].format, kFormats[i].type, nullptr);
    }
    glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
    if (fences[slot]) glDeleteSync(fences[slot]);
    fences[slot] = glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0);
    glFlush();
  }

  // requested: the outputs the caller asked for (the pass may have drawn more).
  void Deliver(std::size_t index, const Camera& cam, std::uint32_t requested, int slot, const Sink& sink) {
    glClientWaitSync(fences[slot], GL_SYNC_FLUSH_COMMANDS_BIT, 10'000'000'000ull);
    CameraImages im;
    im.width = cam.width;
    im.height = cam.height;
    const void* mapped[kOutputs] = {};
    for (int i = 0; i < kOutputs; ++i) {
      if (!(cam.outputs & kFormats[i].bit)) continue;
      glBindBuffer(GL_PIXEL_PACK_BUFFER, pbos[slot][i].buffer);
      mapped[i] = glMapBufferRange(GL_PIXEL_PACK_BUFFER, 0,
                                   static_cast<GLsizeiptr>(static_cast<std::size_t>(cam.width) * cam.height * kFormats[i].bytes),
                                   GL_MAP_READ_BIT);
      if (!mapped[i]) throw std::runtime_error("render: mapping a read-back buffer failed");
    }
    if (cam.HasLensDistortion()) Distort(cam, mapped);
    if (cam.HasMotionBlur() && mapped[0] && mapped[4]) {
      ApplyMotionBlur(cam, static_cast<const std::uint8_t*>(mapped[0]), static_cast<const float*>(mapped[4]), cam.width, cam.height,
                      &blurred);
      mapped[0] = blurred.data();
    }
    im.color = static_cast<const std::uint8_t*>(mapped[0]);
    im.labels = static_cast<const std::uint8_t*>(mapped[1]);
    im.depth = static_cast<const float*>(mapped[2]);
    im.normals = static_cast<const std::uint8_t*>(mapped[3]);
    im.flow = (requested & kOutFlow) ? static_cast<const float*>(mapped[4]) : nullptr;
    sink(index, im);
    for (int i = 0; i < kOutputs; ++i) {
      if (!mapped[i]) continue;
      glBindBuffer(GL_PIXEL_PACK_BUFFER, pbos[slot][i].buffer);
      glUnmapBuffer(GL_PIXEL_PACK_BUFFER);
    }
    glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
  }
};

Renderer::Renderer(DevicePreference preference) : impl_(std::make_unique<Impl>(preference)) {}
Renderer::~Renderer() {
  impl_->context.MakeCurrent();  // release this renderer's objects, not another's
}

const DeviceInfo& Renderer::device() const { return impl_->context.device(); }

void Renderer::SetStaticScene(const std::vector<map::Mesh>& meshes, const std::vector<Vec3>& lamps, const StaticSceneOptions& options) {
  impl_->context.MakeCurrent();
  impl_->statics.Build(meshes, lamps, options);
  impl_->static_shadow.valid = false;
  impl_->stats.static_triangles = impl_->statics.triangles;
}

void Renderer::AddModel(const std::string& key, const Model& model) { impl_->AddModel(key, model); }
bool Renderer::HasModel(const std::string& key) const { return impl_->models.count(key) > 0; }
const Model* Renderer::FindModel(const std::string& key) const {
  auto it = impl_->models.find(key);
  return it == impl_->models.end() ? nullptr : &it->second.model;
}
const RenderStats& Renderer::stats() const { return impl_->stats; }
void Renderer::SetTuning(const RenderTuning& tuning) { impl_->tuning = tuning; }
const RenderTuning& Renderer::tuning() const { return impl_->tuning; }

void Renderer::Render(const std::vector<Camera>& cameras, const WorldView& world, const Sink& sink) {
  if (std::any_of(cameras.begin(), cameras.end(), [](const Camera& c) { return c.wide_angle.enabled; })) {
    // Wide-angle lens cameras: six cube faces each, composed after (wide_angle_cube.h).
    std::vector<Camera> flat;
    std::vector<std::pair<std::size_t, int>> origin;  // camera index, cube face (-1: the camera itself)
    for (std::size_t i = 0; i < cameras.size(); ++i) {
      const Camera& c = cameras[i];
      if (!c.wide_angle.enabled) {
        flat.push_back(c);
        origin.emplace_back(i, -1);
        continue;
      }
      if (!(c.fov_deg > 0 && c.fov_deg <= 360)) {
        throw std::invalid_argument("render: wide-angle fov " + std::to_string(c.fov_deg) + " out of (0, 360]");
      }
      for (int f = 0; f < 6; ++f) {
        flat.push_back(WideAngleFace(c, f));
        origin.emplace_back(i, f);
      }
    }
    std::vector<std::array<CameraFrame, 6>> faces(cameras.size());
    Render(flat, world, [&](std::size_t k, const CameraImages& im) {
      const auto [i, f] = origin[k];
      if (f < 0) sink(i, im);
      else faces[i][static_cast<std::size_t>(f)] = CameraFrame::Copy(im);
    });
    for (std::size_t i = 0; i < cameras.size(); ++i) {
      if (!cameras[i].wide_angle.enabled) continue;
      const CameraFrame out = ComposeWideAngle(cameras[i], faces[i]);
      CameraImages im;
      im.width = out.width;
      im.height = out.height;
      im.color = out.color.empty() ? nullptr : out.color.data();
      im.labels = out.labels.empty() ? nullptr : out.labels.data();
      im.depth = out.depth.empty() ? nullptr : out.depth.data();
      im.normals = out.normals.empty() ? nullptr : out.normals.data();
      sink(i, im);
    }
    return;
  }
  for (const Camera& c : cameras) {
    if (c.width < 1 || c.height < 1 || c.width > 8192 || c.height > 8192) {
      throw std::invalid_argument("render: image size " + std::to_string(c.width) + "x" + std::to_string(c.height) + " out of range");
    }
    if (!(c.fov_deg > 0 && c.fov_deg < 180)) throw std::invalid_argument("render: fov " + std::to_string(c.fov_deg) + " out of (0, 180)");
  }
  Impl& s = *impl_;
  s.context.MakeCurrent();  // another renderer in this process may have made its own current
  s.stats.triangles = 0;
  s.stats.shadow_triangles = 0;
  s.stats.draw_calls = 0;
  s.UploadModels();
  const Lighting l = ComputeLighting(world.weather);
  if (cameras.empty()) return;
  const bool colour = std::any_of(cameras.begin(), cameras.end(), [](const Camera& c) { return (c.outputs & kOutColor) != 0; });
  const auto shadow_vp = colour ? s.DrawShadows(l, world, cameras.front().pose.position) : std::nullopt;
  // A camera with motion blur draws and reads back its flow too (the blur's input).
  std::vector<Camera> passes = cameras;
  for (Camera& c : passes) {
    if (c.HasMotionBlur()) c.outputs |= kOutFlow;
  }
  for (std::size_t i = 0; i < passes.size(); ++i) {
    const int slot = static_cast<int>(i % kSlots);
    s.blur_only_flow = passes[i].HasMotionBlur() && !(cameras[i].outputs & kOutFlow);
    s.DrawCamera(passes[i], world, l, shadow_vp);
    s.StartReadback(passes[i], slot);
    if (i >= 1) s.Deliver(i - 1, passes[i - 1], cameras[i - 1].outputs, static_cast<int>((i - 1) % kSlots), sink);
  }
  s.Deliver(passes.size() - 1, passes.back(), cameras.back().outputs, static_cast<int>((passes.size() - 1) % kSlots), sink);
}

std::vector<CameraFrame> Renderer::RenderFrames(const std::vector<Camera>& cameras, const WorldView& world) {
  std::vector<CameraFrame> out(cameras.size());
  Render(cameras, world, [&](std::size_t i, const CameraImages& im) { out[i] = CameraFrame::Copy(im); });
  return out;
}

}  // namespace lockstep::render
