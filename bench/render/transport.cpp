// Frame delivery between two processes on this machine: this process writes 720p
// images, a child (this program with --transport-reader) receives them and reports the
// latency from Write() to its callback (CLOCK_MONOTONIC is shared by all processes).
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "lockstep/runtime/messages.h"

namespace lockstep::render::bench {

struct Transport {
  double median_ms = 0, p99_ms = 0;
  int received = 0;
};

namespace {
const char* kProfile = "lockstep.participant.loopback";
const char* kTopic = "lockstep/bench/render_image";
double Now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }
constexpr int kWarmup = 20;
}  // namespace

int TransportReader(int argc, char** argv) {
  // --transport-reader DOMAIN FRAMES QOS
  if (argc < 5) return 2;
  const int domain = std::atoi(argv[2]), frames = std::atoi(argv[3]);
  const bool image_qos = std::string(argv[4]) == "image";
  auto bus = CreateDdsBus({domain, "", kProfile, "bench-render-reader"});
  std::mutex mu;
  std::condition_variable cv;
  std::vector<double> lat;
  int count = 0;
  Reader<msg::Image> reader(*bus, Topic<msg::Image>{kTopic, image_qos ? QosKind::kImage : QosKind::kSensor},
                            [&](const msg::Image& im, const SampleInfo&) {
                              const double l = Now() - im.stamp().sim_time();
                              std::lock_guard<std::mutex> lock(mu);
                              if (++count > kWarmup) lat.push_back(l * 1000);
                              cv.notify_all();
                            });
  std::printf("ready\n");
  std::fflush(stdout);
  {
    std::unique_lock<std::mutex> lock(mu);
    cv.wait_for(lock, std::chrono::seconds(60), [&] { return count >= kWarmup + frames; });
  }
  std::sort(lat.begin(), lat.end());
  const double med = lat.empty() ? 0 : lat[lat.size() / 2];
  const double p99 = lat.empty() ? 0 : lat[std::min(lat.size() - 1, lat.size() * 99 / 100)];
  std::printf("%d %.4f %.4f\n", static_cast<int>(lat.size()), med, p99);
  std::fflush(stdout);
  return 0;
}

Transport MeasureTransport(const char* self, int width, int height, int frames, bool image_qos) {
  const int domain = 150 + static_cast<int>(getpid() % 60);
  const std::string cmd = std::string(self) + " --transport-reader " + std::to_string(domain) + " " + std::to_string(frames) + " " +
                          (image_qos ? "image" : "sensor");
  FILE* child = popen(cmd.c_str(), "r");
  Transport t;
  if (!child) return t;
  char line[256];
  if (!std::fgets(line, sizeof line, child)) {  // "ready"
    pclose(child);
    return t;
  }
  auto bus = CreateDdsBus({domain, "", kProfile, "bench-render-writer"});
  Writer<msg::Image> writer(*bus, Topic<msg::Image>{kTopic, image_qos ? QosKind::kImage : QosKind::kSensor});
  for (int i = 0; i < 500 && writer.MatchedReaders() < 1; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // reader side of discovery too
  msg::Image img;
  img.width(static_cast<uint32_t>(width));
  img.height(static_cast<uint32_t>(height));
  img.step(static_cast<uint32_t>(width * 4));
  img.encoding(static_cast<uint32_t>(msg::ImageEncoding::IMAGE_BGRA8));
  std::vector<std::uint8_t> data(static_cast<std::size_t>(width) * height * 4);
  for (std::size_t i = 0; i < data.size(); ++i) data[i] = static_cast<std::uint8_t>(i * 31);
  img.data(data);
  // 50 Hz, like a fast camera: the reader is idle between frames.
  for (int i = 0; i < frames + kWarmup; ++i) {
    img.stamp().frame(static_cast<uint64_t>(i));
    img.stamp().sim_time(Now());
    writer.Write(img);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  if (std::fgets(line, sizeof line, child)) std::sscanf(line, "%d %lf %lf", &t.received, &t.median_ms, &t.p99_ms);
  pclose(child);
  return t;
}

}  // namespace lockstep::render::bench
