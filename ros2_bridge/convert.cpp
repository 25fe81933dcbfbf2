#include "convert.h"

#include <cmath>
#include <cstring>
#include <vector>

namespace lockstep::ros2 {

namespace {

bool StartsWith(const std::string& s, const char* prefix) { return s.rfind(prefix, 0) == 0; }

std_msgs::msg::dds_::Header_ Header(const builtin_interfaces::msg::dds_::Time_& stamp, const std::string& frame_id) {
  std_msgs::msg::dds_::Header_ h;
  h.stamp(stamp);
  h.frame_id(frame_id);
  return h;
}

sensor_msgs::msg::dds_::PointField_ Field(const char* name, uint32_t offset, uint8_t datatype) {
  sensor_msgs::msg::dds_::PointField_ f;
  f.name(name);
  f.offset(offset);
  f.datatype(datatype);
  f.count(1);
  return f;
}

constexpr uint8_t kFloat32 = 7;  // sensor_msgs/PointField.FLOAT32
constexpr uint8_t kUint32 = 6;   // sensor_msgs/PointField.UINT32

geometry_msgs::msg::dds_::Vector3_ Vec(const msg::Vector3& v) {
  geometry_msgs::msg::dds_::Vector3_ out;
  out.x(v.x());
  out.y(v.y());
  out.z(v.z());
  return out;
}

}  // namespace

builtin_interfaces::msg::dds_::Time_ RosTime(double sim_time) {
  double integral = 0;
  const double fractional = std::modf(sim_time, &integral);
  builtin_interfaces::msg::dds_::Time_ t;
  t.sec(static_cast<int32_t>(integral));
  t.nanosec(static_cast<uint32_t>(fractional * 1000000000.0));
  return t;
}

std::string TimeString(const builtin_interfaces::msg::dds_::Time_& t) {
  return std::to_string(t.sec()) + "." + std::to_string(t.nanosec());
}

SensorKind SensorKindOf(const std::string& bp) {
  if (StartsWith(bp, "sensor.camera.")) return SensorKind::kCamera;
  if (bp == "sensor.lidar.ray_cast_semantic") return SensorKind::kSemanticLidar;
  if (StartsWith(bp, "sensor.lidar.")) return SensorKind::kLidar;
  if (bp == "sensor.other.imu") return SensorKind::kImu;
  if (bp == "sensor.other.gnss") return SensorKind::kGnss;
  if (bp == "sensor.other.collision") return SensorKind::kCollision;
  return SensorKind::kNone;
}

bool PerFrame(SensorKind kind, double sensor_tick, double dt) {
  if (kind == SensorKind::kNone || kind == SensorKind::kCollision) return false;
  return !(sensor_tick > dt + 1e-9);
}

std::string ActorInfo::Attribute(const std::string& key, const std::string& fallback) const {
  auto it = attributes.find(key);
  return it == attributes.end() ? fallback : it->second;
}

ActorInfo ActorFromSpawn(const msg::SpawnActor& spawn, uint64_t frame) {
  ActorInfo a;
  a.id = spawn.actor();
  a.parent = spawn.parent();
  a.spawn_frame = frame;
  a.blueprint = spawn.blueprint().to_string();
  for (const auto& attr : spawn.attributes()) a.attributes[attr.key().to_string()] = attr.value().to_string();
  return a;
}

std::string RosName(const ActorInfo& actor) {
  const std::string role = actor.Attribute("role_name");
  const bool vehicle = StartsWith(actor.blueprint, "vehicle.");
  if (!role.empty() && !(vehicle && role == "autopilot")) return role;
  if (vehicle) return "vehicle" + std::to_string(actor.id);
  const size_t dot = actor.blueprint.find_last_of('.');
  return (dot == std::string::npos ? actor.blueprint : actor.blueprint.substr(dot + 1)) + std::to_string(actor.id);
}

std::string BaseTopic(const ActorInfo& actor, const std::map<uint32_t, ActorInfo>& actors) {
  std::string path = RosName(actor);
  uint32_t parent = actor.parent;
  for (int depth = 0; parent != 0 && depth < 16; ++depth) {  // CARLA's chain of ancestors; a cycle cannot loop
    auto it = actors.find(parent);
    if (it == actors.end()) break;
    path = RosName(it->second) + "/" + path;
    parent = it->second.parent;
  }
  return "rt/carla/" + path;
}

bool TakesControl(const ActorInfo& actor) {
  if (!StartsWith(actor.blueprint, "vehicle.")) return false;
  const std::string role = actor.Attribute("role_name");
  return role == "hero" || role == "ego";
}

const char* RosEncoding(uint32_t e) {
  switch (static_cast<msg::ImageEncoding>(e)) {
    case msg::ImageEncoding::IMAGE_BGRA8:
    case msg::ImageEncoding::IMAGE_DEPTH_CARLA_BGRA8:
    case msg::ImageEncoding::IMAGE_SEMANTIC_BGRA8:
    case msg::ImageEncoding::IMAGE_INSTANCE_BGRA8:
    case msg::ImageEncoding::IMAGE_NORMALS_BGRA8:
    case msg::ImageEncoding::IMAGE_SEGMENTATION_BGRA8:
      return "bgra8";
    case msg::ImageEncoding::IMAGE_DEPTH_F32:
    case msg::ImageEncoding::IMAGE_DEPTH_PERSPECTIVE_F32:
    case msg::ImageEncoding::IMAGE_DISPARITY_F32:
      return "32FC1";
    case msg::ImageEncoding::IMAGE_GRAY8:
      return "mono8";
    case msg::ImageEncoding::IMAGE_FLOW_F32X2:
      return "32FC2";
    case msg::ImageEncoding::IMAGE_DVS_EVENTS:
      return nullptr;
  }
  return nullptr;
}

std::optional<sensor_msgs::msg::dds_::Image_> ToRosImage(const msg::Image& image, const std::string& frame_id, std::string* why) {
  const char* encoding = RosEncoding(image.encoding());
  if (encoding == nullptr) {
    if (why) *why = "image encoding " + std::to_string(image.encoding()) + " (DVS events) has no sensor_msgs/Image form";
    return std::nullopt;
  }
  sensor_msgs::msg::dds_::Image_ out;
  out.header(Header(RosTime(image.stamp().sim_time()), frame_id));
  out.height(image.height());
  out.width(image.width());
  out.encoding(encoding);
  out.is_bigendian(0);
  out.step(image.step());
  out.data().assign(image.data().begin(), image.data().end());
  return out;
}

sensor_msgs::msg::dds_::CameraInfo_ ToCameraInfo(uint32_t width, uint32_t height, double fov_rad,
                                                 const builtin_interfaces::msg::dds_::Time_& stamp, const std::string& frame_id) {
  sensor_msgs::msg::dds_::CameraInfo_ info;
  info.header(Header(stamp, frame_id));
  info.height(height);
  info.width(width);
  info.distortion_model("plumb_bob");
  info.d(std::vector<double>(5, 0.0));
  const double cx = width / 2.0, cy = height / 2.0;
  const double fx = width / (2.0 * std::tan(fov_rad / 2.0)), fy = fx;
  info.k({fx, 0, cx, 0, fy, cy, 0, 0, 1});
  info.r({1, 0, 0, 0, 1, 0, 0, 0, 1});
  info.p({fx, 0, cx, 0, 0, fy, cy, 0, 0, 0, 1, 0});
  info.binning_x(0);
  info.binning_y(0);
  sensor_msgs::msg::dds_::RegionOfInterest_ roi;  // CARLA: InitInfoData(0, 0, H, W, fov, do_rectify = true)
  roi.x_offset(0);
  roi.y_offset(0);
  roi.height(height);
  roi.width(width);
  roi.do_rectify(true);
  info.roi(roi);
  return info;
}

sensor_msgs::msg::dds_::PointCloud2_ ToPointCloud2(const msg::PointCloud& cloud, const std::string& frame_id) {
  sensor_msgs::msg::dds_::PointCloud2_ out;
  out.header(Header(RosTime(cloud.stamp().sim_time()), frame_id));
  const bool semantic = cloud.format() == msg::PointFormat::POINTS_SEMANTIC;
  if (semantic) {
    out.fields({Field("x", 0, kFloat32), Field("y", 4, kFloat32), Field("z", 8, kFloat32), Field("cos_inc_angle", 12, kFloat32),
                Field("object_idx", 16, kUint32), Field("object_tag", 20, kUint32)});
  } else {
    out.fields({Field("x", 0, kFloat32), Field("y", 4, kFloat32), Field("z", 8, kFloat32), Field("intensity", 12, kFloat32)});
  }
  out.height(1);
  out.width(cloud.point_count());
  out.is_bigendian(false);
  out.point_step(cloud.point_step());
  out.row_step(cloud.point_step() * cloud.point_count());
  out.data().assign(cloud.data().begin(), cloud.data().end());
  out.is_dense(false);
  return out;
}

sensor_msgs::msg::dds_::Imu_ ToRosImu(const msg::Imu& imu, const std::string& frame_id) {
  sensor_msgs::msg::dds_::Imu_ out;
  out.header(Header(RosTime(imu.stamp().sim_time()), frame_id));
  geometry_msgs::msg::dds_::Quaternion_ q;
  q.x(imu.orientation().x());
  q.y(imu.orientation().y());
  q.z(imu.orientation().z());
  q.w(imu.orientation().w());
  out.orientation(q);
  out.angular_velocity(Vec(imu.gyroscope()));
  out.linear_acceleration(Vec(imu.accelerometer()));
  return out;
}

sensor_msgs::msg::dds_::NavSatFix_ ToNavSatFix(const msg::Gnss& gnss, const std::string& frame_id) {
  sensor_msgs::msg::dds_::NavSatFix_ out;
  out.header(Header(RosTime(gnss.stamp().sim_time()), frame_id));
  out.latitude(gnss.latitude());
  out.longitude(gnss.longitude());
  out.altitude(gnss.altitude());
  return out;  // status, covariance and its type stay 0, as CARLA leaves them
}

carla_msgs::msg::dds_::CarlaCollisionEvent_ ToCollision(const msg::CollisionEvent& event, const std::string& frame_id) {
  carla_msgs::msg::dds_::CarlaCollisionEvent_ out;
  out.header(Header(RosTime(event.stamp().sim_time()), frame_id));
  out.other_actor_id(event.other_actor());
  out.normal_impulse(Vec(event.normal_impulse()));
  return out;
}

msg::VehicleControl FromEgoControl(const carla_msgs::msg::dds_::CarlaEgoVehicleControl_& c, uint32_t actor) {
  msg::VehicleControl v;
  v.actor(actor);
  v.throttle(c.throttle());
  v.steer(c.steer());
  v.brake(c.brake());
  v.hand_brake(c.hand_brake());
  v.reverse(c.reverse());
  v.manual_gear_shift(c.manual_gear_shift());
  v.gear(c.gear());
  return v;
}

}  // namespace lockstep::ros2
