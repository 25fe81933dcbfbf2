#include "lockstep/runtime/domain_lock.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <filesystem>
#include <stdexcept>
#include <string>

#include "lockstep/runtime/error.h"

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

int HoldSimulationDomain(int domain, const std::string& what) {
  const std::string path = std::filesystem::temp_directory_path() / ("lockstep-domain-" + std::to_string(domain) + ".lock");
  const int fd = open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0666);
  if (fd < 0) throw InputError("cannot open " + path + " to hold DDS domain " + std::to_string(domain));
  if (flock(fd, LOCK_EX | LOCK_NB) != 0) {
    char holder[512] = {0};
    const ssize_t n = pread(fd, holder, sizeof holder - 1, 0);
    close(fd);
    std::string who = n > 0 ? std::string(holder, static_cast<size_t>(n)) : std::string("another process");
    while (!who.empty() && (who.back() == '\n' || who.back() == ' ')) who.pop_back();
    throw InputError("DDS domain " + std::to_string(domain) + " is in use on this host by " + who +
                     "; two simulations on one domain would hear each other's ticks, acks and commands: stop it, or "
                     "choose another domain (--domain N or the config's domain_id)");
  }
  const std::string text = "pid " + std::to_string(getpid()) + ": " + what + "\n";
  if (ftruncate(fd, 0) != 0 || pwrite(fd, text.data(), text.size(), 0) != static_cast<ssize_t>(text.size())) {
    // The lock holds without the text; a refused second run then names "another process".
  }
  return fd;
}

}  // namespace lockstep
