#include "lockstep/runtime/error.h"

#include <cstdio>
#include <cstdlib>

namespace lockstep {

void DemandFailed(const char* condition, const char* file, int line) {
  std::fprintf(stderr, "lockstep: internal check failed: %s at %s:%d\n", condition, file, line);
  std::abort();
}

}  // namespace lockstep
