// bench/run render --samples DIR: the sample images of docs/render.md, from one frame of
// Town01 with traffic: every output type from the ego car's dash camera, the drone's view
// of the same frame, and the car's view in several weathers and both times of day.
#include <opencv2/imgcodecs.hpp>

#include <cstdio>
#include <filesystem>
#include <string>

#include "lockstep/render/dvs.h"
#include "lockstep/render/exposure.h"
#include "lockstep/render/images.h"
#include "lockstep/render/weather.h"
#include "town.h"

namespace lockstep::render::bench {

namespace {

constexpr int kW = 320, kH = 180;

void Write(const std::string& dir, const std::string& name, const std::vector<std::uint8_t>& bgra) {
  cv::Mat m(kH, kW, CV_8UC4, const_cast<std::uint8_t*>(bgra.data()));
  cv::Mat bgr;
  cv::Mat channels[4];
  cv::split(m, channels);
  cv::merge(channels, 3, bgr);
  const std::string path = dir + "/" + name + ".png";
  cv::imwrite(path, bgr, {cv::IMWRITE_PNG_COMPRESSION, 9});
  std::printf("{\"sample\":\"%s\",\"bytes\":%ju}\n", path.c_str(), static_cast<std::uintmax_t>(std::filesystem::file_size(path)));
}

std::vector<std::uint8_t> InstanceColors(const std::uint8_t* labels) {
  std::vector<std::uint8_t> out(static_cast<std::size_t>(kW) * kH * 4);
  for (std::size_t i = 0; i < out.size() / 4; ++i) {
    const std::uint32_t id = labels[i * 4 + 1] | (labels[i * 4 + 2] << 8) | (labels[i * 4 + 3] << 16);
    const std::uint32_t h = id * 2654435761u;
    out[i * 4] = id ? static_cast<std::uint8_t>(h >> 8) : 0;
    out[i * 4 + 1] = id ? static_cast<std::uint8_t>(h >> 16) : 0;
    out[i * 4 + 2] = id ? static_cast<std::uint8_t>(h >> 24) : 0;
    out[i * 4 + 3] = 255;
  }
  return out;
}

}  // namespace

int Samples(const std::string& dir) {
  std::filesystem::create_directories(dir);
  Renderer r;
  Town town = LoadTown(r, 50);
  Camera car;
  car.width = kW;
  car.height = kH;
  car.fov_deg = 90;
  car.pose = DashCamera(town);
  car.previous_pose = car.pose * Pose{Vec3(-0.8, 0, 0), Quat(Eigen::AngleAxisd(0.02, Vec3::UnitZ()))};
  car.outputs = kOutColor | kOutDepth | kOutLabels | kOutNormals | kOutFlow;
  Camera drone = car;
  drone.pose = town.drone * Pose{Vec3(0, 0, -0.1), Quat(Eigen::AngleAxisd(M_PI / 5, Vec3::UnitY()))};  // 36 deg down
  drone.previous_pose.reset();
  drone.outputs = kOutColor | kOutLabels;
  town.world.weather = WeatherPreset("ClearNoon");
  for (auto& a : town.world.actors) a.previous_pose = a.pose * Pose{Vec3(-0.5, 0, 0), Quat::Identity()};
  r.Render({car, drone}, town.world, [&](std::size_t i, const CameraImages& im) {
    if (i == 0) {
      Write(dir, "car_rgb_clear_noon", std::vector<std::uint8_t>(im.color, im.color + kW * kH * 4));
      Write(dir, "car_depth", DepthToGray(im.depth, kW, kH));
      Write(dir, "car_semantic", SemanticToPalette(im.labels, kW, kH));
      Write(dir, "car_instance", InstanceColors(im.labels));
      Write(dir, "car_normals", std::vector<std::uint8_t>(im.normals, im.normals + kW * kH * 4));
      Write(dir, "car_optical_flow", FlowToColor(im.flow, kW, kH));
    } else {
      Write(dir, "drone_rgb_same_frame", std::vector<std::uint8_t>(im.color, im.color + kW * kH * 4));
      Write(dir, "drone_semantic_same_frame", SemanticToPalette(im.labels, kW, kH));
    }
  });
  car.outputs = kOutColor;
  car.previous_pose.reset();
  for (const char* preset : {"ClearSunset", "HardRainNoon", "ClearNight", "WetCloudySunset", "DustStorm"}) {
    town.world.weather = WeatherPreset(preset);
    const bool night = ComputeLighting(town.world.weather).night;
    for (auto& a : town.world.actors) a.light_state = night ? light::kPosition | light::kLowBeam : 0u;
    auto f = r.RenderFrames({car}, town.world)[0];
    std::string name = std::string("car_rgb_") + preset;
    Write(dir, name, f.color);
  }
  // Histogram auto exposure at night: 12 images 0.5 s apart, exposure_min_bright lowered
  // to 2 (CARLA's 10 keeps the night as dark as the manual image above).
  {
    town.world.weather = WeatherPreset("ClearNight");
    for (auto& a : town.world.actors) a.light_state = light::kPosition | light::kLowBeam;
    ExposureSettings es;
    es.min_bright = 2;
    AutoExposure ae(es);
    Camera c = car;
    CameraFrame f;
    for (int k = 0; k < 12; ++k) {
      c.exposure = ae.Multiplier();
      f = r.RenderFrames({c}, town.world)[0];
      ae.Update(f.color.data(), kW, kH, c.exposure, c.gamma, k == 0 ? 0.0 : 0.5);
    }
    Write(dir, "car_rgb_ClearNight_auto_exposure", f.color);
    for (auto& a : town.world.actors) a.light_state = 0;
  }
  // Motion blur: the car's camera 0.8 m on since its previous image (CARLA's intensity
  // 0.45; max_distortion 5 %, Unreal's default, so that it shows at this size).
  {
    town.world.weather = WeatherPreset("ClearNoon");
    Camera c = car;
    c.previous_pose = c.pose * Pose{Vec3(-0.8, 0, 0), Quat::Identity()};
    c.motion_blur_intensity = 0.45;
    c.motion_blur_max_distortion = 5;
    Write(dir, "car_rgb_motion_blur", r.RenderFrames({c}, town.world)[0].color);
  }
  // DVS: events between two frames of the car driving 1 m on, red = brighter, blue = darker.
  town.world.weather = WeatherPreset("ClearNoon");
  for (auto& a : town.world.actors) a.light_state = 0;
  DvsSensor dvs(DvsParams{}, kW, kH, 42);
  dvs.Update(r.RenderFrames({car}, town.world)[0].color.data(), 0);
  car.pose = car.pose * Pose{Vec3(1.0, 0, 0), Quat::Identity()};
  const auto events = dvs.Update(r.RenderFrames({car}, town.world)[0].color.data(), 50'000'000);
  std::vector<std::uint8_t> img(static_cast<std::size_t>(kW) * kH * 4, 0);
  for (std::size_t i = 3; i < img.size(); i += 4) img[i] = 255;
  for (const auto& e : events) img[(static_cast<std::size_t>(e.y) * kW + e.x) * 4 + (e.pol ? 2 : 0)] = 255;
  Write(dir, "car_dvs_events", img);
  return 0;
}

}  // namespace lockstep::render::bench
