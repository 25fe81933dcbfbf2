#include "progress.h"

#include <unistd.h>

#include <chrono>
#include <cstdio>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>
#include <system_error>

namespace lockstep::launcher {
namespace {

std::string Printf(const char* fmt, auto... args) {
  char buf[512];
  std::snprintf(buf, sizeof buf, fmt, args...);
  return buf;
}

std::string Duration(double s) {
  if (s < 0) s = 0;
  const auto total = static_cast<long>(s + 0.5);
  if (total < 60) return Printf("%lds", total);
  if (total < 3600) return Printf("%ldm%02lds", total / 60, total % 60);
  return Printf("%ldh%02ldm", total / 3600, (total % 3600) / 60);
}

std::string Bytes(uint64_t b) {
  if (b < 1024) return Printf("%llu B", static_cast<unsigned long long>(b));
  if (b < (1u << 20)) return Printf("%.1f KiB", b / 1024.0);
  if (b < (1u << 30)) return Printf("%.1f MiB", b / 1048576.0);
  return Printf("%.2f GiB", b / 1073741824.0);
}

}  // namespace

std::string FormatProgress(const Progress& p, bool bar, size_t width) {
  std::string figures;
  const double rate = p.wall_s > 0 ? p.frame / p.wall_s : 0;
  if (p.total > 0) {
    const double share = std::min(1.0, static_cast<double>(p.frame) / static_cast<double>(p.total));
    const double eta = p.tick_rate_hz > 0 ? static_cast<double>(p.total - std::min(p.total, p.frame)) / p.tick_rate_hz : -1;
    figures = Printf("%3.0f%% frame %llu/%llu, sim %.1f s, %.1f ticks/s, %s elapsed", share * 100,
                     static_cast<unsigned long long>(p.frame), static_cast<unsigned long long>(p.total), p.sim_time,
                     p.tick_rate_hz > 0 ? p.tick_rate_hz : rate, Duration(p.wall_s).c_str());
    if (eta >= 0) {
      figures += ", ";
      figures += Duration(eta);
      figures += " left";
    }
  } else {
    figures = Printf("frame %llu, sim %.1f s, %.1f ticks/s, %s elapsed", static_cast<unsigned long long>(p.frame), p.sim_time,
                     p.tick_rate_hz > 0 ? p.tick_rate_hz : rate, Duration(p.wall_s).c_str());
  }
  if (!p.state.empty() && p.state != "running") {
    figures += " [";
    figures += p.state;
    figures += "]";
  }
  std::string line;
  if (bar && p.total > 0) {
    const double share = std::min(1.0, static_cast<double>(p.frame) / static_cast<double>(p.total));
    const size_t room = width > figures.size() + 4 ? std::min<size_t>(30, width - figures.size() - 4) : 0;
    if (room >= 5) {
      const auto filled = static_cast<size_t>(share * static_cast<double>(room) + 1e-9);
      line.push_back('[');
      line.append(filled, '#');
      line.append(room - filled, '.');
      line.append("] ");
    }
  }
  line += figures;
  if (line.size() > width) line.resize(width);
  return line;
}

bool PlainLineDue(uint64_t frame, uint64_t total, uint64_t last_reported) {
  const uint64_t step = total > 0 ? std::max<uint64_t>(1, total / 10) : 500;
  return frame / step > last_reported / step;
}

std::vector<OutputGroup> ScanOutputs(const std::string& dir) {
  namespace fs = std::filesystem;
  std::map<std::string, OutputGroup> groups;
  std::error_code ec;
  const fs::path root(dir);
  for (auto it = fs::recursive_directory_iterator(root, ec); !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
    if (!it->is_regular_file(ec)) continue;
    const fs::path rel = fs::relative(it->path(), root, ec).parent_path();
    fs::path key;
    int depth = 0;
    for (const auto& part : rel) {
      if (depth++ == 2) break;
      key /= part;
    }
    const std::string name = key.empty() ? "." : key.string();
    auto& g = groups[name];
    g.path = name;
    ++g.files;
    g.bytes += it->file_size(ec);
  }
  std::vector<OutputGroup> out;
  for (auto& [k, g] : groups) out.push_back(g);
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.bytes != b.bytes ? a.bytes > b.bytes : a.path < b.path; });
  return out;
}

std::string FormatSummary(const Summary& s) {
  std::string out = "\n== summary of '";
  out += s.name;
  out += "' ==\n";
  out += Printf("run      %s after %llu frame(s): %.2f s simulated in %.2f s of wall time", s.state.c_str(),
                static_cast<unsigned long long>(s.frames), s.sim_time, s.wall_s);
  if (s.wall_s > 0) out += Printf(" (%.1f ticks/s, real-time factor %.2f)", s.frames / s.wall_s, s.sim_time / s.wall_s);
  out += "\n";
  if (!s.failure.empty()) {
    out += "failure  ";
    out += s.failure;
    out += "\n";
  }
  if (!s.members.empty()) {
    out += Printf("%-20s %-12s %12s %14s\n", "service", "kind", "last frame", "last step (ms)");
    for (const auto& m : s.members)
      out += Printf("%-20s %-12s %12llu %14.2f\n", m.service.c_str(), m.kind.c_str(), static_cast<unsigned long long>(m.last_frame),
                    m.last_step_us / 1000.0);
  }
  if (!s.output_dir.empty()) {
    uint64_t files = 0, bytes = 0;
    for (const auto& g : s.outputs) {
      files += g.files;
      bytes += g.bytes;
    }
    out += Printf("outputs  %s: %llu file(s), %s\n", s.output_dir.c_str(), static_cast<unsigned long long>(files), Bytes(bytes).c_str());
    for (const auto& g : s.outputs)
      out += Printf("  %-48s %8llu file(s) %12s\n", g.path.c_str(), static_cast<unsigned long long>(g.files), Bytes(g.bytes).c_str());
  }
  for (const auto& [file, text] : s.service_summaries) {
    out += "-- ";
    out += file;
    out += "\n";
    out += text;
    if (!text.empty() && text.back() != '\n') out += "\n";
  }
  return out;
}

namespace {
double NowS() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
}  // namespace

WorkProgress::WorkProgress(std::string what, uint64_t total)
    : what_(std::move(what)), total_(total), terminal_(isatty(STDERR_FILENO) != 0), start_s_(NowS()) {}

void WorkProgress::Update(uint64_t done, double sim_time) {
  const double now = NowS();
  Progress p{done, total_, sim_time, now - start_s_, 0, ""};
  if (terminal_) {
    if (now - last_draw_s_ < 0.1 && done < total_) return;
    last_draw_s_ = now;
    std::fprintf(stderr, "\r%s: %s\033[K", what_.c_str(), FormatProgress(p, true, 100).c_str());
    drawn_ = true;
  } else if (PlainLineDue(done, total_, last_plain_)) {
    last_plain_ = done;
    std::fprintf(stderr, "%s: %s\n", what_.c_str(), FormatProgress(p, false, 200).c_str());
  }
  std::fflush(stderr);
}

void WorkProgress::Done() {
  if (drawn_) std::fprintf(stderr, "\n");
  drawn_ = false;
  std::fflush(stderr);
}

}  // namespace lockstep::launcher
