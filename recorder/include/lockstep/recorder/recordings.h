#pragma once
// Where logs live: header-only, so the coordinator (which resolves a client's
// start_recorder name into the path it answers) needs no recorder library.
#include <cstdlib>
#include <filesystem>
#include <string>

namespace lockstep::recorder {

// The recordings folder: $LOCKSTEP_RECORDINGS_DIR, else ~/.local/share/lockstep/recordings
// ($HOME; /tmp/lockstep-recordings without one). The same default on the client and the
// server, so a name given to start_recorder is found again by show_recorder_* (CARLA's
// server "Saved" folder).
inline std::string RecordingsDir() {
  if (const char* d = std::getenv("LOCKSTEP_RECORDINGS_DIR"); d != nullptr && *d != '\0') return d;
  if (const char* h = std::getenv("HOME"); h != nullptr && *h != '\0') return std::string(h) + "/.local/share/lockstep/recordings";
  return "/tmp/lockstep-recordings";
}

// `name` as a log path: an absolute name stays, a relative one resolves in RecordingsDir().
inline std::string ResolveLogPath(const std::string& name) {
  const std::filesystem::path p(name);
  if (p.is_absolute()) return p.lexically_normal().string();
  return (std::filesystem::path(RecordingsDir()) / p).lexically_normal().string();
}

}  // namespace lockstep::recorder
