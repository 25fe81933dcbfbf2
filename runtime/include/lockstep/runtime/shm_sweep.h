#pragma once
// Removes the shared-memory files that Fast DDS leaves in /dev/shm when a process dies
// without destroying its participants (SIGKILL, a crash, a test timeout). They are
// memory: a tmpfs file keeps its pages until it is unlinked, so a day of killed runs
// can fill the machine. Fast DDS itself never removes another process's segment.
#include <cstdint>
#include <string>

namespace lockstep::runtime {

struct ShmSweepResult {
  int removed_files = 0;
  std::uint64_t removed_bytes = 0;
  int kept_live = 0;  // files some living process still owns or maps
};

// A participant segment `fastrtps_<hex>` is stale when nobody holds the flock on its
// `fastrtps_<hex>_el` lock file (Fast DDS's own test, as `fastdds shm clean` does).
// A data-sharing history `fast_datasharing_*` has no lock file: it is stale when no
// process of ours maps it and it is older than `min_age_s` (a writer maps its file
// right after creating it). Files of other users are left alone.
// Port rings `fastrtps_port<N>` (with `fastrtps_port<N>_el` and the semaphore
// `sem.fastrtps_port<N>_mutex`) are removed when no process maps them and they are older
// than `min_age_s`: then no sender holds the old ring, and the next participant on that
// port creates a fresh one.
ShmSweepResult SweepStaleShm(const std::string& dir = "/dev/shm", double min_age_s = 10);

// A participant id on `domain` whose shared-memory ports (metatraffic and user unicast,
// Fast DDS's default port formula) have no ring in `dir`: no process, live or dead, used
// it since the last sweep, so no sender still writes into a ring of a dead process there.
// Fast DDS 2.9 gives a new participant the lowest free id, often the id of a participant
// killed with SIGKILL; the new one then recreates that port's ring while the live senders
// keep writing into the old one, and it hears nothing (Fast DDS issue 5469). -1: none left.
int FreshParticipantId(int domain, const std::string& dir = "/dev/shm");

// Serializes choosing a participant id and creating the participant among the processes
// of this machine on one domain (an exclusive flock on <tmp>/lockstep-participant-ids-<domain>.lock),
// so two processes starting at once do not pick the same fresh id.
class ParticipantIdLock {
 public:
  explicit ParticipantIdLock(int domain);
  ~ParticipantIdLock();
  ParticipantIdLock(const ParticipantIdLock&) = delete;
  ParticipantIdLock& operator=(const ParticipantIdLock&) = delete;

 private:
  int fd_ = -1;
};

}  // namespace lockstep::runtime
