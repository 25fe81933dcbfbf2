// lockstep_recorder: writes Lockstep logs (docs/recorder.md). Options of its own, before
// the common ones: --record-run [--log-name NAME] records every run from its first frame into
// <output_dir>/run<N>/NAME (default recording.lslog); --read-only never writes (the recorder
// of a re-simulation, which must not overwrite the log it replays); --record-sensors SPEC
// records the outputs of the sensors SPEC chooses in every log ("all", actor ids,
// role_name=NAME, blueprint patterns such as sensor.camera.*: docs/recorder.md); without
// it $LOCKSTEP_RECORD_SENSORS (`lockstep up --record-sensors`) gives SPEC.
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "lockstep/runtime/service_main.h"
#include "recorder.h"

int main(int argc, char** argv) {
  lockstep::RecorderOptions options;
  // Take our options out of argv; the rest goes to RunServiceMain.
  int out = 1;
  bool sensors_given = false;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--record-run") == 0) {
      options.record_run = true;
    } else if (std::strcmp(argv[i], "--read-only") == 0) {
      options.read_only = true;
    } else if (std::strcmp(argv[i], "--log-name") == 0) {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "lockstep_recorder: --log-name needs a file name\n");
        return 2;
      }
      options.run_log_name = argv[++i];
    } else if (std::strcmp(argv[i], "--record-sensors") == 0) {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "lockstep_recorder: --record-sensors needs a selection (all, ids, role_name=NAME, sensor.camera.*)\n");
        return 2;
      }
      options.record_sensors = argv[++i];
      sensors_given = true;
    } else {
      argv[out++] = argv[i];
    }
  }
  argc = out;
  if (const char* env = std::getenv("LOCKSTEP_RECORD_SENSORS"); env != nullptr && !sensors_given) options.record_sensors = env;
  if (const char* ro = std::getenv("LOCKSTEP_RECORDER_READ_ONLY"); ro != nullptr && std::strcmp(ro, "1") == 0) options.read_only = true;
  return lockstep::RunServiceMain(argc, argv, "recorder", true, [&](lockstep::ServiceContext& ctx) {
    lockstep::RecorderOptions o = options;
    o.output_dir = ctx.config.output_dir;
    std::error_code ec;
    const auto source = std::filesystem::absolute(ctx.config.source, ec);
    o.config_source = ec ? ctx.config.source : source.lexically_normal().string();
    if (std::ifstream in(ctx.config.source); in) {
      std::stringstream text;
      text << in.rdbuf();
      o.config_text = text.str();
    }
    for (const auto& s : ctx.config.services) o.service_kinds[s.name] = {s.kind, s.perception};
    return std::make_unique<lockstep::Recorder>(*ctx.bus, o);
  });
}
