// lockstep_noop: a service that joins the barrier and simulates nothing (benchmarks,
// tests, and a stand-in while a real service is developed).
#include "lockstep/runtime/noop_core.h"
#include "lockstep/runtime/service_main.h"

int main(int argc, char** argv) {
  return lockstep::RunServiceMain(argc, argv, "noop", false, [](lockstep::ServiceContext&) {
    return std::make_unique<lockstep::NoopCore>();
  });
}
