// The tick log's rule (runtime/tick_log.h), which the coordinator (append, trim) and a
// replacement's replay (Cursor) share: what is kept, what is forgotten, what is inferred.
#include <gtest/gtest.h>

#include "lockstep/runtime/tick_log.h"

namespace lockstep {
namespace {

msg::Tick TickOf(uint64_t frame, double dt, bool command = false) {
  msg::Tick t;
  t.run(1);
  t.frame(frame);
  t.dt(dt);
  t.sim_time(dt * static_cast<double>(frame));
  if (command) {
    msg::Command c;
    c.sequence_number(frame);
    t.commands({c});
  }
  return t;
}

TEST(TickLog, KeepsWhatReplayCannotInferAndReplayGetsEveryTickBack) {
  std::vector<msg::Tick> all;
  for (uint64_t k = 1; k <= 10; ++k) all.push_back(TickOf(k, k <= 6 ? 0.05 : 0.1, k == 4));
  // sim_time as the coordinator advances it: by each tick's dt.
  for (size_t i = 1; i < all.size(); ++i) all[i].sim_time(all[i - 1].sim_time() + all[i].dt());
  std::vector<msg::Tick> log;
  for (const auto& t : all) ticklog::Append(&log, t);
  std::vector<uint64_t> kept;
  for (const auto& t : log) kept.push_back(t.frame());
  EXPECT_EQ(kept, (std::vector<uint64_t>{1, 4, 7})) << "the first, one with commands, one whose dt changed";
  ticklog::Cursor cursor(log);
  for (const auto& t : all) {
    const msg::Tick& r = cursor.At(t.frame());
    EXPECT_EQ(r.frame(), t.frame());
    EXPECT_EQ(r.commands().size(), t.commands().size()) << t.frame();
    EXPECT_DOUBLE_EQ(r.dt(), t.dt()) << t.frame();
    EXPECT_NEAR(r.sim_time(), t.sim_time(), 1e-12) << t.frame();
  }
  // A replacement that restores frame 5: the ticks up to 5 are forgotten, 6 is written out
  // in full (inferred from 4), and replay from 5 still gets every later tick back.
  uint64_t first_frame = 0;
  ticklog::Trim(&log, &first_frame, 5);
  EXPECT_EQ(first_frame, 5u);
  ASSERT_FALSE(log.empty());
  EXPECT_EQ(log.front().frame(), 6u);
  EXPECT_TRUE(log.front().commands().empty());
  ticklog::Cursor after(log);
  for (uint64_t k = 6; k <= 10; ++k) EXPECT_NEAR(after.At(k).sim_time(), all[k - 1].sim_time(), 1e-12) << k;
  ticklog::Trim(&log, &first_frame, 3);  // not after the first kept frame: nothing
  EXPECT_EQ(first_frame, 5u);
  EXPECT_EQ(log.front().frame(), 6u);
}

}  // namespace
}  // namespace lockstep
