// bench/run render [--frames N] [--samples DIR]: rendering throughput in Town01 with 50
// vehicles (one 800x600 camera with RGB, depth and semantic outputs; 8 cameras at
// 1280x720) and the time to deliver a 720p frame to a client process on this machine.
// Prints JSON lines; the last is the summary.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>

#include "lockstep/map/scene_mesh.h"
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
  std::uint64_t triangles = 0;
};

// Renders `frames` sets of `cams` (after a warm-up), encoding each output as the service does.
Result Run(Renderer& r, Town& town, std::vector<Camera> cams, int frames) {
  std::vector<std::uint8_t> rgb, depth, sem;
  std::uint64_t tris = 0;
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
      EncodeImage(ImageKind::kRgb, cams[i], im, rgb.data());
      EncodeImage(ImageKind::kDepth, cams[i], im, depth.data());
      EncodeImage(ImageKind::kSemantic, cams[i], im, sem.data());
    });
    if (f >= 0) tris += r.stats().triangles;
  };
  for (int i = 0; i < 3; ++i) one(-1);
  const auto t0 = Clock::now();
  for (int i = 0; i < frames; ++i) one(i);
  const double s = std::chrono::duration<double>(Clock::now() - t0).count();
  return Result{frames / s, tris / static_cast<std::uint64_t>(frames)};
}

}  // namespace

int Main(int argc, char** argv) {
  int frames = 40;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--transport-reader")) return TransportReader(argc, argv);
    if (!std::strcmp(argv[i], "--samples") && i + 1 < argc) return Samples(argv[i + 1]);
    if (!std::strcmp(argv[i], "--frames") && i + 1 < argc) frames = std::max(1, std::atoi(argv[++i]));
  }
  Renderer r;
  const auto t0 = Clock::now();
  Town town = LoadTown(r, 50);
  std::printf("{\"bench\":\"render\",\"case\":\"setup\",\"device\":\"%s\",\"platform\":\"%s\",\"gl_renderer\":\"%s\",\"static_triangles\":%llu,"
              "\"actors\":%zu,\"load_s\":%.2f}\n",
              r.device().name.c_str(), r.device().platform.c_str(), r.device().gl_renderer.c_str(),
              static_cast<unsigned long long>(r.stats().static_triangles), town.world.actors.size(),
              std::chrono::duration<double>(Clock::now() - t0).count());
  std::fflush(stdout);
  const std::uint32_t all = kOutColor | kOutDepth | kOutLabels;
  Camera one;
  one.width = 800;
  one.height = 600;
  one.fov_deg = 90;
  one.outputs = all;
  one.pose = DashCamera(town);
  const Result r1 = Run(r, town, {one}, frames);
  std::printf("{\"bench\":\"render\",\"case\":\"1cam_800x600_rgb_depth_semantic\",\"fps\":%.1f,\"triangles\":%llu}\n", r1.fps,
              static_cast<unsigned long long>(r1.triangles));
  std::fflush(stdout);
  std::vector<Camera> eight;
  for (int k = 0; k < 8; ++k) {
    Camera c = one;
    c.width = 1280;
    c.height = 720;
    c.pose = DashCamera(town) * Pose{Vec3::Zero(), Quat(Eigen::AngleAxisd(k * M_PI / 4, Vec3::UnitZ()))};
    eight.push_back(c);
  }
  const Result r8 = Run(r, town, eight, std::max(4, frames / 4));
  std::printf("{\"bench\":\"render\",\"case\":\"8cam_1280x720_rgb_depth_semantic\",\"sets_per_s\":%.2f,\"camera_fps\":%.1f,\"triangles\":%llu}\n",
              r8.fps, r8.fps * 8, static_cast<unsigned long long>(r8.triangles));
  std::fflush(stdout);
  const Transport copy = MeasureTransport(argv[0], 1280, 720, 100, false);
  std::printf("{\"bench\":\"render\",\"case\":\"transport_720p\",\"qos\":\"sensor (copying)\",\"median_ms\":%.3f,\"p99_ms\":%.3f,\"received\":%d}\n",
              copy.median_ms, copy.p99_ms, copy.received);
  std::fflush(stdout);
  const Transport fast = MeasureTransport(argv[0], 1280, 720, 100, true);
  std::printf("{\"bench\":\"render\",\"case\":\"transport_720p\",\"qos\":\"image (data-sharing)\",\"median_ms\":%.3f,\"p99_ms\":%.3f,\"received\":%d}\n",
              fast.median_ms, fast.p99_ms, fast.received);
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
