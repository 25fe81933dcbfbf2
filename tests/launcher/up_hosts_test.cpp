// `lockstep up` across hosts, end to end: the services of this machine start, the others'
// exact commands are printed (and the run waits for the required ones), a bad host is
// refused before anything starts.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "process.h"

namespace lockstep::testing {
namespace {

using namespace std::chrono_literals;

TEST(LockstepUp, StartsTheLocalServicesAndPrintsTheOthersCommands) {
  const int domain = TestDomain();
  const std::string config = WriteTempFile("hosts.yaml", R"(name: split
participant_profile: lockstep.participant.loopback
recorder: false
ticks: 20
hosts:
  far: {address: sim@hostb, build_dir: /opt/lockstep/build}
  boxes: {container: docker, network: simnet}
services:
  - {name: here, kind: noop}
  - {name: there, kind: noop, host: far, required: false}
  - {name: boxed, kind: noop, host: boxes, required: false, args: [--participant-profile, lockstep.participant.udp]}
)");
  const std::string cfg = std::filesystem::absolute(config).lexically_normal().string();
  const std::string dir = std::filesystem::path(cfg).parent_path().string();
  const std::string d = std::to_string(domain);
  Process up({Bin("lockstep"), "up", config, "--domain", d});
  const auto code = up.Wait(60s);
  ASSERT_TRUE(code) << "lockstep up did not finish:\n" << up.Output();
  EXPECT_EQ(*code, 0) << up.Output();
  const std::string out = up.Output();
  EXPECT_NE(out.find("coordinator + 1 service(s)"), std::string::npos) << out;
  EXPECT_NE(out.find("2 service(s) run on other hosts"), std::string::npos) << out;
  EXPECT_NE(out.find("  [far] ssh sim@hostb '/opt/lockstep/build/bin/lockstep_noop --name there --config " + cfg + " --domain " + d + "'\n"),
            std::string::npos)
      << out;
  EXPECT_NE(out.find("  [boxes] docker run -d --name boxed --network simnet -v " + dir + ":/etc/lockstep:ro -e LOCKSTEP_DOMAIN=" + d +
                     " localhost/lockstep/noop --name boxed --config /etc/lockstep/hosts.yaml --domain " + d +
                     " --participant-profile lockstep.participant.udp\n"),
            std::string::npos)
      << out;
  EXPECT_NE(out.find("loopback keeps DDS on this machine"), std::string::npos) << out;
  EXPECT_NE(out.find("here        | info: stopping after frame 20"), std::string::npos) << out;
  EXPECT_EQ(out.find("there       |"), std::string::npos) << "a remote service was started here:\n" << out;
}

TEST(LockstepUp, AnUnknownHostIsRefusedBeforeAnythingStarts) {
  const std::string config = WriteTempFile("badhost.yaml", R"(services:
  - {name: here, kind: noop}
  - {name: there, kind: noop, host: gpu7}
)");
  Process up({Bin("lockstep"), "up", config, "--domain", std::to_string(TestDomain())});
  const auto code = up.Wait(30s);
  ASSERT_TRUE(code) << up.Output();
  EXPECT_EQ(*code, 2) << up.Output();
  EXPECT_NE(up.Output().find("key 'services[1].host' unknown host 'gpu7' (no `hosts:` in this config;"), std::string::npos) << up.Output();
  EXPECT_EQ(up.Output().find("starting"), std::string::npos) << up.Output();
}

// `lockstep up --ros2` (CARLA's server --ros2): the launcher and its children see the flag,
// so the coordinator requires the ros2_bridge the launcher starts, and it steps every frame.
TEST(LockstepUp, Ros2FlagAddsTheBridgeToTheRun) {
  const std::string config = WriteTempFile("ros2flag.yaml", R"(name: flag
participant_profile: lockstep.participant.loopback
recorder: false
ticks: 20
services:
  - {name: here, kind: noop}
)");
  Process up({Bin("lockstep"), "up", config, "--domain", std::to_string(TestDomain()), "--ros2"});
  const auto code = up.Wait(60s);
  ASSERT_TRUE(code) << "lockstep up did not finish:\n" << up.Output();
  EXPECT_EQ(*code, 0) << up.Output();
  EXPECT_NE(up.Output().find("coordinator + 2 service(s)"), std::string::npos) << up.Output();
  EXPECT_NE(up.Output().find("ros2_bridge | info: stopping after frame 20"), std::string::npos) << up.Output();
}

// `lockstep up --record-sensors SPEC` reaches the recorder (the log's header names the
// selection); a selection that is none of the forms is refused before anything starts.
TEST(LockstepUp, RecordSensorsReachesTheRecorderAndABadSelectionIsRefused) {
  const std::string out_dir = std::filesystem::absolute(WriteTempFile("rs.keep", "")).parent_path().string() + "/rs_out";
  std::filesystem::remove_all(out_dir);
  const std::string config = WriteTempFile("recsensors.yaml", "name: rs\nparticipant_profile: lockstep.participant.loopback\n"
                                                              "recorder: false\nticks: 20\noutput_dir: " + out_dir + "\n" + R"(services:
  - {name: here, kind: noop}
  - {name: recorder, kind: recorder, perception: true, args: [--record-run]}
)");
  Process bad({Bin("lockstep"), "up", config, "--domain", std::to_string(TestDomain()), "--record-sensors", "colour=red"});
  const auto bad_code = bad.Wait(30s);
  ASSERT_TRUE(bad_code) << bad.Output();
  EXPECT_EQ(*bad_code, 2) << bad.Output();
  EXPECT_NE(bad.Output().find("--record-sensors: sensor selection 'colour=red'"), std::string::npos) << bad.Output();
  EXPECT_EQ(bad.Output().find("starting"), std::string::npos) << bad.Output();

  Process up({Bin("lockstep"), "up", config, "--domain", std::to_string(TestDomain()), "--record-sensors", "sensor.camera.*"});
  const auto code = up.Wait(60s);
  ASSERT_TRUE(code) << "lockstep up did not finish:\n" << up.Output();
  ASSERT_EQ(*code, 0) << up.Output();
  const std::string log = out_dir + "/run1/recording.lslog";
  ASSERT_TRUE(std::filesystem::exists(log)) << up.Output();
  Process info({Bin("lockstep"), "log", "info", log});
  ASSERT_TRUE(info.Wait(30s)) << info.Output();
  EXPECT_NE(info.Output().find("selection 'sensor.camera.*'"), std::string::npos) << info.Output();
}

}  // namespace
}  // namespace lockstep::testing
