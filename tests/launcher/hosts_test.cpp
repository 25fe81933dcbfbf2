// `lockstep up` across hosts: the `hosts:` and `host:` keys of a launch config, their
// errors, the commands printed for the services of other hosts, and `ros2: true`.
#include <gtest/gtest.h>

#include <cstdlib>

#include "lockstep/runtime/error.h"
#include "lockstep/runtime/launch_config.h"
#include "remote.h"

namespace lockstep::launcher {
namespace {

const char* kConfig = R"(name: split
domain_id: 4
hosts:
  gpu1: {address: sim@10.0.0.5, build_dir: /opt/lockstep/build, config: /opt/lockstep/split.yaml}
  boxes: {container: podman, network: lockstep}
services:
  - {name: air_sim, kind: air_sim}
  - {name: render, kind: render, perception: true, host: gpu1, args: [--save-dir, "my dir"]}
  - {name: ground_sim, kind: ground_sim, host: boxes}
  - {name: sensors, kind: sensors, host: local}
)";

std::string ErrorOf(const std::string& yaml) {
  try {
    ParseLaunchConfig(yaml, "cfg.yaml");
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(LaunchHosts, ServicesNameTheirHosts) {
  const LaunchConfig c = ParseLaunchConfig(kConfig, "split.yaml");
  ASSERT_EQ(c.hosts.size(), 2u);
  EXPECT_EQ(c.hosts[0].name, "gpu1");
  EXPECT_EQ(c.hosts[0].address, "sim@10.0.0.5");
  EXPECT_EQ(c.hosts[1].container, "podman");
  EXPECT_EQ(c.HostOf("air_sim"), nullptr);
  EXPECT_EQ(c.HostOf("sensors"), nullptr);  // 'local' is this machine
  ASSERT_NE(c.HostOf("render"), nullptr);
  EXPECT_EQ(c.HostOf("render")->name, "gpu1");
  EXPECT_EQ(c.HostOf("ground_sim")->name, "boxes");
  EXPECT_EQ(c.RequiredServices().size(), 4u);  // the run waits for the remote ones too
}

TEST(LaunchHosts, CommandsForTheOtherHostsAreExact) {
  const LaunchConfig c = ParseLaunchConfig(kConfig, "split.yaml");
  const auto lines = RemoteCommands(c, "/work/cfg/split.yaml", "/home/me/lockstep/build");
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[0],
            "[gpu1] ssh sim@10.0.0.5 '/opt/lockstep/build/bin/lockstep_render --name render --config /opt/lockstep/split.yaml "
            "--domain 4 --save-dir '\\''my dir'\\'''");
  EXPECT_EQ(lines[1],
            "[boxes] podman run -d --name ground_sim --network lockstep -v /work/cfg:/etc/lockstep:ro -e LOCKSTEP_DOMAIN=4 "
            "localhost/lockstep/ground_sim --name ground_sim --config /etc/lockstep/split.yaml --domain 4");
}

TEST(LaunchHosts, AnSshHostDefaultsToThisBuildAndConfigPath) {
  const LaunchConfig c = ParseLaunchConfig(R"(
hosts: {b: {address: hostb}}
services: [{name: rec, kind: recorder, host: b}]
)", "x.yaml");
  EXPECT_EQ(RemoteCommands(c, "/data/x.yaml", "/srv/build"),
            std::vector<std::string>{"[b] ssh hostb '/srv/build/bin/lockstep_recorder --name rec --config /data/x.yaml --domain 0'"});
}

// The error names `what` (a key path and the reason); prints the whole message if not.
#define EXPECT_ERROR(yaml, what)                                      \
  do {                                                                \
    const std::string message_ = ErrorOf(yaml);                       \
    EXPECT_NE(message_.find(what), std::string::npos) << message_;    \
  } while (0)

TEST(LaunchHosts, BadHostsAreErrorsThatNameThem) {
  EXPECT_ERROR("hosts: {gpu1: {address: a}}\nservices: [{name: s, kind: noop}, {name: t, kind: noop, host: gpu9}]\n",
               "cfg.yaml:2: key 'services[1].host' unknown host 'gpu9' (hosts: gpu1;");
  EXPECT_ERROR("services: [{name: t, kind: noop, host: gpu9}]\n", "no `hosts:` in this config");
  EXPECT_ERROR("hosts: {g: {address: a, container: podman}}\n", "hosts.g: give either 'address'");
  EXPECT_ERROR("hosts: {g: {}}\n", "hosts.g: give either");
  EXPECT_ERROR("hosts: {g: {container: lxc}}\n", "hosts.g.container: must be 'podman' or 'docker', got 'lxc'");
  EXPECT_ERROR("hosts: {g: {address: a, adress: b}}\n", "adress");
  EXPECT_ERROR("hosts: {g: {container: docker, build_dir: /x}}\n", "'build_dir' and 'config' are for a machine");
  EXPECT_ERROR("hosts: [a, b]\n", "key 'hosts' must be a map");
  EXPECT_ERROR("hosts: {localhost: {address: a}}\n", "names this machine");
}

TEST(LaunchRos2, Ros2AddsTheBridgeAsARequiredPerceptionService) {
  unsetenv("LOCKSTEP_ROS2");
  LaunchConfig c = ParseLaunchConfig("services: [{name: g, kind: ground_sim}]\n", "x.yaml");
  EXPECT_FALSE(c.ros2);
  EXPECT_EQ(c.services.size(), 1u);
  c = ParseLaunchConfig("ros2: true\nservices: [{name: g, kind: ground_sim}]\n", "x.yaml");
  ASSERT_EQ(c.services.size(), 2u);
  EXPECT_EQ(c.services[1].name, "ros2_bridge");
  EXPECT_EQ(c.services[1].kind, "ros2_bridge");
  EXPECT_TRUE(c.services[1].required);
  EXPECT_TRUE(c.services[1].perception);
  // `lockstep up --ros2` sets LOCKSTEP_ROS2=1 for itself and its children.
  setenv("LOCKSTEP_ROS2", "1", 1);
  c = ParseLaunchConfig("services: [{name: g, kind: ground_sim}]\n", "x.yaml");
  unsetenv("LOCKSTEP_ROS2");
  EXPECT_EQ(c.services.size(), 2u);
  // A bridge the config lists itself is not added twice.
  c = ParseLaunchConfig("ros2: true\nservices: [{name: view, kind: ros2_bridge, host: local}]\n", "x.yaml");
  EXPECT_EQ(c.services.size(), 1u);
  EXPECT_ERROR("ros2: true\nservices: [{name: ros2_bridge, kind: noop}]\n", "'ros2_bridge' is taken");
  EXPECT_ERROR("ros2: yes please\n", "ros2");
}

}  // namespace
}  // namespace lockstep::launcher
