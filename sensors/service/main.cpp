// lockstep_sensors: LiDAR, radar, inertial, navigation, proximity and event sensors.
#include "lockstep/runtime/service_main.h"
#include "sensors_service.h"

int main(int argc, char** argv) {
  return lockstep::RunServiceMain(argc, argv, "sensors", true, [](lockstep::ServiceContext& ctx) {
    lockstep::SensorsOptions o;
    o.output_dir = ctx.config.output_dir;
    return std::make_unique<lockstep::SensorsService>(*ctx.bus, ctx.name, o);
  });
}
