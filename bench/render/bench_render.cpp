// bench/run render [--frames N] [--samples DIR]: rendering throughput in Town01 with 50
// vehicles (one 800x600 camera with RGB, depth and semantic outputs; 8 cameras at
// 1280x720) and the time to deliver a 720p frame to a client process on this machine.
// Prints JSON lines; the last is the summary.
#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>

#include "lockstep/map/scene_mesh.h"
#include "lockstep/render/camera_config.h"
#include "lockstep/render/images.h"
#include "town.h"

namespace lockstep::render::bench {

int Samples(const std::string& dir);
struct Transport {
  double median_ms = 0, p99_ms = 0;
  int received = 0;
};
Transport MeasureTransport(const char* self, int width, int height, int frames, bool image_qos);
int TransportReader(int argc, char** argv);

namespace {

using Clock = std::chrono::steady_clock;

struct Result {
  double fps = 0;
  std::uint64_t triangles = 0;         // per set, in the cameras' views
  std::uint64_t shadow_triangles = 0;  // per set, drawn into the shadow map
  double cpu_ms = 0;  // CPU time of this process (all threads, llvmpipe's included) per set
};

double CpuSeconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + (u.ru_utime.tv_usec + u.ru_stime.tv_usec) * 1e-6;
}

double LoadAverage() {
  double l[1] = {0};
  return getloadavg(l, 1) == 1 ? l[0] : -1;
}

// Renders `frames` sets of `cams` (after a warm-up), encoding each output as the service does.
Result Run(Renderer& r, Town& town, std::vector<Camera> cams, int frames, int warmup = 3) {
  std::vector<std::uint8_t> rgb, depth, sem;
  std::uint64_t tris = 0, shadow_tris = 0;
  auto one = [&](int f) {
    // The traffic moves a little every frame, as it would in a run.
    for (auto& a : town.world.actors) {
      a.previous_pose = a.pose;
      a.pose.position += a.pose.orientation * Vec3(0.4, 0, 0);
    }
    for (auto& c : cams) {
      c.previous_pose = c.pose;
      c.pose.position += c.pose.orientation * Vec3(0.4, 0, 0);
    }
    r.Render(cams, town.world, [&](std::size_t i, const CameraImages& im) {
      const std::size_t n = static_cast<std::size_t>(im.width) * im.height * 4;
      rgb.resize(n);
      depth.resize(n);
      sem.resize(n);
      if (im.color) EncodeImage(ImageKind::kRgb, cams[i], im, rgb.data());
      if (im.depth) EncodeImage(ImageKind::kDepth, cams[i], im, depth.data());
      if (im.labels) EncodeImage(ImageKind::kSemantic, cams[i], im, sem.data());
    });
    if (f >= 0) tris += r.stats().triangles;
    if (f >= 0) shadow_tris += r.stats().shadow_triangles;
  };
  for (int i = 0; i < warmup; ++i) one(-1);
  const auto t0 = Clock::now();
  const double c0 = CpuSeconds();
  for (int i = 0; i < frames; ++i) one(i);
  const double s = std::chrono::duration<double>(Clock::now() - t0).count();
  const auto n = static_cast<std::uint64_t>(frames);
  return Result{frames / s, tris / n, shadow_tris / n, (CpuSeconds() - c0) * 1e3 / frames};
}

// The same cameras with the renderer's speed-ups off ("before") and on ("after"), in
// alternating rounds so both see the same machine load.
std::pair<Result, Result> Compare(Renderer& r, Town& town, const std::vector<Camera>& cams, int frames) {
  const int rounds = 4, per = std::max(1, frames / rounds);
  Result sum[2];
  double seconds[2] = {0, 0};
  for (int k = 0; k < rounds; ++k) {
    for (int on = 0; on < 2; ++on) {
      r.SetTuning(on ? RenderTuning{} : RenderTuning{false, false, false, false, false});
      const Result x = Run(r, town, cams, per, 1);
      seconds[on] += per / x.fps;
      sum[on].triangles += x.triangles;
      sum[on].shadow_triangles += x.shadow_triangles;
      sum[on].cpu_ms += x.cpu_ms;
    }
  }
  r.SetTuning(RenderTuning{});
  for (int on = 0; on < 2; ++on) {
    sum[on].fps = rounds * per / seconds[on];
    sum[on].triangles /= rounds;
    sum[on].shadow_triangles /= rounds;
    sum[on].cpu_ms /= rounds;
  }
  return {sum[0], sum[1]};
}

void PrintCompare(const char* name, const std::pair<Result, Result>& c, double load) {
  std::printf("{\"bench\":\"render\",\"case\":\"%s\",\"fps_before\":%.2f,\"fps_after\":%.2f,\"fps_ratio\":%.2f,"
              "\"cpu_ms_before\":%.1f,\"cpu_ms_after\":%.1f,\"cpu_ratio\":%.2f,\"shadow_triangles_before\":%llu,"
              "\"shadow_triangles_after\":%llu,\"load_average\":%.1f}\n",
              name, c.first.fps, c.second.fps, c.second.fps / c.first.fps, c.first.cpu_ms, c.second.cpu_ms,
              c.first.cpu_ms / c.second.cpu_ms, static_cast<unsigned long long>(c.first.shadow_triangles),
              static_cast<unsigned long long>(c.second.shadow_triangles), load);
  std::fflush(stdout);
}

}  // namespace

int Main(int argc, char** argv) {
  int frames = 40;
  std::string only;       // --case 1cam|8cam|transport: run one case (for profiling)
  bool ablation = false;  // --ablation: the 1-camera case with each speed-up off alone
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--transport-reader")) return TransportReader(argc, argv);
    if (!std::strcmp(argv[i], "--samples") && i + 1 < argc) return Samples(argv[i + 1]);
    if (!std::strcmp(argv[i], "--frames") && i + 1 < argc) frames = std::max(1, std::atoi(argv[++i]));
    if (!std::strcmp(argv[i], "--case") && i + 1 < argc) only = argv[++i];
    if (!std::strcmp(argv[i], "--ablation")) ablation = true;
  }
  auto run = [&](const char* name) { return only.empty() || only == name; };
  Renderer r;
  const auto t0 = Clock::now();
  Town town = LoadTown(r, 50);
  std::printf("{\"bench\":\"render\",\"case\":\"setup\",\"device\":\"%s\",\"platform\":\"%s\",\"gl_renderer\":\"%s\",\"static_triangles\":%llu,"
              "\"actors\":%zu,\"load_s\":%.2f,\"load_average\":%.1f}\n",
              r.device().name.c_str(), r.device().platform.c_str(), r.device().gl_renderer.c_str(),
              static_cast<unsigned long long>(r.stats().static_triangles), town.world.actors.size(),
              std::chrono::duration<double>(Clock::now() - t0).count(), LoadAverage());
  std::fflush(stdout);
  const std::uint32_t all = kOutColor | kOutDepth | kOutLabels;
  Camera one;
  one.width = 800;
  one.height = 600;
  one.fov_deg = 90;
  one.outputs = all;
  one.pose = DashCamera(town);
  Result r1;
  if (run("1cam")) {
    PrintCompare("1cam_800x600_before_after", Compare(r, town, {one}, frames), LoadAverage());
    if (ablation) {
      const char* names[] = {"output_variants", "depth_prepass", "front_to_back", "static_shadow_cache", "sky_by_clear"};
      for (int k = 0; k < 5; ++k) {
        RenderTuning t;
        bool* flags[] = {&t.output_variants, &t.depth_prepass, &t.front_to_back, &t.static_shadow_cache, &t.sky_by_clear};
        *flags[k] = false;
        r.SetTuning(t);
        const Result off = Run(r, town, {one}, frames / 2, 1);
        r.SetTuning(RenderTuning{});
        const Result on = Run(r, town, {one}, frames / 2, 1);
        std::printf("{\"bench\":\"render\",\"case\":\"1cam_without_%s\",\"fps_without\":%.2f,\"fps_with\":%.2f,"
                    "\"cpu_ms_without\":%.1f,\"cpu_ms_with\":%.1f,\"load_average\":%.1f}\n",
                    names[k], off.fps, on.fps, off.cpu_ms, on.cpu_ms, LoadAverage());
        std::fflush(stdout);
      }
    }
    r1 = Run(r, town, {one}, frames);
    // cpu_ms: CPU time per frame over all threads; on an idle machine llvmpipe spreads it
    // over the cores, so wall time is between cpu_ms / cores and cpu_ms.
    std::printf("{\"bench\":\"render\",\"case\":\"1cam_800x600_rgb_depth_semantic\",\"fps\":%.1f,\"cpu_ms_per_frame\":%.1f,"
                "\"triangles\":%llu,\"shadow_triangles\":%llu,\"draw_calls\":%llu,\"load_average\":%.1f}\n",
                r1.fps, r1.cpu_ms, static_cast<unsigned long long>(r1.triangles), static_cast<unsigned long long>(r1.shadow_triangles),
                static_cast<unsigned long long>(r.stats().draw_calls), LoadAverage());
    std::fflush(stdout);
    // The same camera with CARLA's default colour attributes (sensor.camera.rgb): motion
    // blur on (intensity 0.45, at most 0.35 % of the width), which adds the flow output.
    Camera carla = one;
    const CameraSettings defaults = ParseCamera("sensor.camera.rgb", {});
    carla.motion_blur_intensity = defaults.camera.motion_blur_intensity;
    carla.motion_blur_max_distortion = defaults.camera.motion_blur_max_distortion;
    carla.motion_blur_min_object_screen_size = defaults.camera.motion_blur_min_object_screen_size;
    const Result rb = Run(r, town, {carla}, frames);
    std::printf("{\"bench\":\"render\",\"case\":\"1cam_800x600_rgb_depth_semantic_motion_blur\",\"fps\":%.1f,\"cpu_ms_per_frame\":%.1f,"
                "\"load_average\":%.1f}\n",
                rb.fps, rb.cpu_ms, LoadAverage());
    std::fflush(stdout);
  }
  if (run("8cam")) {
    std::vector<Camera> eight;
    for (int k = 0; k < 8; ++k) {
      Camera c = one;
      c.width = 1280;
      c.height = 720;
      c.pose = DashCamera(town) * Pose{Vec3::Zero(), Quat(Eigen::AngleAxisd(k * M_PI / 4, Vec3::UnitZ()))};
      eight.push_back(c);
    }
    PrintCompare("8cam_1280x720_before_after", Compare(r, town, eight, std::max(4, frames / 5)), LoadAverage());
    const Result r8 = Run(r, town, eight, std::max(4, frames / 4));
    std::printf("{\"bench\":\"render\",\"case\":\"8cam_1280x720_rgb_depth_semantic\",\"sets_per_s\":%.2f,\"camera_fps\":%.1f,"
                "\"cpu_ms_per_set\":%.1f,\"triangles\":%llu,\"load_average\":%.1f}\n",
                r8.fps, r8.fps * 8, r8.cpu_ms, static_cast<unsigned long long>(r8.triangles), LoadAverage());
    std::fflush(stdout);
  }
  Transport fast;
  if (run("transport")) {
    const Transport copy = MeasureTransport(argv[0], 1280, 720, 100, false);
    std::printf("{\"bench\":\"render\",\"case\":\"transport_720p\",\"qos\":\"sensor (copying)\",\"median_ms\":%.3f,\"p99_ms\":%.3f,\"received\":%d}\n",
                copy.median_ms, copy.p99_ms, copy.received);
    std::fflush(stdout);
    fast = MeasureTransport(argv[0], 1280, 720, 100, true);
    std::printf("{\"bench\":\"render\",\"case\":\"transport_720p\",\"qos\":\"image (data-sharing)\",\"median_ms\":%.3f,\"p99_ms\":%.3f,\"received\":%d}\n",
                fast.median_ms, fast.p99_ms, fast.received);
  }
  std::printf("{\"bench\":\"render\",\"device\":\"%s\",\"width\":800,\"height\":600,\"cameras\":1,\"fps\":%.1f,\"triangles\":%llu,"
              "\"frame_transport_ms_720p\":%.3f}\n",
              r.device().name.c_str(), r1.fps, static_cast<unsigned long long>(r1.triangles), fast.median_ms);
  return 0;
}

}  // namespace lockstep::render::bench

int main(int argc, char** argv) {
  try {
    return lockstep::render::bench::Main(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_render: %s\n", e.what());
    return 1;
  }
}
