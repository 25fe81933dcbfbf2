// The render service's own options on the common service command line (CLI11, beside
// --name, --config, --domain): the same flags as before, each value checked as it is
// parsed, the error naming the option and the value.
#include <gtest/gtest.h>

#include <algorithm>

#include <CLI/CLI.hpp>

#include "render_service.h"

namespace lockstep {
namespace {

// Parses `args` as RunServiceMain does (its own options plus the render ones); empty on
// success, else CLI11's message.
std::string Parse(std::vector<std::string> args, RenderOptions& o) {
  CLI::App app{"test"};
  std::string name;
  app.add_option("--name", name);
  AddRenderOptions(app, o);
  std::reverse(args.begin(), args.end());  // CLI11 takes a reversed vector
  try {
    app.parse(args);
  } catch (const CLI::ParseError& e) {
    return e.what();
  }
  return {};
}

TEST(RenderOptions, TheFlagsAreParsedBesideTheServicesOwn) {
  RenderOptions o;
  ASSERT_EQ(Parse({"--name", "render_a", "--device", "cpu", "--claim-unowned", "--save-dir", "out", "--save-every", "20", "--asset",
                   "box=/tmp/box.obj", "--asset", "tree=/tmp/tree.glb,Vegetation,0.01"},
                  o),
            "");
  EXPECT_EQ(o.device, "cpu");
  EXPECT_TRUE(o.claim_unowned);
  EXPECT_EQ(o.save_dir, "out");
  EXPECT_EQ(o.save_every, 20u);
  ASSERT_EQ(o.assets.size(), 2u);
  EXPECT_EQ(o.assets[0].name, "box");
  EXPECT_EQ(o.assets[0].path, "/tmp/box.obj");
  EXPECT_EQ(o.assets[0].tag, 20) << "Static by default";
  EXPECT_EQ(o.assets[1].name, "tree");
  EXPECT_EQ(o.assets[1].path, "/tmp/tree.glb");
  EXPECT_EQ(o.assets[1].tag, render::ClassFromName("Vegetation"));
  EXPECT_DOUBLE_EQ(o.assets[1].scale, 0.01);
  RenderOptions d;
  ASSERT_EQ(Parse({}, d), "");
  EXPECT_EQ(d.device, "auto");
  EXPECT_FALSE(d.claim_unowned);
  EXPECT_EQ(d.save_every, 1u);
  EXPECT_TRUE(d.assets.empty());
}

TEST(RenderOptions, ABadValueIsRefusedNamingTheOptionAndTheValue) {
  const std::vector<std::pair<std::vector<std::string>, std::string>> bad{
      {{"--device", "tpu"}, "render device 'tpu': expected auto, gpu or cpu"},
      {{"--save-every", "0"}, "render option --save-every '0': expected a positive count"},
      {{"--save-every", "-3"}, "render option --save-every '-3': expected a positive count"},
      {{"--save-every", "ten"}, "render option --save-every 'ten': expected a positive count"},
      {{"--asset", "box"}, "render option --asset 'box': expected name=path[,class[,scale]]"},
      {{"--asset", "box=/a.obj,Nonsense"}, "render option --asset 'box=/a.obj,Nonsense': unknown semantic class 'Nonsense'"},
      {{"--asset", "box=/a.obj,Static,big"}, "render option --asset 'box=/a.obj,Static,big': bad scale"},
      {{"--save-dir"}, "--save-dir"},
      {{"--no-such-option"}, "--no-such-option"},
  };
  for (const auto& [args, why] : bad) {
    RenderOptions o;
    const std::string error = Parse(args, o);
    EXPECT_NE(error.find(why), std::string::npos) << args[0] << ": " << (error.empty() ? "accepted" : error);
  }
}

}  // namespace
}  // namespace lockstep
