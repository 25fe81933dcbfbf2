#include "lockstep/recorder/carla_text.h"

#include <cmath>
#include <ctime>
#include <filesystem>
#include <functional>
#include <iomanip>
#include <map>
#include <set>
#include <sstream>

#include "lockstep/recorder/log_reader.h"

namespace lockstep::recorder {
namespace {

constexpr double kDeg = 180.0 / M_PI;
constexpr uint32_t kNoActor = 0xffffffffu;  // CARLA's id of a non-actor (static geometry)

struct CarlaPose {
  double x, y, z;           // cm, left-handed
  double roll, pitch, yaw;  // deg, CARLA's signs
};

// Lockstep's ENU box-centre pose as CARLA's actor location (vehicles: the base of the box).
CarlaPose ToCarla(double x, double y, double z, double roll, double pitch, double yaw, double half_z, bool base) {
  if (base && half_z != 0) {
    // The box's up axis (third column of R = Rz(yaw) Ry(pitch) Rx(roll)).
    const double ux = std::cos(yaw) * std::sin(pitch) * std::cos(roll) + std::sin(yaw) * std::sin(roll);
    const double uy = std::sin(yaw) * std::sin(pitch) * std::cos(roll) - std::cos(yaw) * std::sin(roll);
    const double uz = std::cos(pitch) * std::cos(roll);
    x -= ux * half_z;
    y -= uy * half_z;
    z -= uz * half_z;
  }
  // + 0.0 turns -0 into 0, as CARLA prints a zero.
  return CarlaPose{x * 100 + 0.0, -y * 100 + 0.0, z * 100 + 0.0, roll * kDeg + 0.0, -pitch * kDeg + 0.0, -yaw * kDeg + 0.0};
}

CarlaPose ToCarla(const ActorState& s, const ActorInfo* info) {
  const bool vehicle = s.kind == msg::ActorKind::ACTOR_VEHICLE;
  return ToCarla(s.x, s.y, s.z, s.roll, s.pitch, s.yaw, info ? info->half_extents[2] : 0, vehicle);
}

bool IsHero(const ActorInfo* a) { return a != nullptr && a->Attribute("role_name") == "hero"; }

// Opens the log for a query, or writes CARLA's message into `info` and returns null.
std::unique_ptr<LogReader> OpenForQuery(const std::string& name, std::ostream& info) {
  const std::string path = ResolveLogPath(name);
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    info << "File " << path << " not found on server\n";
    return nullptr;
  }
  std::unique_ptr<LogReader> log;
  try {
    log = std::make_unique<LogReader>(path);
  } catch (const std::exception& e) {
    info << "File is not a Lockstep log (" << e.what() << ")" << std::endl;
    return nullptr;
  }
  // CARLA's CheckFileInfo.
  info << "Version: " << log->header().format_version << std::endl;
  info << "Map: " << log->header().map_name << std::endl;
  const std::time_t t = static_cast<std::time_t>(log->header().start_unix_time);
  std::tm tm_buf{};
  localtime_r(&t, &tm_buf);
  char date[100];
  std::strftime(date, sizeof date, "%x %X", &tm_buf);
  info << "Date: " << date << std::endl << std::endl;
  return log;
}

// The collisions of a frame as CARLA records them: one per pair of actors (the first
// direction reported), static geometry as CARLA's non-actor id.
std::vector<std::pair<uint32_t, uint32_t>> FrameCollisions(const LogFrame& f) {
  std::vector<std::pair<uint32_t, uint32_t>> out;
  std::set<std::pair<uint32_t, uint32_t>> seen;
  for (const auto& c : f.collisions) {
    const uint32_t a = c.actor;
    const uint32_t b = c.other_actor == 0 ? kNoActor : c.other_actor;
    if (seen.count({a, b}) || seen.count({b, a})) continue;
    seen.insert({a, b});
    out.emplace_back(a, b);
  }
  return out;
}

bool Positioned(msg::ActorKind k) {
  return k == msg::ActorKind::ACTOR_VEHICLE || k == msg::ActorKind::ACTOR_WALKER || k == msg::ActorKind::ACTOR_DRONE ||
         k == msg::ActorKind::ACTOR_PROP || k == msg::ActorKind::ACTOR_OTHER;
}

std::string LightList(uint32_t bits) {
  static const char* names[] = {"Position", "LowBeam", "HighBeam", "Brake", "RightBlinker", "LeftBlinker",
                                "Reverse", "Fog", "Interior", "Special1", "Special2"};
  std::string out;
  for (int i = 0; i < 11; ++i) {
    if (bits & (1u << i)) out += std::string(names[i]) + " ";
  }
  return out.empty() ? "None" : out.substr(0, out.size() - 1);
}

}  // namespace

std::string ShowRecorderFileInfo(const std::string& name, bool show_all) {
  std::stringstream info;
  auto log = OpenForQuery(name, info);
  if (!log) return info.str();
  const auto& actors = log->actors();
  auto find = [&](uint32_t id) -> const ActorInfo* {
    auto it = actors.find(id);
    return it == actors.end() ? nullptr : &it->second;
  };
  uint64_t index = 0;
  double elapsed = 0;
  uint64_t collision_id = 0;
  std::map<uint32_t, uint32_t> lights_before;
  log->ForEach([&](const LogFrame& f) {
    ++index;
    elapsed = f.elapsed;
    bool printed = false;
    auto print_frame = [&] {
      if (!printed) info << "Frame " << index << " at " << elapsed << " seconds\n";
      printed = true;
    };
    if (show_all) print_frame();
    for (uint32_t id : f.spawned) {
      const ActorInfo* a = find(id);
      if (a == nullptr) continue;
      print_frame();
      CarlaPose p{};
      if (const ActorState* s = f.Find(id); s != nullptr && Positioned(s->kind)) {
        p = ToCarla(*s, a);
      } else {
        const auto& sp = a->spawn_pose;
        p = ToCarla(sp.position().x(), sp.position().y(), sp.position().z(), 0, 0, 0, 0, false);
        if (const ActorState* l = f.Find(id); l != nullptr) p = ToCarla(l->x, l->y, l->z, 0, 0, 0, 0, false);
      }
      info << " Create " << id << ": " << a->blueprint << " (" << CarlaActorType(a->kind) << ") at (" << p.x << ", " << p.y << ", "
           << p.z << ")" << std::endl;
      for (const auto& [k, v] : a->attributes) info << "  " << k << " = " << v << std::endl;
    }
    for (uint32_t id : f.destroyed) {
      print_frame();
      info << " Destroy " << id << "\n";
    }
    for (uint32_t id : f.spawned) {
      const ActorInfo* a = find(id);
      if (a == nullptr || a->parent == 0) continue;
      print_frame();
      info << " Parenting " << id << " with " << a->parent << " (parent)\n";
    }
    for (const auto& [a, b] : FrameCollisions(f)) {
      print_frame();
      info << " Collision id " << ++collision_id << " between " << a;
      if (IsHero(find(a))) info << " (hero) ";
      info << " with " << b;
      if (b != kNoActor && IsHero(find(b))) info << " (hero) ";
      info << std::endl;
    }
    if (!show_all) return true;
    size_t positioned = 0, lights = 0, vehicles = 0, walkers = 0;
    for (const auto& s : f.actors) {
      positioned += Positioned(s.kind);
      lights += s.kind == msg::ActorKind::ACTOR_TRAFFIC_LIGHT;
      vehicles += s.kind == msg::ActorKind::ACTOR_VEHICLE;
      walkers += s.kind == msg::ActorKind::ACTOR_WALKER;
    }
    info << " Positions: " << positioned << std::endl;
    for (const auto& s : f.actors) {
      if (!Positioned(s.kind)) continue;
      const CarlaPose p = ToCarla(s, find(s.id));
      info << "  Id: " << s.id << " Location: (" << p.x << ", " << p.y << ", " << p.z << ") Rotation: (" << p.roll << ", " << p.pitch
           << ", " << p.yaw << ")" << std::endl;
    }
    info << " State traffic lights: " << lights << std::endl;
    for (const auto& s : f.actors) {
      if (s.kind != msg::ActorKind::ACTOR_TRAFFIC_LIGHT) continue;
      info << "  Id: " << s.id << " state: " << static_cast<char>(0x30 + static_cast<int>(s.light)) << " frozen: " << s.frozen
           << " elapsedTime: " << s.elapsed << std::endl;
    }
    info << " Vehicle animations: " << vehicles << std::endl;
    for (const auto& s : f.actors) {
      if (s.kind != msg::ActorKind::ACTOR_VEHICLE) continue;
      info << "  Id: " << s.id << " Steering: " << s.steer << " Throttle: " << s.throttle << " Brake: " << s.brake
           << " Handbrake: " << s.hand_brake << " Gear: " << s.gear << std::endl;
    }
    info << " Walker animations: " << walkers << std::endl;
    for (const auto& s : f.actors) {
      if (s.kind != msg::ActorKind::ACTOR_WALKER) continue;
      info << "  Id: " << s.id << " speed: " << s.speed * 100 << std::endl;  // cm/s, as Unreal's
    }
    std::vector<const ActorState*> changed;
    for (const auto& s : f.actors) {
      if (s.kind != msg::ActorKind::ACTOR_VEHICLE) continue;
      auto it = lights_before.find(s.id);
      if (it == lights_before.end() || it->second != s.light_state) changed.push_back(&s);
      lights_before[s.id] = s.light_state;
    }
    info << " Vehicle light animations: " << changed.size() << std::endl;
    for (const ActorState* s : changed) info << "  Id: " << s->id << " " << LightList(s->light_state) << std::endl;
    return true;
  });
  info << "\nFrames: " << index << "\n";
  info << "Duration: " << elapsed << " seconds\n";
  return info.str();
}

std::string ShowRecorderCollisions(const std::string& name, char type1, char type2) {
  std::stringstream info;
  auto log = OpenForQuery(name, info);
  if (!log) return info.str();
  const auto& actors = log->actors();
  auto category = [&](uint32_t id) -> char {
    if (id == kNoActor) return 'o';
    auto it = actors.find(id);
    static const char cats[] = {'o', 'v', 'w', 't', 'h', 'a'};
    const int type = it == actors.end() ? 0 : CarlaActorType(it->second.kind);
    return cats[type];
  };
  auto hero = [&](uint32_t id) {
    auto it = actors.find(id);
    return it != actors.end() && IsHero(&it->second);
  };
  auto blueprint = [&](uint32_t id) -> std::string {
    auto it = actors.find(id);
    return it == actors.end() ? std::string() : it->second.blueprint;
  };
  info << std::setw(8) << "Time";
  info << " " << std::setw(6) << "Types";
  info << " " << std::setw(6) << std::right << "Id";
  info << " " << std::setw(35) << std::left << "Actor 1";
  info << " " << std::setw(6) << std::right << "Id";
  info << " " << std::setw(35) << std::left << "Actor 2";
  info << std::endl;
  std::set<std::pair<uint32_t, uint32_t>> before, now;
  uint64_t index = 0;
  double elapsed = 0;
  log->ForEach([&](const LogFrame& f) {
    ++index;
    elapsed = f.elapsed;
    before = std::move(now);
    now.clear();
    for (const auto& [a, b] : FrameCollisions(f)) {
      const char t1 = category(a), t2 = category(b);
      int valid = 0;
      if (type1 == 'a' || type1 == t1 || (type1 == 'h' && hero(a))) ++valid;
      if (type2 == 'a' || type2 == t2 || (type2 == 'h' && b != kNoActor && hero(b))) ++valid;
      if (valid != 2) continue;
      if (before.count({a, b}) == 0) {
        info << std::setw(8) << std::setprecision(0) << std::right << std::fixed << elapsed;
        info << " " << "  " << t1 << " " << t2 << " ";
        info << " " << std::setw(6) << std::right << a;
        info << " " << std::setw(35) << std::left << blueprint(a);
        info << " " << std::setw(6) << std::right << b;
        info << " " << std::setw(35) << std::left << blueprint(b);
        info << std::endl;
      }
      now.insert({a, b});
    }
    return true;
  });
  info << "\nFrames: " << index << "\n";
  info << "Duration: " << elapsed << " seconds\n";
  return info.str();
}

std::string ShowRecorderActorsBlocked(const std::string& name, double min_time, double min_distance) {
  std::stringstream info;
  auto log = OpenForQuery(name, info);
  if (!log) return info.str();
  struct Blocked {
    std::string blueprint;
    double last[3] = {0, 0, 0};  // cm
    double time = 0;
    double duration = 0;
  };
  std::map<uint32_t, Blocked> actors;
  std::multimap<double, std::string, std::greater<double>> results;
  info << std::setw(8) << "Time";
  info << " " << std::setw(6) << "Id";
  info << " " << std::setw(35) << std::left << "Actor";
  info << " " << std::setw(10) << std::right << "Duration";
  info << std::endl;
  auto result = [&](uint32_t id, const Blocked& b) {
    std::stringstream r;
    r << std::setw(8) << std::setprecision(0) << std::fixed << b.time;
    r << " " << std::setw(6) << id;
    r << " " << std::setw(35) << std::left << b.blueprint;
    r << " " << std::setw(10) << std::setprecision(0) << std::fixed << std::right << b.duration;
    r << std::endl;
    results.emplace(b.duration, r.str());
  };
  uint64_t index = 0;
  double elapsed = 0;
  const uint64_t last = log->last_frame();
  const auto& infos = log->actors();
  log->ForEach([&](const LogFrame& f) {
    ++index;
    elapsed = f.elapsed;
    // CARLA stores with each frame the time to the next one (-1 for the last frame).
    const double duration_this = f.frame < last ? log->SimTime(f.frame + 1) - f.sim_time : -1.0;
    for (uint32_t id : f.spawned) {
      auto it = infos.find(id);
      actors[id] = Blocked{it == infos.end() ? std::string() : it->second.blueprint, {0, 0, 0}, 0, 0};
    }
    for (uint32_t id : f.destroyed) actors.erase(id);
    for (const auto& s : f.actors) {
      if (!Positioned(s.kind)) continue;
      auto it = infos.find(s.id);
      const CarlaPose p = ToCarla(s, it == infos.end() ? nullptr : &it->second);
      Blocked& b = actors[s.id];
      const double d = std::sqrt((p.x - b.last[0]) * (p.x - b.last[0]) + (p.y - b.last[1]) * (p.y - b.last[1]) +
                                 (p.z - b.last[2]) * (p.z - b.last[2]));
      if (d < min_distance) {
        if (b.duration == 0) b.time = f.elapsed;
        b.duration += duration_this;
      } else {
        if (b.duration >= min_time) result(s.id, b);
        b.duration = 0;
        b.last[0] = p.x;
        b.last[1] = p.y;
        b.last[2] = p.z;
      }
    }
    return true;
  });
  for (const auto& [id, b] : actors) {
    if (b.duration >= min_time) result(id, b);
  }
  for (const auto& [d, line] : results) info << line;
  info << "\nFrames: " << index << "\n";
  info << "Duration: " << elapsed << " seconds\n";
  return info.str();
}

}  // namespace lockstep::recorder
