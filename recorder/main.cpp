// lockstep_recorder: writes every frame's world state under the config's output_dir.
#include "lockstep/runtime/service_main.h"
#include "recorder.h"

int main(int argc, char** argv) {
  return lockstep::RunServiceMain(argc, argv, "recorder", true, [](lockstep::ServiceContext& ctx) {
    lockstep::RecorderOptions o;
    o.output_dir = ctx.config.output_dir;
    return std::make_unique<lockstep::Recorder>(*ctx.bus, o);
  });
}
