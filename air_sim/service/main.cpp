// lockstep_air_sim: the multirotor service (6-DOF physics at 1 kHz, flight controller).
#include "air_service.h"
#include "lockstep/runtime/service_main.h"

int main(int argc, char** argv) {
  return lockstep::RunServiceMain(argc, argv, "air_sim", false, [](lockstep::ServiceContext& ctx) {
    return std::make_unique<lockstep::AirService>(*ctx.bus, ctx.name);
  });
}
