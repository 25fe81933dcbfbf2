"""A script that hosts the coordinator of its simulation (lockstep.Coordinator), whose
services `lockstep up CONFIG --no-coordinator` started: the drop-in clients tick it as any
other, and the clock stops with the script's close()."""
import os
import signal
import subprocess

import pytest

import airsim
import carla
import lockstep

from conftest import BIN, DOMAIN


def _config(directory):
    town = os.path.join(os.path.dirname(BIN), 'maps', 'generated', 'LockstepTown1.xodr')
    path = os.path.join(directory, 'embedded.yaml')
    with open(path, 'w') as f:
        f.write('name: embedded\ndomain_id: %d\nseed: 5\nmap: %s\nworld:\n  synchronous_mode: true\n'
                '  fixed_delta_seconds: 0.05\n  service_timeout: 30\nservices:\n  - {name: air_sim, kind: air_sim}\n'
                % (DOMAIN, town))
    return path


def test_a_script_hosts_the_coordinator_of_the_services_lockstep_up_started(tmp_path):
    config = _config(str(tmp_path))
    log_path = str(tmp_path / 'up.log')
    with open(log_path, 'w') as log:
        up = subprocess.Popen([os.path.join(BIN, 'lockstep'), 'up', config, '--no-coordinator'], stdout=log,
                              stderr=subprocess.STDOUT)
        try:
            with lockstep.Coordinator(config) as coordinator:
                assert coordinator.running and coordinator.domain == DOMAIN
                client = carla.Client('localhost', 2000)
                client.set_timeout(30)
                world = client.get_world()
                assert world._client.wait_ready(60), open(log_path).read()
                frames = [world.tick() for _ in range(20)]
                assert frames == list(range(frames[0], frames[0] + 20))
                # This coordinator, and no other, completed every frame.
                assert coordinator.stats()['frames'] == frames[-1]
                # air_sim, a process of `lockstep up`, steps with it: a drone climbs.
                bp = world.get_blueprint_library().find('drone.generic_quad')
                bp.set_attribute('role_name', 'embedded')
                drone = world.spawn_actor(bp, carla.Transform(carla.Location(43.25, 1.75, 0.2)))
                for _ in range(40):  # it settles on the road (AirSim refuses a takeoff while it moves)
                    world.tick()
                c = airsim.MultirotorClient()
                c.enableApiControl(True, 'embedded')
                c.armDisarm(True, 'embedded')
                c.takeoffAsync(vehicle_name='embedded').join()
                assert c.getMultirotorState(vehicle_name='embedded').kinematics_estimated.position.z_val < -1.0
                drone.destroy()
                del c, drone, world, client
            assert not coordinator.running
            assert coordinator.close() == 0
        finally:
            up.send_signal(signal.SIGINT)
            up.wait(30)
    out = open(log_path).read()
    assert "no coordinator (a script hosts it), 1 service(s)" in out, out


def test_a_bad_config_names_the_file():
    with pytest.raises(ValueError, match='no_such_config.yaml: cannot open'):
        lockstep.Coordinator('/nonexistent/no_such_config.yaml')
