// Keyed topics past Fast DDS's default of 10 instances per endpoint: the reply topic is
// keyed by client, so the coordinator's 11th client used to get no reply ("history full" in
// its log); acks and announcements are keyed by service, so an 11th service could not join.
#include <gtest/gtest.h>

#include <atomic>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "lockstep/runtime/messages.h"
#include "lockstep/runtime/noop_core.h"
#include "lockstep/runtime/service.h"
#include "observer.h"
#include "process.h"

namespace lockstep::testing {
namespace {

using namespace std::chrono_literals;
const char* kProfile = "lockstep.participant.loopback";

TEST(ManyClients, EveryShortLivedClientGetsItsReply) {
  const int domain = TestDomain();
  const std::string config = WriteTempFile("clients.yaml", "domain_id: " + std::to_string(domain) +
                                                               "\nparticipant_profile: " + kProfile +
                                                               "\nworld:\n  synchronous_mode: true\n"
                                                               "services:\n  - {name: alpha, kind: noop}\n");
  Process coordinator({Bin("lockstep_coordinator"), config});
  Process alpha({Bin("lockstep_noop"), "--name", "alpha", "--config", config});
  auto bus = CreateDdsBus({domain, "", kProfile, "clients-test"});
  {
    Observer first(*bus, "client-0");
    ASSERT_TRUE(first.WaitUntil([&] { return first.status() && first.status()->state() == msg::RunState::RUN_READY; }, 20s))
        << coordinator.Output();
  }
  // One after another, as scripts come and go; 24 > the 10 instances of the default limits.
  for (int i = 1; i <= 24; ++i) {
    Observer client(*bus, "client-" + std::to_string(i));
    ASSERT_TRUE(client.WaitConnected(10s));
    msg::WeatherParameters w;
    w.cloudiness(static_cast<float>(i));
    msg::CommandBody body;
    body.weather(w);
    // Our reader matched the coordinator's writer, but its writer may not have matched our
    // reader yet (discovery runs on both sides), and a reply written before that is lost
    // (VOLATILE): send again, a few times, until one reply comes.
    std::optional<msg::CommandReply> reply;
    for (int attempt = 0; attempt < 10 && !reply; ++attempt) reply = client.WaitReply(client.Send(body), 1s);
    ASSERT_TRUE(reply) << "client " << i << " got no reply\ncoordinator:\n" << coordinator.Output();
    EXPECT_TRUE(reply->accepted()) << reply->reason();
  }
  EXPECT_EQ(coordinator.Output().find("failed"), std::string::npos) << coordinator.Output();
  coordinator.Signal(SIGINT);
  EXPECT_EQ(coordinator.Wait(10s), std::optional<int>(0)) << coordinator.Output();
}

TEST(ManyServices, TwelveServicesJoinOneBarrier) {
  constexpr int kServices = 12;
  const int domain = TestDomain();
  std::string services;
  for (int i = 0; i < kServices; ++i) services.append("  - {name: s").append(std::to_string(i)).append(", kind: noop}\n");
  const std::string config = WriteTempFile("services.yaml", "domain_id: " + std::to_string(domain) +
                                                                "\nparticipant_profile: " + kProfile +
                                                                "\nworld:\n  synchronous_mode: false\n  service_timeout: 10\n"
                                                                "services:\n" + services);
  Process coordinator({Bin("lockstep_coordinator"), config});
  auto bus = CreateDdsBus({domain, "", kProfile, "services-test"});
  Observer observer(*bus);
  // Every service on its own thread of this process (one participant, twelve keys).
  std::atomic<bool> stop{false};
  std::vector<std::unique_ptr<NoopCore>> cores;
  std::vector<std::unique_ptr<ServiceRunner>> runners;
  std::vector<std::thread> threads;
  for (int i = 0; i < kServices; ++i) {
    cores.push_back(std::make_unique<NoopCore>());
    std::string name = "s";
    name.append(std::to_string(i));
    runners.push_back(std::make_unique<ServiceRunner>(*bus, ServiceOptions{name, "noop", false}, *cores.back()));
  }
  for (auto& r : runners) threads.emplace_back([&stop, runner = r.get()] { runner->Run(stop); });
  const bool ticked = observer.WaitUntil([&] { return observer.last_frame() >= 20; }, 30s);
  stop = true;
  for (auto& t : threads) t.join();
  ASSERT_TRUE(ticked) << coordinator.Output();
  EXPECT_EQ(coordinator.Output().find("failed"), std::string::npos) << coordinator.Output();
}

}  // namespace
}  // namespace lockstep::testing
