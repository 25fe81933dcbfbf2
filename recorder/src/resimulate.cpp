#include "lockstep/recorder/resimulate.h"

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>

#include "lockstep/recorder/log_writer.h"
#include "lockstep/runtime/hash.h"
#include "lockstep/runtime/messages.h"

namespace lockstep::recorder {
namespace {

std::string ReadText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw LogError("cannot read " + path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string Hex(uint64_t v) {
  char buf[24];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(v));
  return buf;
}

// What a re-simulation changes in a recorded command: no client ticks it, so recorded
// world settings run free at full speed.
void Normalise(msg::Command* c) {
  if (c->body()._d() != msg::CommandKind::CMD_SET_WORLD_SETTINGS) return;
  auto& s = c->body().world_settings();
  s.synchronous_mode(false);
  s.real_time_factor(0);
}

const char* KindName(msg::CommandKind k) {
  switch (k) {
    case msg::CommandKind::CMD_SPAWN_ACTOR: return "spawn_actor";
    case msg::CommandKind::CMD_DESTROY_ACTOR: return "destroy_actor";
    case msg::CommandKind::CMD_SET_TRANSFORM: return "set_transform";
    case msg::CommandKind::CMD_VEHICLE_CONTROL: return "vehicle_control";
    case msg::CommandKind::CMD_WALKER_CONTROL: return "walker_control";
    case msg::CommandKind::CMD_DRONE: return "drone";
    case msg::CommandKind::CMD_TRAFFIC_LIGHT: return "traffic_light";
    case msg::CommandKind::CMD_TRAFFIC_MANAGER: return "traffic_manager";
    case msg::CommandKind::CMD_SET_WEATHER: return "set_weather";
    case msg::CommandKind::CMD_SET_WORLD_SETTINGS: return "world_settings";
    case msg::CommandKind::CMD_RECORDER: return "recorder";
    default: return "command";
  }
}

std::string Describe(const msg::Command& c) {
  return std::string(KindName(c.body()._d())) + " from '" + c.client().to_string() + "' #" + std::to_string(c.sequence_number());
}

// Why two ticks differ (the same frame), "" if they do not.
std::string TickDifference(msg::Tick recorded, const msg::Tick& now) {
  recorded.run(now.run());
  for (auto& c : recorded.commands()) Normalise(&c);
  if (ToCdr(recorded) == ToCdr(now)) return {};
  if (recorded.commands().size() != now.commands().size()) {
    std::string r = "the tick has " + std::to_string(now.commands().size()) + " commands, the log's " +
                    std::to_string(recorded.commands().size());
    const size_t n = std::min(recorded.commands().size(), now.commands().size());
    for (size_t i = 0; i < n; ++i) {
      if (ToCdr(recorded.commands()[i]) != ToCdr(now.commands()[i])) {
        return r + "; the first that differs is command " + std::to_string(i) + ": " + Describe(now.commands()[i]) + " (log: " +
               Describe(recorded.commands()[i]) + ")";
      }
    }
    return r;
  }
  for (size_t i = 0; i < now.commands().size(); ++i) {
    if (ToCdr(recorded.commands()[i]) != ToCdr(now.commands()[i])) {
      return "command " + std::to_string(i) + " (" + Describe(now.commands()[i]) + ") differs from the log's";
    }
  }
  if (recorded.dt() != now.dt()) return "dt " + std::to_string(now.dt()) + " s, the log's " + std::to_string(recorded.dt()) + " s";
  if (recorded.sim_time() != now.sim_time()) return "sim time differs from the log's";
  if (recorded.seed() != now.seed()) return "seed " + std::to_string(now.seed()) + ", the log's " + std::to_string(recorded.seed());
  return "the tick differs from the log's";
}

}  // namespace

uint64_t MapDigest(const std::string& xodr_path) {
  if (xodr_path.empty()) return Fnv1a64().Add(std::string_view()).Add(std::string_view()).value();
  const std::filesystem::path p(xodr_path);
  const std::filesystem::path scene = p.parent_path() / (p.stem().string() + ".scene.yaml");
  const std::string od = ReadText(xodr_path);
  const std::string sc = std::filesystem::exists(scene) ? ReadText(scene.string()) : std::string();
  return Fnv1a64().Add(std::string_view(od)).Add(std::string_view(sc)).value();
}

std::string ResimulationRefusal(const LogReader& log, const LaunchConfig& config) {
  const LogHeader& h = log.header();
  if (log.empty()) return "the log has no whole frame";
  uint64_t digest = 0;
  try {
    digest = MapDigest(config.map);
  } catch (const std::exception& e) {
    return std::string("the config's map cannot be read: ") + e.what();
  }
  const std::string config_map = config.map.empty() ? "(none)" : std::filesystem::path(config.map).stem().string();
  if (digest != h.map_digest) {
    return "the log was recorded on map '" + h.map_name + "' (digest " + Hex(h.map_digest) + "), the config loads '" + config_map +
           "' (digest " + Hex(digest) + ")";
  }
  if (h.seed != config.seed) {
    return "the log's run used seed " + std::to_string(h.seed) + ", the config's seed is " + std::to_string(config.seed);
  }
  std::vector<std::string> logged;
  for (const auto& s : h.world.required_services()) logged.push_back(s.to_string());
  std::vector<std::string> configured = config.RequiredServices();
  std::sort(logged.begin(), logged.end());
  std::sort(configured.begin(), configured.end());
  if (logged != configured) {
    auto join = [](const std::vector<std::string>& v) {
      std::string out;
      for (const auto& s : v) out += (out.empty() ? "" : ", ") + s;
      return out;
    };
    return "the log's services are [" + join(logged) + "], the config's [" + join(configured) + "]";
  }
  for (const auto& s : h.services) {
    for (const auto& c : config.services) {
      if (c.name == s.name && !s.kind.empty() && c.kind != s.kind) {
        return "service '" + s.name + "' is a " + s.kind + " in the log, a " + c.kind + " in the config";
      }
    }
  }
  if (log.first_frame() > 1 && h.prelude_frames + 1 != log.first_frame()) {
    return "the log starts at frame " + std::to_string(log.first_frame()) +
           " of its run without the ticks before it (the recorder joined mid-run, or they exceeded its prelude limit)";
  }
  return {};
}

LaunchConfig ResimulationConfig(LogReader& log, const LaunchConfig& config) {
  if (auto why = ResimulationRefusal(log, config); !why.empty()) throw LogError("cannot re-simulate " + log.path() + ": " + why);
  LaunchConfig c = config;
  c.ticks = log.last_frame();
  c.world.synchronous_mode(false);
  c.world.real_time_factor(0);
  c.scenario.clear();
  auto add = [&](const msg::Tick& t) {
    for (const auto& cmd : t.commands()) {
      ScheduledCommand s;
      s.frame = t.frame();
      s.command = cmd;
      Normalise(&s.command);
      c.scenario.push_back(std::move(s));
    }
  };
  for (const auto& t : log.header().prelude) {
    if (t.frame() < log.first_frame()) add(t);
  }
  log.ForEachTick(log.first_frame(), log.last_frame(), [&](uint64_t, const std::string& cdr, const std::optional<FrameHashes>&) {
    add(FromCdr<msg::Tick>(cdr.data(), cdr.size()));
    return true;
  });
  return c;
}

struct ResimulationCheck::Impl {
  uint64_t first = 0, last = 0;
  std::vector<std::string> ticks;                     // recorded tick CDR by frame - first
  std::vector<std::optional<FrameHashes>> hashes;     // recorded hashes by frame - first
  std::mutex mu;
  std::condition_variable cv;
  std::map<uint64_t, std::string> tick_diff;          // frame -> why its tick differs
  std::map<uint64_t, uint64_t> done;                  // frame -> world hash
  std::map<uint64_t, std::map<std::string, uint64_t>> acks;
  uint64_t max_done = 0;
  Reader<msg::Tick> tick_reader;
  Reader<msg::Ack> ack_reader;
  Reader<msg::FrameDone> done_reader;

  Impl(Bus& bus, LogReader& log, std::vector<std::string> recorded_ticks, std::vector<std::optional<FrameHashes>> recorded_hashes)
      : first(log.first_frame()),
        last(log.last_frame()),
        ticks(std::move(recorded_ticks)),
        hashes(std::move(recorded_hashes)),
        tick_reader(bus, topics::kTick,
                    [this](const msg::Tick& t, const SampleInfo&) {
                      if (t.frame() < first || t.frame() > last) return;
                      const std::string& bytes = ticks[t.frame() - first];
                      std::string why = TickDifference(FromCdr<msg::Tick>(bytes.data(), bytes.size()), t);
                      if (why.empty()) return;
                      std::lock_guard<std::mutex> lock(mu);
                      tick_diff.emplace(t.frame(), std::move(why));
                      cv.notify_all();
                    }),
        ack_reader(bus, topics::kAck,
                   [this](const msg::Ack& a, const SampleInfo&) {
                     std::lock_guard<std::mutex> lock(mu);
                     acks[a.frame()][a.service().to_string()] = a.state_hash();
                   }),
        done_reader(bus, topics::kFrameDone, [this](const msg::FrameDone& d, const SampleInfo&) {
          {
            std::lock_guard<std::mutex> lock(mu);
            done[d.frame()] = d.world_hash();
            max_done = std::max(max_done, d.frame());
          }
          cv.notify_all();
        }) {}
};

ResimulationCheck::ResimulationCheck(Bus& bus, LogReader& log) {
  // The recorded ticks first: the readers' callbacks compare against them.
  std::vector<std::string> ticks;
  std::vector<std::optional<FrameHashes>> hashes;
  log.ForEachTick(log.first_frame(), log.last_frame(), [&](uint64_t, const std::string& cdr, const std::optional<FrameHashes>& h) {
    ticks.push_back(cdr);
    hashes.push_back(h);
    return true;
  });
  impl_ = std::make_unique<Impl>(bus, log, std::move(ticks), std::move(hashes));
}

ResimulationCheck::~ResimulationCheck() = default;

ResimulationResult ResimulationCheck::Wait(double timeout_s, const std::atomic<bool>& stop,
                                           const std::function<void(uint64_t, uint64_t)>& progress) {
  Impl& m = *impl_;
  ResimulationResult r;
  const auto timeout = std::chrono::duration<double>(timeout_s);
  const uint64_t total = m.last - m.first + 1;
  for (uint64_t k = m.first; k <= m.last; ++k) {
    std::unique_lock<std::mutex> lock(m.mu);
    auto last_progress = std::chrono::steady_clock::now();
    while (!m.done.count(k) && m.max_done <= k && !m.tick_diff.count(k) && !stop) {
      m.cv.wait_for(lock, std::chrono::milliseconds(100));
      if (std::chrono::steady_clock::now() - last_progress > timeout) {
        r.reason = "no frame " + std::to_string(k) + " of the re-simulation within " + std::to_string(timeout_s) + " s";
        return r;
      }
    }
    if (stop) {
      r.reason = "stopped at frame " + std::to_string(k);
      return r;
    }
    if (auto it = m.tick_diff.find(k); it != m.tick_diff.end()) {
      r.first_differing = k;
      r.reason = "the tick of frame " + std::to_string(k) + " differs: " + it->second;
      return r;
    }
    const auto& want = m.hashes[k - m.first];
    auto got = m.done.find(k);
    if (!want || got == m.done.end()) {
      ++r.frames_unchecked;
    } else if (got->second != want->world_hash) {
      r.first_differing = k;
      r.reason = "frame " + std::to_string(k) + ": world hash " + Hex(got->second) + ", the log's " + Hex(want->world_hash);
      const auto& a = m.acks[k];
      for (const auto& [service, hash] : want->services) {
        auto s = a.find(service);
        if (s != a.end() && s->second != hash) {
          r.service = service;
          r.reason += "; service '" + service + "' state hash " + Hex(s->second) + ", the log's " + Hex(hash);
          break;
        }
      }
      return r;
    } else {
      ++r.frames_checked;
    }
    m.done.erase(m.done.begin(), m.done.upper_bound(k));
    m.acks.erase(m.acks.begin(), m.acks.upper_bound(k));
    lock.unlock();
    if (progress && ((k - m.first) % 64 == 0 || k == m.last)) progress(k - m.first + 1, total);
  }
  return r;
}

}  // namespace lockstep::recorder
