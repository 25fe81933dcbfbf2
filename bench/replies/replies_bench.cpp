// What a client that came and went leaves in the coordinator: its instance of the keyed
// lockstep/command_reply topic, with up to 256 replies in the writer's history (KEEP_LAST
// 256 per instance). Writes a full history of replies for each of many client names, with a
// reader that acknowledges them, and prints the growth of resident memory per 100 clients.
// The coordinator never unregisters a client's instance: this shows what that costs (Fast
// DDS drops acknowledged samples of a VOLATILE writer; the instance entry stays).
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <fstream>
#include <string>

#include "lockstep/runtime/bus.h"
#include "lockstep/runtime/messages.h"

namespace {

double RssMb() {
  std::ifstream f("/proc/self/status");
  std::string line;
  while (std::getline(f, line)) {
    if (line.rfind("VmRSS:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const int clients = argc > 1 ? std::atoi(argv[1]) : 400;
  const int replies = 256;  // the reply writer's history depth per client
  const int domain = 200 + static_cast<int>(getpid() % 20);
  auto bus = lockstep::CreateDdsBus({domain, "", "lockstep.participant", "bench-replies"});
  std::atomic<long> received{0};
  lockstep::Reader<lockstep::msg::CommandReply> reader(*bus, lockstep::topics::kCommandReply,
                                                       [&](const lockstep::msg::CommandReply&, const lockstep::SampleInfo&) { ++received; });
  {
    lockstep::Writer<lockstep::msg::CommandReply> writer(*bus, lockstep::topics::kCommandReply);
    while (writer.MatchedReaders() < 1) usleep(1000);
    double rss_at_100 = 0;
    for (int c = 0; c < clients; ++c) {
      lockstep::msg::CommandReply r;
      r.client("client-" + std::to_string(c));
      r.accepted(true);
      for (int k = 0; k < replies; ++k) {
        r.sequence_number(static_cast<uint64_t>(k));
        writer.Write(r);
      }
      writer.WaitForAcknowledgments(5.0);
      if (c + 1 == 100) rss_at_100 = RssMb();
    }
    const double rss = RssMb();
    std::printf("{\"bench\":\"replies\",\"clients\":%d,\"replies_per_client\":%d,\"rss_mb\":%.1f,"
                "\"rss_growth_mb_per_100_clients\":%.2f}\n",
                clients, replies, rss, (rss - rss_at_100) / ((clients - 100) / 100.0));
    std::fflush(stdout);
  }
  return received > 0 ? 0 : 1;
}
