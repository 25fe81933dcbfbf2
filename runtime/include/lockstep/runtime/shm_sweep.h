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
ShmSweepResult SweepStaleShm(const std::string& dir = "/dev/shm", double min_age_s = 10);

}  // namespace lockstep::runtime
