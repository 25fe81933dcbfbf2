#include "process.h"

#include "lockstep/runtime/domain_lock.h"

#include <fcntl.h>
#include <poll.h>
#include <sys/file.h>
#include <sys/syscall.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <thread>

namespace lockstep::testing {

std::string BinDir() { return LOCKSTEP_TEST_BIN_DIR; }
std::string Bin(const std::string& name) { return BinDir() + "/" + name; }
std::string SourceDir() { return LOCKSTEP_TEST_SOURCE_DIR; }

// The lock files are shared with the Python tests and the benchmarks.
int TestDomain() { return LockFreeDdsDomain(); }

static std::string TempDir() {
  static const std::string dir = [] {
    auto d = std::filesystem::temp_directory_path() / ("lockstep-test-" + std::to_string(getpid()));
    // An earlier test process with the same pid may have left its files here: a child's
    // log read before the child truncated it showed that process's output.
    std::filesystem::remove_all(d);
    std::filesystem::create_directories(d);
    return d.string();
  }();
  return dir;
}

std::string WriteTempFile(const std::string& name, const std::string& text) {
  const std::string path = TempDir() + "/" + name;
  std::ofstream(path) << text;
  return path;
}

Process::Process(std::vector<std::string> argv, const std::map<std::string, std::string>& env) {
  static std::atomic<int> counter{0};
  log_ = TempDir() + "/proc-" + std::to_string(counter++) + ".log";
  std::ofstream(log_, std::ios::trunc);  // empty before the child runs: Output() never shows a stale file
  pid_ = fork();
  if (pid_ < 0) throw std::runtime_error("fork failed");
  if (pid_ == 0) {
    int fd = open(log_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(fd, 1);
    dup2(fd, 2);
    setpgid(0, 0);
    for (const auto& [k, v] : env) setenv(k.c_str(), v.c_str(), 1);
    std::vector<char*> args;
    for (auto& a : argv) args.push_back(a.data());
    args.push_back(nullptr);
    execv(args[0], args.data());
    _exit(127);
  }
}

Process::~Process() {
  // SIGTERM first: a service that stops destroys its participants, and one killed with
  // SIGKILL leaves its shared-memory segments in /dev/shm.
  if (Running()) {
    kill(pid_, SIGTERM);
    if (!Wait(std::chrono::seconds(3))) {
      kill(pid_, SIGKILL);
      Wait(std::chrono::seconds(5));
    }
  }
}

void Process::Signal(int sig) { kill(pid_, sig); }

bool Process::Running() {
  if (status_) return false;
  int st = 0;
  pid_t r = waitpid(pid_, &st, WNOHANG);
  if (r == pid_) {
    status_ = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
    return false;
  }
  return true;
}

std::optional<int> Process::Wait(std::chrono::milliseconds timeout) {
  // waitpid has no timeout; a pidfd becomes readable when the child exits.
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  const int fd = static_cast<int>(syscall(SYS_pidfd_open, pid_, 0));
  while (Running()) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) break;
    if (fd >= 0) {
      pollfd p{fd, POLLIN, 0};
      poll(&p, 1, static_cast<int>(left.count()));
    } else {
      std::this_thread::sleep_for(std::min(left, std::chrono::milliseconds(5)));  // kernels without pidfd
    }
  }
  if (fd >= 0) close(fd);
  if (Running()) return std::nullopt;
  return status_;
}

std::string Process::Output() const {
  std::ifstream in(log_);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace lockstep::testing
