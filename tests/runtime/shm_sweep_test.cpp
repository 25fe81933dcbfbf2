// The /dev/shm sweep removes exactly what a dead process left: unlocked participant
// segments, unmapped data-sharing histories and port rings; never what a living process
// holds. A fresh participant id is one no port ring is left of.
#include "lockstep/runtime/shm_sweep.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <thread>

#include "lockstep/runtime/bus.h"
#include "process.h"

namespace lockstep::runtime {
namespace {

namespace fs = std::filesystem;

class ShmSweep : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("lockstep-shm-sweep-" + std::to_string(getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  void Make(const std::string& name, size_t bytes = 4096) {
    std::ofstream(dir_ / name) << std::string(bytes, 'x');
  }
  bool Exists(const std::string& name) const { return fs::exists(dir_ / name); }
  fs::path dir_;
};

TEST_F(ShmSweep, RemovesASegmentWhoseLockNobodyHolds) {
  Make("fastrtps_00349cadf7280588", 100000);
  Make("fastrtps_00349cadf7280588_el", 0);
  const auto r = SweepStaleShm(dir_.string(), 0);
  EXPECT_FALSE(Exists("fastrtps_00349cadf7280588"));
  EXPECT_FALSE(Exists("fastrtps_00349cadf7280588_el"));
  EXPECT_EQ(r.removed_files, 2);
  EXPECT_EQ(r.removed_bytes, 100000u);
}

TEST_F(ShmSweep, KeepsASegmentWhoseLockIsHeld) {
  Make("fastrtps_aa", 10);
  Make("fastrtps_aa_el", 0);
  const int fd = open((dir_ / "fastrtps_aa_el").c_str(), O_RDONLY);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(flock(fd, LOCK_EX | LOCK_NB), 0);
  const auto r = SweepStaleShm(dir_.string(), 0);
  EXPECT_TRUE(Exists("fastrtps_aa"));
  EXPECT_TRUE(Exists("fastrtps_aa_el"));
  EXPECT_EQ(r.removed_files, 0);
  EXPECT_EQ(r.kept_live, 1);
  close(fd);
  SweepStaleShm(dir_.string(), 0);  // the holder is gone: now it goes
  EXPECT_FALSE(Exists("fastrtps_aa"));
}

TEST_F(ShmSweep, RemovesAPortRingNobodyMapsWithItsLockAndMutexAndLeavesOtherFiles) {
  Make("fastrtps_port7411");
  Make("fastrtps_port7411_el", 0);
  Make("sem.fastrtps_port7411_mutex");
  Make("fastrtps_port7413");  // a living participant's ring: mapped
  Make("sem.fastrtps_port7413_mutex");
  Make("someone_elses_segment");
  const int fd = open((dir_ / "fastrtps_port7413").c_str(), O_RDWR);
  ASSERT_GE(fd, 0);
  void* map = mmap(nullptr, 4096, PROT_READ, MAP_SHARED, fd, 0);
  ASSERT_NE(map, MAP_FAILED);
  close(fd);
  const auto r = SweepStaleShm(dir_.string(), 0);
  EXPECT_EQ(r.removed_files, 3);
  EXPECT_FALSE(Exists("fastrtps_port7411"));
  EXPECT_FALSE(Exists("fastrtps_port7411_el"));
  EXPECT_FALSE(Exists("sem.fastrtps_port7411_mutex"));
  EXPECT_TRUE(Exists("fastrtps_port7413"));
  EXPECT_TRUE(Exists("sem.fastrtps_port7413_mutex"));
  EXPECT_TRUE(Exists("someone_elses_segment"));
  munmap(map, 4096);
}

TEST_F(ShmSweep, KeepsABrandNewPortRing) {
  Make("fastrtps_port7411");
  SweepStaleShm(dir_.string(), 3600);  // a participant may be about to map it
  EXPECT_TRUE(Exists("fastrtps_port7411"));
}

// Domain 2: metatraffic unicast port 7400 + 250 * 2 + 10 + 2 * id, user port one above.
TEST_F(ShmSweep, AFreshParticipantIdHasNoPortRingLeft) {
  EXPECT_EQ(FreshParticipantId(2, dir_.string()), 0);
  Make("fastrtps_port7910");  // id 0, metatraffic
  Make("fastrtps_port7913");  // id 1, user traffic only (its other ring swept or not yet made)
  Make("fastrtps_port7664");  // domain 1: no matter
  EXPECT_EQ(FreshParticipantId(2, dir_.string()), 2);
  EXPECT_EQ(FreshParticipantId(1, dir_.string()), 0);
  EXPECT_EQ(FreshParticipantId(233, dir_.string()), -1) << "no valid port: Fast DDS picks";
}

TEST_F(ShmSweep, RemovesAnUnmappedDataSharingHistoryButNotAMappedOne) {
  Make("fast_datasharing_01.0f.78.fd_0.0.12.3", 8192);
  Make("fast_datasharing_01.0f.aa.bb_0.0.12.3", 8192);
  const int fd = open((dir_ / "fast_datasharing_01.0f.aa.bb_0.0.12.3").c_str(), O_RDWR);
  ASSERT_GE(fd, 0);
  void* map = mmap(nullptr, 8192, PROT_READ, MAP_SHARED, fd, 0);
  ASSERT_NE(map, MAP_FAILED);
  close(fd);  // the mapping alone keeps it alive
  const auto r = SweepStaleShm(dir_.string(), 0);
  EXPECT_FALSE(Exists("fast_datasharing_01.0f.78.fd_0.0.12.3"));
  EXPECT_TRUE(Exists("fast_datasharing_01.0f.aa.bb_0.0.12.3"));
  EXPECT_EQ(r.removed_files, 1);
  munmap(map, 8192);
}

TEST_F(ShmSweep, KeepsABrandNewDataSharingHistory) {
  Make("fast_datasharing_01.0f.78.fd_0.0.12.3");
  SweepStaleShm(dir_.string(), 3600);  // younger than an hour: a writer may be about to map it
  EXPECT_TRUE(Exists("fast_datasharing_01.0f.78.fd_0.0.12.3"));
}

std::set<std::string> LockFiles() {
  std::set<std::string> out;
  for (const auto& e : fs::directory_iterator("/dev/shm")) {
    const std::string n = e.path().filename().string();
    if (n.rfind("fastrtps_", 0) == 0 && n.rfind("fastrtps_port", 0) != 0 && n.size() > 3 &&
        n.compare(n.size() - 3, 3, "_el") == 0)
      out.insert(n);
  }
  return out;
}

// The criterion is Fast DDS's own: a real participant's segment is kept while it lives
// and removed once it was killed with SIGKILL.
TEST(ShmSweepFastDds, RemovesTheSegmentOfAKilledParticipantAndKeepsALiveOnes) {
  if (!fs::exists("/dev/shm")) GTEST_SKIP() << "no /dev/shm";
  int ready[2];
  ASSERT_EQ(pipe(ready), 0);
  const auto before = LockFiles();
  const int domain = lockstep::testing::TestDomain();
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    close(ready[0]);
    auto bus = CreateDdsBus({domain, "", "lockstep.participant", "shm-sweep-victim"});
    const char ok = 1;
    if (write(ready[1], &ok, 1) != 1) _exit(3);
    pause();
    _exit(0);
  }
  close(ready[1]);
  char ok = 0;
  ASSERT_EQ(read(ready[0], &ok, 1), 1);
  close(ready[0]);
  // The child's own lock files: those /proc/locks says its pid holds (other tests may
  // be creating and removing participants meanwhile).
  std::set<unsigned long> inodes;
  std::ifstream locks("/proc/locks");
  std::string line;
  while (std::getline(locks, line)) {
    std::istringstream in(line);
    std::string id, kind, advisory, mode, dev_ino;
    long pid = 0;
    in >> id >> kind >> advisory >> mode >> pid >> dev_ino;
    if (kind == "FLOCK" && pid == child) inodes.insert(std::stoul(dev_ino.substr(dev_ino.rfind(':') + 1)));
  }
  std::set<std::string> victims;
  for (const auto& n : LockFiles()) {
    struct stat st {};
    if (!before.count(n) && stat(("/dev/shm/" + n).c_str(), &st) == 0 && inodes.count(st.st_ino)) victims.insert(n);
  }
  ASSERT_FALSE(victims.empty()) << "the participant created no SHM segment";

  SweepStaleShm("/dev/shm");  // alive: kept
  for (const auto& n : victims) EXPECT_TRUE(fs::exists("/dev/shm/" + n)) << n;

  kill(child, SIGKILL);
  int st = 0;
  waitpid(child, &st, 0);
  SweepStaleShm("/dev/shm");
  for (const auto& n : victims) {
    EXPECT_FALSE(fs::exists("/dev/shm/" + n)) << n;
    EXPECT_FALSE(fs::exists("/dev/shm/" + n.substr(0, n.size() - 3))) << n;
  }
}

}  // namespace
}  // namespace lockstep::runtime
