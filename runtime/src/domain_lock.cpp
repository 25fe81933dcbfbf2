#include "lockstep/runtime/domain_lock.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <filesystem>
#include <stdexcept>
#include <string>

namespace lockstep {

int LockFreeDdsDomain() {
  static const int domain = [] {
    const int start = static_cast<int>(getpid() % 200);
    for (int i = 0; i < 200; ++i) {
      const int d = 1 + (start + i) % 200;
      const std::string path = std::filesystem::temp_directory_path() / ("lockstep-test-domain-" + std::to_string(d) + ".lock");
      const int fd = open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0666);
      if (fd < 0) continue;
      if (flock(fd, LOCK_EX | LOCK_NB) == 0) return d;  // fd stays open: the lock lives with the process
      close(fd);
    }
    throw std::runtime_error("no free DDS domain: all 200 lock files are held");
  }();
  return domain;
}

}  // namespace lockstep
