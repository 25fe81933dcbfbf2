#include "lockstep/coordinator/tick_barrier.h"

#include <gtest/gtest.h>

namespace lockstep {
namespace {

using R = TickBarrier::AckResult;

TEST(TickBarrier, CompletesOnlyWhenEveryRequiredServiceAcked) {
  TickBarrier b;
  b.Open(1, 5, {"air", "ground", "render"});
  EXPECT_FALSE(b.Complete());
  EXPECT_EQ(b.OnAck("ground", 1, 5, 11), R::kCounted);
  EXPECT_EQ(b.OnAck("air", 1, 5, 22), R::kCounted);
  EXPECT_FALSE(b.Complete());
  EXPECT_EQ(b.Missing(), std::vector<std::string>{"render"});
  EXPECT_EQ(b.OnAck("render", 1, 5, 33), R::kCounted);
  EXPECT_TRUE(b.Complete());
}

TEST(TickBarrier, AnAckIsCountedOnce) {
  TickBarrier b;
  b.Open(1, 1, {"a", "b"});
  EXPECT_EQ(b.OnAck("a", 1, 1, 0), R::kCounted);
  EXPECT_EQ(b.OnAck("a", 1, 1, 0), R::kDuplicate);
  EXPECT_EQ(b.OnAck("a", 1, 1, 0), R::kDuplicate);
  EXPECT_FALSE(b.Complete()) << "duplicates of 'a' must not stand in for 'b'";
  EXPECT_EQ(b.OnAck("b", 1, 1, 0), R::kCounted);
  EXPECT_TRUE(b.Complete());
}

TEST(TickBarrier, StaleAndForeignAcksAreIgnored) {
  TickBarrier b;
  b.Open(2, 7, {"a"});
  EXPECT_EQ(b.OnAck("a", 2, 6, 0), R::kStale);      // previous frame
  EXPECT_EQ(b.OnAck("a", 1, 7, 0), R::kStale);      // previous run
  EXPECT_EQ(b.OnAck("viewer", 2, 7, 0), R::kNotRequired);
  EXPECT_FALSE(b.Complete());
  EXPECT_EQ(b.OnAck("a", 2, 7, 0), R::kCounted);
  EXPECT_TRUE(b.Complete());
  b.Close();
  EXPECT_EQ(b.OnAck("a", 2, 7, 0), R::kStale);
}

TEST(TickBarrier, WorldHashDependsOnEveryStateAndNotOnAckOrder) {
  TickBarrier x, y, z;
  x.Open(1, 1, {"a", "b"});
  y.Open(1, 1, {"b", "a"});
  z.Open(1, 1, {"a", "b"});
  x.OnAck("a", 1, 1, 1);
  x.OnAck("b", 1, 1, 2);
  y.OnAck("b", 1, 1, 2);
  y.OnAck("a", 1, 1, 1);
  z.OnAck("a", 1, 1, 1);
  z.OnAck("b", 1, 1, 3);
  EXPECT_EQ(x.WorldHash(), y.WorldHash());
  EXPECT_NE(x.WorldHash(), z.WorldHash());
}

}  // namespace
}  // namespace lockstep
