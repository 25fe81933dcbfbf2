#pragma once
// The missing-input check every service's test makes (GroundInputs, AirInputs,
// SensorsInputs): a step whose input did not come throws MissingInput naming it, and the
// service's state is as it was before the step.
#include <gtest/gtest.h>

#include <string>

#include "lockstep/runtime/service.h"

namespace lockstep::testing {

// Steps `core` with `tick`; expects MissingInput whose message contains `names` and an
// unchanged state hash.
inline void ExpectMissingInput(ServiceCore& core, const msg::Tick& tick, const std::string& names) {
  const uint64_t hash = core.StateHash();
  try {
    core.Step(tick);
    ADD_FAILURE() << "frame " << tick.frame() << " stepped without its input (" << names << ")";
  } catch (const MissingInput& e) {
    EXPECT_NE(std::string(e.what()).find(names), std::string::npos) << e.what();
  }
  EXPECT_EQ(core.StateHash(), hash) << "the failed step changed the state";
}

}  // namespace lockstep::testing
