// The barrier with real processes over DDS and steps that take time: services sleep a
// random, seeded 0..N ms per step (one of them up to 20 ms), and each writes when every
// step began and ended (CLOCK_MONOTONIC, one clock for the machine). A barrier that let
// tick k+1 out before every required service acked k would show a step k+1 that began
// before some service's step k ended.
#include <gtest/gtest.h>
#include <signal.h>

#include <fstream>
#include <map>
#include <mutex>
#include <sstream>

#include "lockstep/runtime/messages.h"
#include "lockstep/runtime/noop_core.h"
#include "observer.h"
#include "process.h"

namespace lockstep::testing {
namespace {

using namespace std::chrono_literals;
const char* kProfile = "lockstep.participant.loopback";

struct Step {
  int64_t start = 0, end = 0;
  uint64_t hash = 0;  // state after the step
  int count = 0;
};
using Ledger = std::map<std::pair<uint32_t, uint64_t>, Step>;  // (run, frame) -> step

Ledger ReadLedger(const std::string& path) {
  Ledger out;
  std::ifstream in(path);
  unsigned run = 0;
  unsigned long long frame = 0;
  long long start = 0, end = 0;
  unsigned long long hash = 0;
  while (in >> run >> frame >> start >> end >> hash) {
    Step& s = out[{run, frame}];
    s.start = start;
    s.end = end;
    s.hash = hash;
    ++s.count;
  }
  return out;
}

struct Witness {
  std::string name;
  std::string step_ms;  // LOCKSTEP_NOOP_STEP_MS
  std::string ledger;
  std::unique_ptr<Process> process;
};

class BarrierProcesses : public ::testing::Test {
 protected:
  void Start(uint64_t ticks, const std::vector<std::pair<std::string, std::string>>& services) {
    std::string list;
    for (const auto& [name, step] : services) list += "  - {name: " + name + ", kind: noop}\n";
    config_ = WriteTempFile("barrier.yaml", "domain_id: " + std::to_string(TestDomain()) + "\nparticipant_profile: " + kProfile +
                                                "\nseed: 9\nticks: " + std::to_string(ticks) +
                                                "\nworld:\n  service_timeout: 30\nservices:\n" + list);
    bus_ = CreateDdsBus({TestDomain(), "", kProfile, "barrier-test"});
    observer_ = std::make_unique<Observer>(*bus_);
    coordinator_ = std::make_unique<Process>(std::vector<std::string>{Bin("lockstep_coordinator"), config_});
    for (const auto& [name, step] : services) {
      Witness w{name, step, WriteTempFile(name + ".ledger", ""), nullptr};
      w.process = std::make_unique<Process>(std::vector<std::string>{Bin("lockstep_noop"), "--name", name, "--config", config_},
                                            std::map<std::string, std::string>{{"LOCKSTEP_NOOP_STEP_MS", step},
                                                                               {"LOCKSTEP_NOOP_LEDGER", w.ledger}});
      witnesses_.push_back(std::move(w));
    }
  }
  std::string Logs() {
    std::string out = "coordinator:\n" + coordinator_->Output();
    for (auto& w : witnesses_) out += "\n" + w.name + ":\n" + w.process->Output();
    return out;
  }
  void TearDown() override {
    if (HasFailure()) std::cerr << Logs();
  }
  std::string config_;
  std::unique_ptr<Bus> bus_;
  std::unique_ptr<Observer> observer_;
  std::unique_ptr<Process> coordinator_;
  std::vector<Witness> witnesses_;
};

TEST_F(BarrierProcesses, NoServiceStartsStepKPlusOneBeforeEveryServiceFinishedK) {
  constexpr uint64_t kTicks = 150;
  Start(kTicks, {{"fast", "1:1"}, {"medium", "5:2"}, {"slow", "20:3"}, {"steady", "0:0"}});
  auto code = coordinator_->Wait(120s);
  ASSERT_TRUE(code) << "the run did not finish";
  ASSERT_EQ(*code, 0);
  std::vector<Ledger> ledgers;
  for (auto& w : witnesses_) {
    w.process->Signal(SIGTERM);
    w.process->Wait(10s);
    ledgers.push_back(ReadLedger(w.ledger));
  }
  for (size_t i = 0; i < ledgers.size(); ++i) {
    ASSERT_EQ(ledgers[i].size(), kTicks) << witnesses_[i].name << " did not step every frame once";
    for (const auto& [key, s] : ledgers[i]) ASSERT_EQ(s.count, 1) << witnesses_[i].name << " stepped frame " << key.second << " twice";
  }
  int violations = 0;
  std::string first;
  for (uint64_t k = 1; k < kTicks; ++k) {
    for (size_t a = 0; a < ledgers.size(); ++a) {
      for (size_t b = 0; b < ledgers.size(); ++b) {
        const Step& next = ledgers[a].at({1, k + 1});
        const Step& done = ledgers[b].at({1, k});
        if (next.start < done.end) {
          if (violations++ == 0) {
            first = witnesses_[a].name + " began frame " + std::to_string(k + 1) + " " + std::to_string((done.end - next.start) / 1000) +
                    " us before " + witnesses_[b].name + " finished frame " + std::to_string(k);
          }
        }
      }
    }
  }
  EXPECT_EQ(violations, 0) << first;
}

// A reset: every service starts the new run from frame 1 with the new seed. The seed is
// checked through each service's state hash after frame 1, which NoopCore starts from
// (run, seed); the control shows another seed gives another hash.
TEST_F(BarrierProcesses, AResetReachesEveryServiceWithItsSeedAtFrameOne) {
  Start(0, {{"one", "1:4"}, {"two", "2:5"}});
  ASSERT_TRUE(observer_->WaitUntil([&] { return observer_->last_frame() >= 20; }, 60s)) << Logs();
  msg::ResetWorld r;
  r.seed(777);
  msg::CommandBody body;
  body.reset(r);
  auto reply = observer_->WaitReply(observer_->Send(body), 10s);
  ASSERT_TRUE(reply && reply->accepted());
  EXPECT_EQ(reply->run(), 2u);
  EXPECT_EQ(reply->frame(), 1u);
  ASSERT_TRUE(observer_->WaitUntil([&] { return observer_->status() && observer_->status()->run() == 2 && observer_->status()->frame() >= 10; }, 30s));
  // Each service's first step of run 2 was frame 1 (its ledger), from seed 777 (its hash).
  // NoopCore's state after frames 1..k of run 2 (no commands) from `seed`.
  auto expected = [](uint64_t seed, uint64_t frames) {
    NoopCore core;
    msg::WorldInfo w;
    w.run(2);
    w.seed(seed);
    core.BeginRun(w);
    for (uint64_t k = 1; k <= frames; ++k) {
      msg::Tick t;
      t.run(2);
      t.frame(k);
      core.Step(t);
    }
    return core.StateHash();
  };
  ASSERT_NE(expected(777, 5), expected(778, 5)) << "the control: another seed, another hash";
  for (auto& w : witnesses_) {
    const Ledger ledger = ReadLedger(w.ledger);
    auto first_of_run2 = ledger.lower_bound({2, 0});
    ASSERT_NE(first_of_run2, ledger.end()) << w.name;
    EXPECT_EQ(first_of_run2->first, std::make_pair(2u, uint64_t{1})) << w.name << ": run 2 must begin at frame 1";
    EXPECT_EQ(first_of_run2->second.hash, expected(777, 1)) << w.name << " did not start run 2 from seed 777";
  }
}

}  // namespace
}  // namespace lockstep::testing
