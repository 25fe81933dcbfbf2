#include "bridge.h"

#include <spdlog/spdlog.h>

#include <chrono>

#include "lockstep/runtime/frame_buffer.h"

namespace lockstep::ros2 {

namespace {

using EgoControl = carla_msgs::msg::dds_::CarlaEgoVehicleControl_;

// Image's bound (1920 x 1080 BGRA): a larger camera publishes LargeImage (docs/topics.md).
constexpr uint64_t kImageBoundBytes = 8294400;

uint32_t SensorOf(const msg::PointCloud& s) { return s.sensor(); }
uint32_t SensorOf(const msg::Imu& s) { return s.sensor(); }
uint32_t SensorOf(const msg::Gnss& s) { return s.sensor(); }
uint32_t SensorOf(const msg::CollisionEvent& s) { return s.sensor(); }

const char* KindName(SensorKind k) {
  switch (k) {
    case SensorKind::kCamera: return "image";
    case SensorKind::kLidar:
    case SensorKind::kSemanticLidar: return "point cloud";
    case SensorKind::kImu: return "IMU sample";
    case SensorKind::kGnss: return "GNSS fix";
    case SensorKind::kCollision: return "collision event";
    case SensorKind::kNone: break;
  }
  return "sample";
}

template <class T>
std::unique_ptr<RawWriter> MakeWriter(Bus& bus, const std::string& topic, QosKind qos) {
  return bus.CreateRawWriter(topic, TypeOpsOf<T>(), qos);
}

double Number(const std::string& s, double fallback) {
  try {
    return s.empty() ? fallback : std::stod(s);
  } catch (const std::exception&) {
    return fallback;
  }
}

}  // namespace

Bridge::Bridge(Bus& bus, std::string name, BridgeOptions options)
    : bus_(bus),
      name_(std::move(name)),
      options_(options),
      clock_(bus, kClock),
      map_(bus, kMap),
      commands_(bus, topics::kCommand),
      map_reader_(bus, topics::kMap,
                  [this](const msg::MapData& m, const SampleInfo&) {
                    std::lock_guard<std::mutex> lock(mu_);
                    map_data_ = m;
                    cv_.notify_all();
                  }),
      replies_(bus, topics::kCommandReply,
               [this](const msg::CommandReply& r, const SampleInfo&) {
                 if (r.client().to_string() != name_ || r.accepted()) return;
                 spdlog::warn("vehicle_control_cmd (command {}) rejected: {}", r.sequence_number(), r.reason().to_string());
               }),
      clouds_(bus, topics::kPointCloud, [this](const msg::PointCloud& s, const SampleInfo&) { OnSensor(s); }),
      imus_(bus, topics::kImu, [this](const msg::Imu& s, const SampleInfo&) { OnSensor(s); }),
      gnss_(bus, topics::kGnss, [this](const msg::Gnss& s, const SampleInfo&) { OnSensor(s); }),
      collisions_(bus, topics::kCollision, [this](const msg::CollisionEvent& s, const SampleInfo&) { OnSensor(s); }) {}

Bridge::~Bridge() {
  // Per-actor readers first, outside mu_ (their callbacks take it).
  image_readers_.clear();
  large_image_readers_.clear();
  control_readers_.clear();
}

uint64_t Bridge::published() const {
  std::lock_guard<std::mutex> lock(mu_);
  return published_;
}

double Bridge::InputTimeout() const {
  return options_.input_timeout_s > 0 ? options_.input_timeout_s : 0.9 * world_.settings().service_timeout();
}

void Bridge::BeginRun(const msg::WorldInfo& world) {
  ResetActors();
  world_ = world;
  map_published_ = false;
  std::lock_guard<std::mutex> lock(mu_);
  run_ = world.run();
  for (auto it = pending_.begin(); it != pending_.end();) {
    auto& v = it->second;
    std::erase_if(v, [&](const Pending& p) {
      return std::visit([&](const auto& s) { return s.stamp().run() != run_; }, p);
    });
    it = v.empty() ? pending_.erase(it) : std::next(it);
  }
}

void Bridge::ResetActors() {
  image_readers_.clear();
  large_image_readers_.clear();
  control_readers_.clear();
  std::lock_guard<std::mutex> lock(mu_);
  actors_.clear();
  outputs_.clear();
}

void Bridge::PublishMap() {
  if (world_.map_hash() == 0) return;  // no map in this run
  const double timeout_s = InputTimeout();
  std::unique_lock<std::mutex> lock(mu_);
  if (!cv_.wait_for(lock, std::chrono::duration<double>(timeout_s),
                    [&] { return map_data_ && map_data_->content_hash() == world_.map_hash(); })) {
    throw MissingInput("ros2_bridge: no lockstep/map of '" + world_.map_name().to_string() + "' within " +
                       std::to_string(timeout_s) + " s for rt/carla/map");
  }
  std_msgs::msg::dds_::String_ s;
  s.data(map_data_->opendrive());
  lock.unlock();
  map_.Write(s);
}

void Bridge::Register(const ActorInfo& a) {
  const SensorKind kind = SensorKindOf(a.blueprint);
  std::string base;
  {
    std::lock_guard<std::mutex> lock(mu_);
    actors_[a.id] = a;
    base = BaseTopic(a, actors_);
  }
  if (TakesControl(a)) {
    const uint32_t id = a.id;
    const std::string topic = base + "/vehicle_control_cmd";
    control_readers_[id] = std::make_unique<Reader<EgoControl>>(
        bus_, Topic<EgoControl>{topic.c_str(), QosKind::kCommand},
        [this, id](const EgoControl& c, const SampleInfo&) { OnControl(id, c); });
    spdlog::info("ROS 2: {} takes carla_msgs/CarlaEgoVehicleControl for vehicle {}", topic, id);
  }
  if (kind == SensorKind::kNone) return;

  Output out;
  out.actor = a;
  out.kind = kind;
  out.base = base;
  out.frame_id = RosName(a);
  out.per_frame = PerFrame(kind, Number(a.Attribute("sensor_tick"), 0), world_.settings().fixed_delta_seconds()) &&
                  !(kind == SensorKind::kCamera && world_.settings().no_rendering_mode());
  switch (kind) {
    case SensorKind::kCamera:
      out.writer = MakeWriter<sensor_msgs::msg::dds_::Image_>(bus_, base + "/image", QosKind::kLargeImage);
      out.info_writer = MakeWriter<sensor_msgs::msg::dds_::CameraInfo_>(bus_, base + "/camera_info", QosKind::kSensor);
      break;
    case SensorKind::kLidar:
    case SensorKind::kSemanticLidar:
      out.writer = MakeWriter<sensor_msgs::msg::dds_::PointCloud2_>(bus_, base, QosKind::kLargeImage);
      break;
    case SensorKind::kImu: out.writer = MakeWriter<sensor_msgs::msg::dds_::Imu_>(bus_, base, QosKind::kSensor); break;
    case SensorKind::kGnss: out.writer = MakeWriter<sensor_msgs::msg::dds_::NavSatFix_>(bus_, base, QosKind::kSensor); break;
    case SensorKind::kCollision:
      out.writer = MakeWriter<carla_msgs::msg::dds_::CarlaCollisionEvent_>(bus_, base, QosKind::kEvent);
      break;
    case SensorKind::kNone: break;
  }
  spdlog::info("ROS 2: {} '{}' (actor {}) on {}{}", a.blueprint, out.frame_id, a.id, base,
               kind == SensorKind::kCamera ? "/image, /camera_info" : "");
  std::vector<Pending> early;
  {
    std::lock_guard<std::mutex> lock(mu_);
    auto& slot = outputs_[a.id];
    slot = std::move(out);
    auto it = pending_.find(a.id);
    if (it != pending_.end()) {
      early = std::move(it->second);
      pending_.erase(it);
    }
    for (const auto& p : early) Forward(slot, p);
  }
  if (kind == SensorKind::kCamera) {
    const uint64_t bytes = static_cast<uint64_t>(Number(a.Attribute("image_size_x"), 800)) *
                           static_cast<uint64_t>(Number(a.Attribute("image_size_y"), 600)) * 4;
    const uint32_t id = a.id;
    if (bytes > kImageBoundBytes) {
      const std::string topic = topics::LargeImageTopicName(id);
      large_image_readers_[id] = std::make_unique<Reader<msg::LargeImage>>(
          bus_, Topic<msg::LargeImage>{topic.c_str(), QosKind::kLargeImage}, [this, id](const msg::LargeImage& i, const SampleInfo&) {
            ForwardImage(id, i.stamp(), i.width(), i.height(), i.step(), i.encoding(), i.fov(), i.data());
          });
    } else {
      const std::string topic = topics::ImageTopicName(id);
      image_readers_[id] = std::make_unique<Reader<msg::Image>>(
          bus_, Topic<msg::Image>{topic.c_str(), QosKind::kImage}, [this, id](const msg::Image& i, const SampleInfo&) {
            ForwardImage(id, i.stamp(), i.width(), i.height(), i.step(), i.encoding(), i.fov(), i.data());
          });
    }
  }
}

void Bridge::Unregister(uint32_t id) {
  image_readers_.erase(id);
  large_image_readers_.erase(id);
  control_readers_.erase(id);
  std::lock_guard<std::mutex> lock(mu_);
  actors_.erase(id);
  outputs_.erase(id);
  pending_.erase(id);
}

template <class Sample>
void Bridge::OnSensor(const Sample& s) {
  std::lock_guard<std::mutex> lock(mu_);
  if (s.stamp().run() < run_) return;
  auto it = outputs_.find(SensorOf(s));
  if (it == outputs_.end() || s.stamp().run() != run_) {
    // Its spawn is in a tick this bridge has not stepped yet (or a run it has not begun):
    // keep the last few until it does.
    auto& v = pending_[SensorOf(s)];
    v.emplace_back(s);
    if (v.size() > 8) v.erase(v.begin());
    return;
  }
  Forward(it->second, s);
}

void Bridge::Forward(Output& out, const Pending& p) {
  std::visit(
      [&](const auto& s) {
        using T = std::decay_t<decltype(s)>;
        if constexpr (std::is_same_v<T, msg::PointCloud>) {
          if (out.kind != SensorKind::kLidar && out.kind != SensorKind::kSemanticLidar) return;
          const auto m = ToPointCloud2(s, out.frame_id);
          out.writer->Write(&m);
        } else if constexpr (std::is_same_v<T, msg::Imu>) {
          if (out.kind != SensorKind::kImu) return;
          const auto m = ToRosImu(s, out.frame_id);
          out.writer->Write(&m);
        } else if constexpr (std::is_same_v<T, msg::Gnss>) {
          if (out.kind != SensorKind::kGnss) return;
          const auto m = ToNavSatFix(s, out.frame_id);
          out.writer->Write(&m);
        } else {
          if (out.kind != SensorKind::kCollision) return;
          const auto m = ToCollision(s, out.frame_id);
          out.writer->Write(&m);
        }
        if (s.stamp().frame() > out.last_frame) out.last_frame = s.stamp().frame();
        ++published_;
      },
      p);
  cv_.notify_all();
}

void Bridge::ForwardImage(uint32_t sensor, const msg::FrameStamp& stamp, uint32_t width, uint32_t height, uint32_t step,
                          uint32_t encoding, double fov, const std::vector<uint8_t>& data) {
  std::lock_guard<std::mutex> lock(mu_);
  auto it = outputs_.find(sensor);
  if (it == outputs_.end() || stamp.run() != run_ || stamp.frame() <= it->second.last_frame) return;
  Output& out = it->second;
  msg::Image image;  // the bounded type's fields; its data sequence is only read by ToRosImage
  image.stamp(stamp);
  image.width(width);
  image.height(height);
  image.step(step);
  image.encoding(encoding);
  image.fov(fov);
  std::string why;
  std::optional<sensor_msgs::msg::dds_::Image_> ros;
  {
    ros = ToRosImage(image, out.frame_id, &why);
    if (ros) ros->data().assign(data.begin(), data.end());
  }
  out.last_frame = stamp.frame();  // forwarded, or not publishable: either way the frame is done
  if (!ros) {
    if (!out.warned) spdlog::warn("ROS 2: camera {} ({}): {}; not published", sensor, out.base, why);
    out.warned = true;
  } else {
    out.writer->Write(&*ros);
    const auto info = ToCameraInfo(width, height, fov, ros->header().stamp(), out.frame_id);
    out.info_writer->Write(&info);
    ++published_;
  }
  cv_.notify_all();
}

void Bridge::OnControl(uint32_t actor, const EgoControl& c) {
  msg::CommandBody body;
  body.vehicle_control(FromEgoControl(c, actor));
  msg::Command command;
  command.client(name_);
  {
    std::lock_guard<std::mutex> lock(mu_);
    command.sequence_number(++sequence_);
  }
  command.body(body);
  if (commands_.MatchedReaders() == 0) spdlog::warn("vehicle_control_cmd for actor {}: no coordinator to send it to", actor);
  commands_.Write(command);
}

void Bridge::Step(const msg::Tick& tick) {
  for (const auto& c : tick.commands()) {
    const auto& b = c.body();
    if (b._d() == msg::CommandKind::CMD_SPAWN_ACTOR) {
      Register(ActorFromSpawn(b.spawn_actor(), tick.frame()));
    } else if (b._d() == msg::CommandKind::CMD_DESTROY_ACTOR) {
      Unregister(b.destroy_actor().actor());
    }
  }
  if (replaying()) return;  // the process it replaces published those frames
  rosgraph_msgs::msg::dds_::Clock_ clock;
  clock.clock(RosTime(tick.sim_time()));
  clock_.Write(clock);
  if (!map_published_) {
    PublishMap();
    map_published_ = true;
  }
  const uint64_t frame = PerceptionFrame(world_.settings().perception_mode(), tick.frame());
  if (frame < 1) return;
  // Every sensor that publishes each frame must have had its sample of `frame` forwarded
  // before this step acks: the run never moves past a frame the ROS view has not shown.
  const double timeout_s = InputTimeout();
  std::unique_lock<std::mutex> lock(mu_);
  const Output* missing = nullptr;
  auto all_in = [&] {
    for (const auto& [id, out] : outputs_) {
      if (out.per_frame && out.actor.spawn_frame <= frame && out.last_frame < frame) {
        missing = &out;
        return false;
      }
    }
    return true;
  };
  if (!cv_.wait_for(lock, std::chrono::duration<double>(timeout_s), all_in)) {
    throw MissingInput("ros2_bridge: no " + std::string(KindName(missing->kind)) + " of sensor " + std::to_string(missing->actor.id) +
                       " (" + missing->actor.blueprint + ", " + missing->base + ") for frame " + std::to_string(frame) + " within " +
                       std::to_string(timeout_s) + " s");
  }
}

}  // namespace lockstep::ros2
