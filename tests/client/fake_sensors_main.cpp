// lockstep_fake_sensors: the stand-in sensors service of the client tests as a process,
// for the Python tests (an IMU and an RGB camera, one sample per frame).
#include "fake_sensors.h"
#include "lockstep/runtime/service_main.h"

int main(int argc, char** argv) {
  return lockstep::RunServiceMain(argc, argv, "fake_sensors", /*perception=*/true, [](lockstep::ServiceContext& ctx) {
    return std::make_unique<lockstep::testing::FakeSensors>(*ctx.bus, ctx.name);
  });
}
