// Issue 21, item 7: simulations on one machine do not disturb each other. Two runs on two
// DDS domains at once never see each other's samples (names on every clock topic, and the
// world hash of every frame equals that of the same run alone); a second `lockstep up` on
// a domain in use on this host is refused, naming the domain and the holder.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/file.h>
#include <unistd.h>

#include <filesystem>
#include <functional>
#include <map>
#include <mutex>
#include <set>
#include <string>
#include <thread>

#include "lockstep/runtime/bus.h"
#include "lockstep/runtime/messages.h"
#include "process.h"

namespace lockstep::testing {
namespace {

using namespace std::chrono_literals;
const char* kProfile = "lockstep.participant.loopback";

// A second domain of this process's own, from the same lock files as TestDomain().
int SecondDomain() {
  static const int domain = [] {
    const int first = TestDomain();
    for (int i = 1; i < 200; ++i) {
      const int d = 1 + (first - 1 + i) % 200;
      const std::string path = std::filesystem::temp_directory_path() / ("lockstep-test-domain-" + std::to_string(d) + ".lock");
      const int fd = open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0666);
      if (fd < 0) continue;
      if (flock(fd, LOCK_EX | LOCK_NB) == 0) return d;  // held until the process exits
      close(fd);
    }
    return -1;
  }();
  return domain;
}

// A run of no-op services named <prefix>alpha and <prefix>beta, `ticks` frames as fast as
// possible, with weather commands of its own (folded into the no-op hash chain, so a tick
// or command from another run would change the world hashes).
std::string Config(int domain, const std::string& prefix, uint64_t seed, double cloudiness, uint64_t ticks,
                   double real_time_factor = 0) {
  return "name: " + prefix + "run\ndomain_id: " + std::to_string(domain) + "\nparticipant_profile: " + kProfile +
         "\nseed: " + std::to_string(seed) + "\nticks: " + std::to_string(ticks) +
         "\nrecorder: false\nworld:\n  synchronous_mode: false\n  real_time_factor: " + std::to_string(real_time_factor) +
         "\n  service_timeout: 10\nservices:\n"
         "  - {name: " + prefix + "alpha, kind: noop}\n  - {name: " + prefix + "beta, kind: noop}\n"
         "scenario:\n"
         "  - {frame: 5, weather: {cloudiness: " + std::to_string(cloudiness) + "}}\n"
         "  - {frame: 40, weather: {fog_density: " + std::to_string(cloudiness / 2) + "}}\n";
}

// Everything one domain shows: the service names on ticks' acks, announcements and run
// status, and each frame's world hash.
class DomainWatch {
 public:
  explicit DomainWatch(int domain)
      : bus_(CreateDdsBus({domain, "", kProfile, "isolation-test-" + std::to_string(domain)})),
        acks_(*bus_, topics::kAck, [this](const msg::Ack& a, const SampleInfo&) { Add(a.service().to_string()); }),
        announces_(*bus_, topics::kService,
                   [this](const msg::ServiceAnnounce& a, const SampleInfo&) { Add(a.service().to_string()); }),
        status_(*bus_, topics::kRunStatus,
                [this](const msg::RunStatus& s, const SampleInfo&) {
                  for (const auto& m : s.members()) Add(m.service().to_string());
                }),
        frames_(*bus_, topics::kFrameDone, [this](const msg::FrameDone& f, const SampleInfo&) {
          std::lock_guard<std::mutex> lock(mu_);
          hashes_[f.frame()] = f.world_hash();
        }) {}
  std::set<std::string> names() {
    std::lock_guard<std::mutex> lock(mu_);
    return names_;
  }
  std::map<uint64_t, uint64_t> hashes() {
    std::lock_guard<std::mutex> lock(mu_);
    return hashes_;
  }

 private:
  void Add(const std::string& name) {
    std::lock_guard<std::mutex> lock(mu_);
    names_.insert(name);
  }
  std::unique_ptr<Bus> bus_;
  std::mutex mu_;
  std::set<std::string> names_;
  std::map<uint64_t, uint64_t> hashes_;
  Reader<msg::Ack> acks_;
  Reader<msg::ServiceAnnounce> announces_;
  Reader<msg::RunStatus> status_;
  Reader<msg::FrameDone> frames_;
};

constexpr uint64_t kTicks = 150;

// Waits until `pred` holds, checking every 20 ms; false on timeout.
bool Until(const std::function<bool()>& pred, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!pred()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(20ms);
  }
  return true;
}

std::map<uint64_t, uint64_t> RunAlone(const std::string& config) {
  DomainWatch watch(TestDomain());
  Process up({Bin("lockstep"), "up", config});
  auto code = up.Wait(60s);
  EXPECT_TRUE(code && *code == 0) << up.Output();
  return watch.hashes();
}

TEST(Isolation, TwoSimulationsOnTwoDomainsNeverSeeEachOther) {
  const int a = TestDomain(), b = SecondDomain();
  ASSERT_GT(b, 0) << "no second free DDS domain";
  ASSERT_NE(a, b);
  const std::string config_a = WriteTempFile("iso-a.yaml", Config(a, "a_", 11, 30, kTicks));
  const std::string config_b = WriteTempFile("iso-b.yaml", Config(b, "b_", 12, 70, kTicks));
  const auto alone = RunAlone(config_a);
  ASSERT_GE(alone.size(), kTicks) << "the undisturbed run did not complete its frames";

  // (One participant per process here: Fast DDS refuses a second one with the same
  // participant id, and ids are chosen per domain. B's side is what `lockstep up` reports.)
  DomainWatch watch_a(a);
  Process up_a({Bin("lockstep"), "up", config_a});
  Process up_b({Bin("lockstep"), "up", config_b});
  auto code_a = up_a.Wait(60s);
  auto code_b = up_b.Wait(60s);
  ASSERT_TRUE(code_a && *code_a == 0) << up_a.Output();
  ASSERT_TRUE(code_b && *code_b == 0) << up_b.Output();

  EXPECT_EQ(watch_a.names(), (std::set<std::string>{"a_alpha", "a_beta"}));
  // B completed its own frames with its own services.
  EXPECT_NE(up_b.Output().find("b_alpha"), std::string::npos) << up_b.Output();
  EXPECT_NE(up_b.Output().find(std::to_string(kTicks)), std::string::npos) << up_b.Output();
  // Every frame of run A, with B running beside it, is the frame of A alone.
  const auto together = watch_a.hashes();
  for (uint64_t f = 1; f <= kTicks; ++f) {
    ASSERT_TRUE(alone.count(f) && together.count(f)) << "frame " << f << " missing";
    ASSERT_EQ(together.at(f), alone.at(f)) << "frame " << f << " of run A differs with run B beside it";
  }
}

TEST(Isolation, SecondLockstepUpOnTheSameDomainIsRefused) {
  const int d = TestDomain();
  // Long enough to outlive the second attempt: stopped with Ctrl-C below.
  const std::string config = WriteTempFile("iso-held.yaml", Config(d, "held_", 3, 10, 1000000, 1.0));
  DomainWatch watch(d);
  Process first({Bin("lockstep"), "up", config});
  ASSERT_TRUE(Until([&] { return watch.hashes().size() >= 5; }, 30s))
      << first.Output();

  Process second({Bin("lockstep"), "up", config});
  auto code = second.Wait(30s);
  ASSERT_TRUE(code.has_value()) << "a second `lockstep up` on domain " << d << " kept running:\n" << second.Output();
  EXPECT_EQ(*code, 2) << second.Output();
  const std::string out = second.Output();
  EXPECT_NE(out.find("DDS domain " + std::to_string(d) + " is in use on this host by pid " + std::to_string(first.pid())),
            std::string::npos)
      << out;
  EXPECT_NE(out.find(config), std::string::npos) << "the reason names the holder's config: " << out;
  // The first run is undisturbed: still ticking, its services only.
  const size_t frames = watch.hashes().size();
  ASSERT_TRUE(Until([&] { return watch.hashes().size() > frames + 5; }, 30s));
  EXPECT_EQ(watch.names(), (std::set<std::string>{"held_alpha", "held_beta"}));

  // The lock goes with the process: after Ctrl-C the domain is free again.
  first.Signal(SIGINT);
  ASSERT_TRUE(first.Wait(30s).has_value());
  const std::string short_config = WriteTempFile("iso-after.yaml", Config(d, "after_", 3, 10, 20));
  Process third({Bin("lockstep"), "up", short_config});
  auto third_code = third.Wait(60s);
  ASSERT_TRUE(third_code && *third_code == 0) << third.Output();
}

}  // namespace
}  // namespace lockstep::testing
