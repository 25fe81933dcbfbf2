#include "lockstep/runtime/shm_sweep.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <set>
#include <system_error>

namespace lockstep::runtime {
namespace {

namespace fs = std::filesystem;

bool StartsWith(const std::string& s, const std::string& p) { return s.rfind(p, 0) == 0; }
bool EndsWith(const std::string& s, const std::string& p) {
  return s.size() >= p.size() && s.compare(s.size() - p.size(), p.size(), p) == 0;
}

// True when some process holds the lock file (it may be ours: flock locks belong to an
// open file description, so our own second open conflicts with our first, too).
bool LockHeld(const fs::path& lock_file) {
  const int fd = open(lock_file.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return true;  // cannot tell: keep it
  const bool held = flock(fd, LOCK_EX | LOCK_NB) != 0;
  close(fd);  // releases the lock we may have taken
  return held;
}

// Every file path under `dir` that a process of this user maps, read from /proc/*/maps.
std::set<std::string> MappedFiles(const fs::path& dir) {
  std::set<std::string> mapped;
  const std::string prefix = dir.string() + "/";
  std::error_code ec;
  for (const auto& proc : fs::directory_iterator("/proc", ec)) {
    const std::string pid = proc.path().filename().string();
    if (pid.empty() || pid.find_first_not_of("0123456789") != std::string::npos) continue;
    std::ifstream maps(proc.path() / "maps");
    std::string line;
    while (std::getline(maps, line)) {
      const auto at = line.find(prefix);
      if (at == std::string::npos) continue;
      std::string path = line.substr(at);
      if (EndsWith(path, " (deleted)")) continue;
      mapped.insert(path);
    }
  }
  return mapped;
}

double AgeSeconds(const fs::path& file) {
  struct stat st {};
  if (stat(file.c_str(), &st) != 0) return 0;
  const double changed = static_cast<double>(st.st_ctim.tv_sec) + st.st_ctim.tv_nsec * 1e-9;
  const double now = std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
  return now - changed;
}

bool Ours(const fs::path& file) {
  struct stat st {};
  return stat(file.c_str(), &st) == 0 && st.st_uid == geteuid();
}

void Remove(const fs::path& file, ShmSweepResult& result) {
  std::error_code ec;
  const auto size = fs::file_size(file, ec);
  if (fs::remove(file, ec)) {
    ++result.removed_files;
    result.removed_bytes += ec ? 0 : size;
  }
}

}  // namespace

ShmSweepResult SweepStaleShm(const std::string& dir_name, double min_age_s) {
  ShmSweepResult result;
  const fs::path dir(dir_name);
  std::error_code ec;
  std::set<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir, ec)) names.insert(entry.path().filename().string());
  if (ec) return result;

  // Participant segments: `fastrtps_<hex>` with its lock `fastrtps_<hex>_el`. Port rings
  // (`fastrtps_port<N>`) come below.
  for (const auto& name : names) {
    if (!StartsWith(name, "fastrtps_") || !EndsWith(name, "_el") || StartsWith(name, "fastrtps_port")) continue;
    const fs::path lock = dir / name;
    const fs::path segment = dir / name.substr(0, name.size() - 3);
    if (!Ours(lock)) continue;
    if (LockHeld(lock)) {
      ++result.kept_live;
      continue;
    }
    Remove(segment, result);
    Remove(lock, result);
  }

  // Data-sharing histories and port rings: stale when unmapped and not brand new.
  std::set<std::string> mapped;
  bool scanned = false;
  for (const auto& name : names) {
    const bool port = StartsWith(name, "fastrtps_port") && !EndsWith(name, "_el");
    if (!StartsWith(name, "fast_datasharing_") && !port) continue;
    const fs::path file = dir / name;
    if (!Ours(file)) continue;
    if (!scanned) {
      mapped = MappedFiles(fs::canonical(dir, ec));
      scanned = true;
    }
    const std::string canonical = fs::canonical(file, ec).string();
    if (mapped.count(canonical) || AgeSeconds(file) < min_age_s) {
      ++result.kept_live;
      continue;
    }
    if (port) {
      // Its lock file and named mutex go with it, unless someone still uses the mutex.
      const fs::path sem = dir / ("sem." + name + "_mutex");
      if (fs::exists(sem, ec) && mapped.count(fs::canonical(sem, ec).string())) {
        ++result.kept_live;
        continue;
      }
      if (fs::exists(dir / (name + "_el"), ec)) Remove(dir / (name + "_el"), result);
      if (fs::exists(sem, ec)) Remove(sem, result);
    }
    Remove(file, result);
  }
  return result;
}

int FreshParticipantId(int domain, const std::string& dir_name) {
  // Fast DDS defaults: PB 7400, DG 250, PG 2, d1 10 (metatraffic), d3 11 (user unicast).
  // 120 ids fit in a domain's 250 ports.
  const fs::path dir(dir_name);
  std::error_code ec;
  for (int id = 0; id < 120; ++id) {
    const int meta = 7400 + 250 * domain + 10 + 2 * id;
    if (meta + 1 > 65535) break;
    const bool used = fs::exists(dir / ("fastrtps_port" + std::to_string(meta)), ec) ||
                      fs::exists(dir / ("fastrtps_port" + std::to_string(meta + 1)), ec);
    if (!used) return id;
  }
  return -1;
}

ParticipantIdLock::ParticipantIdLock(int domain) {
  const fs::path path = fs::temp_directory_path() / ("lockstep-participant-ids-" + std::to_string(domain) + ".lock");
  fd_ = open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0666);
  if (fd_ >= 0 && flock(fd_, LOCK_EX) != 0) {
    close(fd_);
    fd_ = -1;  // no lock: a rare collision is then caught by the join retry
  }
}

ParticipantIdLock::~ParticipantIdLock() {
  if (fd_ >= 0) close(fd_);  // releases the lock
}

}  // namespace lockstep::runtime
