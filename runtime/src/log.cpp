#include "lockstep/runtime/log.h"

#include <cstdlib>

namespace lockstep {

void InitLogging(const std::string& process_name) {
  spdlog::set_pattern("[" + process_name + "] %^%l%$: %v");
  const char* level = std::getenv("LOCKSTEP_LOG");
  spdlog::set_level(level ? spdlog::level::from_str(level) : spdlog::level::info);
}

}  // namespace lockstep
