// Large sensor payloads reach the client without a copy: a TakingReader hands over the
// received sample, SamplePool swaps it with a recycled object, and a sample that is
// still in use (a numpy view) is never overwritten by the ones after it. Over Fast DDS
// (the take path) and over the in-process bus (which shares samples between readers).
#include <gtest/gtest.h>

#include <chrono>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <vector>

#include "lockstep/client/sample_pool.h"
#include "lockstep/runtime/messages.h"
#include "process.h"

namespace lockstep::client {
namespace {

msg::Image Filled(uint32_t sensor, uint64_t frame, size_t bytes) {
  msg::Image im;
  im.sensor(sensor);
  im.stamp().frame(frame);
  im.data(std::vector<uint8_t>(bytes, static_cast<uint8_t>(frame)));
  return im;
}

bool AllBytesAre(const msg::Image& im, uint8_t v) {
  for (uint8_t b : im.data()) {
    if (b != v) return false;
  }
  return true;
}

TEST(SamplePool, TakesTheContentsAndRecyclesTheBufferWhenReleased) {
  auto pool = std::make_shared<SamplePool<msg::Image>>(2);
  msg::Image received = Filled(7, 1, 1000);
  const uint8_t* payload = received.data().data();
  std::shared_ptr<const msg::Image> taken = pool->Take(received);
  EXPECT_EQ(taken->data().data(), payload) << "the payload moved, it was not copied";
  EXPECT_EQ(taken->stamp().frame(), 1u);
  EXPECT_TRUE(received.data().empty()) << "a fresh pooled object was swapped in";
  EXPECT_EQ(pool->idle(), 0u);
  taken.reset();
  EXPECT_EQ(pool->idle(), 1u);
  // The next sample is read into the recycled buffer, which keeps its size.
  received = Filled(7, 2, 1000);
  taken = pool->Take(received);
  EXPECT_EQ(received.data().size(), 1000u);
  EXPECT_EQ(received.data().data(), payload) << "the released buffer came back";
}

TEST(SamplePool, KeepsAtMostItsLimitIdle) {
  auto pool = std::make_shared<SamplePool<msg::Image>>(2);
  std::vector<std::shared_ptr<const msg::Image>> held;
  for (int i = 0; i < 5; ++i) {
    msg::Image m = Filled(1, i, 10);
    held.push_back(pool->Take(m));
  }
  held.clear();
  EXPECT_EQ(pool->idle(), 2u);
}

TEST(SamplePool, OutlivesItsOwnerWhileSamplesAreInUse) {
  auto pool = std::make_shared<SamplePool<msg::Image>>(2);
  msg::Image m = Filled(1, 9, 10);
  std::shared_ptr<const msg::Image> taken = pool->Take(m);
  pool.reset();  // the client went away; a numpy view still holds its sample
  EXPECT_TRUE(AllBytesAre(*taken, 9));
  taken.reset();
}

// Receives images with a TakingReader into a pool and keeps every one.
class Keeper {
 public:
  Keeper(Bus& bus, const char* topic)
      : pool_(std::make_shared<SamplePool<msg::Image>>(4)),
        reader_(bus, Topic<msg::Image>{topic, QosKind::kImage}, [this](msg::Image& m, const SampleInfo&) {
          auto taken = pool_->Take(m);
          std::lock_guard<std::mutex> lock(mu_);
          kept_.push_back(std::move(taken));
          cv_.notify_all();
        }) {}
  bool WaitFor(size_t n) {
    std::unique_lock<std::mutex> lock(mu_);
    return cv_.wait_for(lock, std::chrono::seconds(20), [&] { return kept_.size() >= n; });
  }
  std::vector<std::shared_ptr<const msg::Image>> kept() {
    std::lock_guard<std::mutex> lock(mu_);
    return kept_;
  }
  void Release() {
    std::lock_guard<std::mutex> lock(mu_);
    kept_.clear();
  }

 private:
  std::shared_ptr<SamplePool<msg::Image>> pool_;
  std::mutex mu_;
  std::condition_variable cv_;
  std::vector<std::shared_ptr<const msg::Image>> kept_;
  TakingReader<msg::Image> reader_;  // last: its callback uses the members above
};

void ExpectEachKeepsItsOwnPayload(Keeper& keeper, uint64_t first, int count, size_t bytes) {
  ASSERT_TRUE(keeper.WaitFor(static_cast<size_t>(count)));
  auto kept = keeper.kept();
  ASSERT_EQ(kept.size(), static_cast<size_t>(count));
  for (int i = 0; i < count; ++i) {
    EXPECT_EQ(kept[i]->stamp().frame(), first + i);
    ASSERT_EQ(kept[i]->data().size(), bytes);
    EXPECT_TRUE(AllBytesAre(*kept[i], static_cast<uint8_t>(first + i))) << "sample " << i << " was overwritten";
  }
}

TEST(TakingReader, OverFastDdsEverySampleKeepsItsOwnPayload) {
  auto writer_bus = CreateDdsBus({testing::TestDomain(), "", "lockstep.participant.loopback", "taking-writer"});
  auto reader_bus = CreateDdsBus({testing::TestDomain(), "", "lockstep.participant.loopback", "taking-reader"});
  Keeper keeper(*reader_bus, "lockstep/test/taking");
  // The camera QoS (transient local): a sample written before the two matched still arrives.
  Writer<msg::Image> writer(*writer_bus, Topic<msg::Image>{"lockstep/test/taking", QosKind::kImage});
  // Each sample waits for the one before: KEEP_LAST 2 may replace unread samples.
  const size_t bytes = 1280 * 720 * 4;
  for (int i = 0; i < 6; ++i) {
    writer.Write(Filled(3, 10 + i, bytes));
    ASSERT_TRUE(keeper.WaitFor(static_cast<size_t>(i + 1)));
  }
  ExpectEachKeepsItsOwnPayload(keeper, 10, 6, bytes);
  // Released samples go back to the pool and the next ones are read into them.
  keeper.Release();
  for (int i = 0; i < 3; ++i) {
    writer.Write(Filled(3, 20 + i, bytes));
    ASSERT_TRUE(keeper.WaitFor(static_cast<size_t>(i + 1)));
  }
  ExpectEachKeepsItsOwnPayload(keeper, 20, 3, bytes);
}

TEST(TakingReader, OnTheInProcessBusTwoReadersEachGetTheWholeSample) {
  auto bus = CreateInProcessBus();
  Keeper a(*bus, "lockstep/test/taking");
  Keeper b(*bus, "lockstep/test/taking");
  Writer<msg::Image> writer(*bus, Topic<msg::Image>{"lockstep/test/taking", QosKind::kImage});
  for (int i = 0; i < 4; ++i) writer.Write(Filled(3, 30 + i, 4096));
  ExpectEachKeepsItsOwnPayload(a, 30, 4, 4096);
  ExpectEachKeepsItsOwnPayload(b, 30, 4, 4096);
}

}  // namespace
}  // namespace lockstep::client
