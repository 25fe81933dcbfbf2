// lockstep_noop: a service that joins the barrier and simulates nothing (benchmarks,
// tests, and a stand-in while a real service is developed).
// For the barrier's process tests, two environment variables make it a witness:
//   LOCKSTEP_NOOP_STEP_MS=MAX[:SEED]  each step sleeps a random 0..MAX ms (seeded by SEED,
//                                     the service name and the frame)
//   LOCKSTEP_NOOP_LEDGER=FILE         one line per step: "<run> <frame> <start_ns> <end_ns> <hash>"
//                                     (CLOCK_MONOTONIC, comparable across processes; the
//                                     state hash after the step)
#include <time.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <thread>

#include "lockstep/runtime/hash.h"
#include "lockstep/runtime/noop_core.h"
#include "lockstep/runtime/service_main.h"

namespace {

int64_t MonotonicNs() {
  timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1000000000 + ts.tv_nsec;
}

class WitnessCore final : public lockstep::NoopCore {
 public:
  WitnessCore(std::string name, double max_ms, uint64_t seed, const char* ledger)
      : name_(std::move(name)), max_ms_(max_ms), seed_(seed), ledger_(ledger ? std::fopen(ledger, "w") : nullptr) {}
  ~WitnessCore() override {
    if (ledger_) std::fclose(ledger_);
  }
  bool StepNeverWaits() const override { return false; }
  void Step(const lockstep::msg::Tick& tick) override {
    const int64_t start = MonotonicNs();
    if (max_ms_ > 0 && !replaying()) {
      std::mt19937_64 rng(lockstep::Fnv1a64().Add(seed_).Add(std::string_view(name_)).Add(tick.frame()).value());
      std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(std::uniform_real_distribution<double>(0, max_ms_)(rng)));
    }
    lockstep::NoopCore::Step(tick);
    if (ledger_ && !replaying()) {
      std::fprintf(ledger_, "%u %llu %lld %lld %llu\n", tick.run(), static_cast<unsigned long long>(tick.frame()),
                   static_cast<long long>(start), static_cast<long long>(MonotonicNs()),
                   static_cast<unsigned long long>(StateHash()));
      std::fflush(ledger_);
    }
  }

 private:
  std::string name_;
  double max_ms_;
  uint64_t seed_;
  std::FILE* ledger_;
};

}  // namespace

int main(int argc, char** argv) {
  return lockstep::RunServiceMain(argc, argv, "noop", false, [](lockstep::ServiceContext& ctx) -> std::unique_ptr<lockstep::ServiceCore> {
    const char* step = std::getenv("LOCKSTEP_NOOP_STEP_MS");
    const char* ledger = std::getenv("LOCKSTEP_NOOP_LEDGER");
    if (!step && !ledger) return std::make_unique<lockstep::NoopCore>();
    double max_ms = 0;
    unsigned long long seed = 0;
    if (step) std::sscanf(step, "%lf:%llu", &max_ms, &seed);
    return std::make_unique<WitnessCore>(ctx.name, max_ms, seed, ledger);
  });
}
