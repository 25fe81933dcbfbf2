// lockstep_render: the camera service (headless OpenGL through EGL).
#include <CLI/CLI.hpp>

#include "lockstep/runtime/service_main.h"
#include "render_service.h"

int main(int argc, char** argv) {
  lockstep::RenderOptions options;
  return lockstep::RunServiceMain(
      argc, argv, "render", true,
      [&](lockstep::ServiceContext& ctx) {
        lockstep::RenderOptions o = options;
        // A relative save folder lives under the run's output folder.
        if (!o.save_dir.empty() && o.save_dir[0] != '/' && !ctx.config.output_dir.empty()) o.save_dir = ctx.config.output_dir + "/" + o.save_dir;
        return std::make_unique<lockstep::RenderService>(*ctx.bus, ctx.name, o);
      },
      [&](CLI::App& app) { lockstep::AddRenderOptions(app, options); });
}
