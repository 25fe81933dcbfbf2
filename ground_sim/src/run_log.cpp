#include "lockstep/ground/run_log.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

namespace lockstep::ground {
namespace {

constexpr double kSummaryPeriod = 1.0;  // s of simulated time between summary rewrites

void Json(std::ostream& o, const Infractions& f) {
  o << "\"red_lights\": " << f.red_lights << ", \"stop_signs\": " << f.stop_signs << ", \"vehicle_collisions\": "
    << f.vehicle_collisions << ", \"walker_collisions\": " << f.walker_collisions << ", \"static_collisions\": "
    << f.static_collisions << ", \"lane_invasions\": " << f.lane_invasions;
}

std::string Escaped(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    if (static_cast<unsigned char>(c) >= 0x20) out += c;
  }
  return out;
}

}  // namespace

RunLog::RunLog(std::string dir, bool fresh) : dir_(std::move(dir)) {
  std::error_code ec;
  std::filesystem::create_directories(dir_, ec);
  if (ec) throw std::runtime_error("ground log: cannot create " + dir_ + ": " + ec.message());
  const std::string path = dir_ + "/vehicles.csv";
  const bool header = fresh || !std::filesystem::exists(path);
  csv_.open(path, fresh ? std::ios::trunc : std::ios::app);
  if (!csv_) throw std::runtime_error("ground log: cannot write " + path);
  if (header) {
    csv_ << "frame,sim_time_s,id,blueprint,role_name,x_m,y_m,z_m,yaw_deg,speed_mps,accel_mps2,throttle,steer,brake,gear,"
            "autopilot,kinematic,speed_limit_mps,traffic_light,stop_line_m,opposite_lane,sidewalk,red_lights,stop_signs,"
            "collisions,lane_invasions\n";
  }
}

RunLog::~RunLog() {
  try {
    WriteSummary();
  } catch (...) {
    // A destructor must not throw; the last periodic summary stays.
  }
}

void RunLog::Write(const World& world, uint64_t frame, double sim_time) {
  const double dt = frames_ > 0 ? std::max(0.0, sim_time - last_time_) : 0.0;
  ++frames_;
  last_time_ = sim_time;
  char row[512];
  for (const auto& v : world.Vehicles()) {
    const double speed = v.velocity.norm();
    const auto& f = v.infractions;
    std::snprintf(row, sizeof row, ",%.3f,%.3f,%.3f,%.2f,%.3f,%.3f,%.3f,%.3f,%.3f,%d,%d,%d,%.2f,%u,%.2f,%.3f,%.3f,%d,%d,%d,%d\n",
                  v.pose.position.x(), v.pose.position.y(), v.pose.position.z(), v.pose.Yaw() * 180.0 / M_PI, speed,
                  v.acceleration.norm(), v.control.throttle, v.control.steer, v.control.brake, v.gear, v.autopilot ? 1 : 0,
                  v.kinematic ? 1 : 0, v.speed_limit, v.traffic_light, v.stop_line_distance, v.opposite_lane, v.sidewalk,
                  f.red_lights, f.stop_signs, f.vehicle_collisions + f.walker_collisions + f.static_collisions,
                  f.lane_invasions);
    csv_ << frame << ',' << sim_time << ',' << v.id << ',' << v.blueprint << ',' << v.role_name << row;
    PerVehicle& p = vehicles_[v.id];
    p.blueprint = v.blueprint;
    p.role_name = v.role_name;
    p.infractions = v.infractions;  // cumulative in the world
    p.autopilot = v.autopilot;
    if (p.has_last) p.distance += (v.pose.position - p.last).head<2>().norm();
    p.last = v.pose.position;
    p.has_last = true;
    p.time += dt;
  }
  for (const auto& c : world.Collisions()) {
    if (c.other_kind == ObjectKind::kVehicle && world.IsVehicle(c.actor))
      vehicle_pairs_.insert({std::min(c.actor, c.other_actor), std::max(c.actor, c.other_actor)});
  }
  if (sim_time >= summary_due_) {
    csv_.flush();
    WriteSummary();
    summary_due_ = sim_time + kSummaryPeriod;
  }
}

void RunLog::WriteSummary() const {
  Infractions total;
  double distance = 0, time = 0;
  for (const auto& [id, p] : vehicles_) {
    total.red_lights += p.infractions.red_lights;
    total.stop_signs += p.infractions.stop_signs;
    total.vehicle_collisions += p.infractions.vehicle_collisions;
    total.walker_collisions += p.infractions.walker_collisions;
    total.static_collisions += p.infractions.static_collisions;
    total.lane_invasions += p.infractions.lane_invasions;
    distance += p.distance;
    time += p.time;
  }
  const std::string path = dir_ + "/infractions.json", tmp = path + ".tmp";
  {
    std::ofstream o(tmp, std::ios::trunc);
    if (!o) throw std::runtime_error("ground log: cannot write " + tmp);
    o << "{\n  \"frames\": " << frames_ << ", \"sim_time_s\": " << last_time_ << ", \"vehicles\": " << vehicles_.size()
      << ",\n  \"mean_speed_kmh\": " << (time > 0 ? distance / time * 3.6 : 0.0)
      << ", \"vehicle_pairs_in_contact\": " << vehicle_pairs_.size() << ",\n  \"total\": {";
    Json(o, total);
    o << "},\n  \"per_vehicle\": [";
    bool first = true;
    for (const auto& [id, p] : vehicles_) {
      o << (first ? "\n" : ",\n") << "    {\"id\": " << id << ", \"blueprint\": \"" << Escaped(p.blueprint) << "\", \"role_name\": \""
        << Escaped(p.role_name) << "\", \"autopilot\": " << (p.autopilot ? "true" : "false") << ", \"distance_m\": " << p.distance
        << ", ";
      Json(o, p.infractions);
      o << "}";
      first = false;
    }
    o << "\n  ]\n}\n";
  }
  std::filesystem::rename(tmp, path);
}

}  // namespace lockstep::ground
