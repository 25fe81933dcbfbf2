// Writes flushed by two threads leave in the order they were queued.
#include "lockstep/coordinator/outbox.h"

#include <gtest/gtest.h>

#include <string>
#include <thread>

namespace lockstep {
namespace {

using namespace std::chrono_literals;

TEST(OrderedOutbox, ALaterFlushWaitsForTheEarlierOneToFinishWriting) {
  std::mutex owner;  // the coordinator's lock
  OrderedOutbox box;
  std::mutex mu;
  std::condition_variable cv;
  std::vector<std::string> written;
  bool first_writing = false;
  auto record = [&](const std::string& what) {
    std::lock_guard<std::mutex> lock(mu);
    written.push_back(what);
    cv.notify_all();
  };
  std::thread main_loop([&] {
    std::unique_lock<std::mutex> lock(owner);
    box.Post([&] {
      record("frame 1 begins");
      {
        std::unique_lock<std::mutex> l(mu);
        first_writing = true;
        cv.notify_all();
        // A write that takes a while (a slow reader); frame 2 must not overtake it.
        cv.wait_for(l, 500ms, [&] { return written.size() > 1; });
      }
      record("frame 1 ends");
    });
    box.Flush(lock);
  });
  {
    std::unique_lock<std::mutex> l(mu);
    ASSERT_TRUE(cv.wait_for(l, 10s, [&] { return first_writing; }));
  }
  std::thread callback([&] {
    std::unique_lock<std::mutex> lock(owner);  // free: the first flush released it to write
    box.Post([&] { record("frame 2"); });
    box.Flush(lock);
  });
  main_loop.join();
  callback.join();
  EXPECT_EQ(written, (std::vector<std::string>{"frame 1 begins", "frame 1 ends", "frame 2"}));
}

}  // namespace
}  // namespace lockstep
