// lockstep_ground_sim: vehicles, walkers, traffic lights and the Traffic Manager.
#include "ground_service.h"
#include "lockstep/runtime/service_main.h"

int main(int argc, char** argv) {
  return lockstep::RunServiceMain(argc, argv, "ground_sim", false, [](lockstep::ServiceContext& ctx) {
    return std::make_unique<lockstep::GroundService>(*ctx.bus, ctx.name, ctx.config.output_dir);
  });
}
