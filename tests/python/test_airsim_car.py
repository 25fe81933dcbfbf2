"""AirSim's car mode against a running simulation (SimMode "Car", ground_sim's vehicles): the
settings' cars at their poses from the player start (the map's first vehicle spawn point, its
heading where the settings give no Yaw), reset() back to them, the VehicleClient calls
(poses, kinematics, collisions, IMU) addressing the car, API control held by the car across
processes, and the engine rpm of ground_sim's powertrain."""
import json
import math
import os
import subprocess
import sys

import pytest

from conftest import has_service

pytestmark = pytest.mark.skipif(not has_service('ground_sim') or not has_service('sensors'),
                                reason='needs ground_sim and sensors')

# Car2 8 m east of Car1 (NED Y): behind it on the first spawn point's road, which runs east-west
# in the generated town (both take the spawn point's heading, west).
SETTINGS = {
    'SettingsVersion': 1.2, 'SimMode': 'Car',
    'Vehicles': {
        'Car1': {'VehicleType': 'PhysXCar', 'X': 0, 'Y': 0, 'Z': 0},
        'Car2': {'VehicleType': 'PhysXCar', 'X': 0, 'Y': 8, 'Z': 0},
    }}


@pytest.fixture(scope='module')
def car(sim, tmp_path_factory):
    path = tmp_path_factory.mktemp('airsim') / 'settings.json'
    path.write_text(json.dumps(SETTINGS))
    os.environ['LOCKSTEP_AIRSIM_SETTINGS'] = str(path)
    import airsim
    c = airsim.CarClient()
    yield c
    os.environ.pop('LOCKSTEP_AIRSIM_SETTINGS', None)


def _ticks(c, n):
    for _ in range(n):
        c._client.tick()


def _enu(c, name):
    a = c._car(name)
    return c._client.state(a['id'])['transform']


def _drive(c, name, controls, ticks):
    c.enableApiControl(True, name)
    c.setCarControls(controls, name)
    _ticks(c, ticks)


def test_the_settings_cars_start_at_their_poses_on_the_road(car):
    import airsim
    assert car.listVehicles() == ['Car1', 'Car2']
    sp = car._client.map().spawn_points(2.0)[0]
    c1, c2 = _enu(car, 'Car1'), _enu(car, 'Car2')
    # Car1 at the player start (the first spawn point), Car2 8 m east of it (NED Y = ENU x).
    assert (c1[0], c1[1]) == (pytest.approx(sp[0], abs=0.05), pytest.approx(sp[1], abs=0.05))
    assert (c2[0] - c1[0], c2[1] - c1[1]) == (pytest.approx(8.0, abs=0.05), pytest.approx(0.0, abs=0.05))
    # No Yaw in the settings: the player start's heading (ENU yaw -> NED yaw = 90 deg - yaw).
    want = math.pi / 2 - sp[3]
    for name in ('Car1', 'Car2'):
        yaw = airsim.to_eularian_angles(car.simGetVehiclePose(name).orientation)[2]
        assert abs(math.remainder(yaw - want, 2 * math.pi)) < math.radians(1)
        assert car.simGetVehiclePose(name).position.get_length() < 0.1   # NED from its own start
    assert car.isApiControlEnabled('Car1') is False   # AirSim's cars start without API control


def test_the_vehicle_calls_address_the_car(car):
    """simGetVehiclePose, simSetVehiclePose, simGetGroundTruthKinematics, getImuData and
    getHomeGeoPoint on a CarClient are the car's (there is no drone in SimMode "Car")."""
    import airsim
    s = car.getCarState('Car1')
    p = car.simGetVehiclePose('Car1').position
    assert (p - s.kinematics_estimated.position).get_length() < 1e-6
    assert (car.simGetGroundTruthKinematics('Car1').position - p).get_length() < 1e-6
    imu = car.getImuData(vehicle_name='Car1')
    assert imu.linear_acceleration.z_val == pytest.approx(-9.81, abs=0.3)   # at rest: gravity up, FRD
    q = car.simGetVehiclePose('Car1').orientation
    assert abs(q.dot(imu.orientation)) == pytest.approx(1.0, abs=1e-3)
    home = car.getHomeGeoPoint('Car1')
    assert home.latitude != 0 or home.longitude != 0
    # Teleport Car2 4 m ahead along the road (west: NED Y -4) and back.
    start = car.simGetVehiclePose('Car2')
    car.simSetVehiclePose(airsim.Pose(airsim.Vector3r(0.0, -4.0, start.position.z_val), start.orientation), True, 'Car2')
    _ticks(car, 2)
    moved = car.simGetVehiclePose('Car2').position
    assert (moved.x_val, moved.y_val) == (pytest.approx(0.0, abs=0.05), pytest.approx(-4.0, abs=0.05))
    c2 = _enu(car, 'Car2')
    assert c2[0] - _enu(car, 'Car1')[0] == pytest.approx(4.0, abs=0.1)
    car.simSetVehiclePose(start, True, 'Car2')
    _ticks(car, 10)
    assert car.simGetVehiclePose('Car2').position.get_length() < 0.1


def test_rpm_is_the_engines(car):
    """getCarState().rpm: ground_sim's powertrain, the wheels' speed through the gear and the
    final drive (AirSim's GetEngineRotationSpeed), 0 at rest, at most maxrpm."""
    import airsim
    assert car.getCarState('Car1').rpm < 0.01   # at rest (the car settles at mm/s)
    _drive(car, 'Car1', airsim.CarControls(throttle=0.6), 30)
    s = car.getCarState('Car1')
    phys = car._client.vehicle_physics(car._car('Car1')['id'])
    assert s.speed > 2.0 and s.gear >= 1
    ratio = phys['forward_gears'][s.gear - 1][0] * phys['final_ratio']
    want = s.speed / phys['wheel_radius'] * ratio * 60 / (2 * math.pi)
    assert s.rpm == pytest.approx(max(want, 1000.0), rel=1e-6)
    assert 1000.0 <= s.rpm <= s.maxrpm == phys['max_rpm']


def test_reset_puts_the_cars_back_at_their_settings_poses(car):
    """AirSim's reset: every car at its start, at rest, CarControls() (CarPawnApi's
    resetImplementation), its collision cleared; API control stays the car's."""
    import airsim
    _drive(car, 'Car1', airsim.CarControls(throttle=1.0, steering=0.3), 40)
    assert car.simGetVehiclePose('Car1').position.get_length() > 2.0
    car.reset()
    _ticks(car, 3)
    s = car.getCarState('Car1')
    assert s.kinematics_estimated.position.get_length() < 0.1
    assert abs(s.speed) < 0.2
    assert car.getCarControls('Car1') == airsim.CarControls() or car.getCarControls('Car1').throttle == 0
    assert car.isApiControlEnabled('Car1') is True
    assert car._client.state(car._car('Car1')['id'])['control']['throttle'] == 0
    _ticks(car, 20)
    assert car.simGetVehiclePose('Car1').position.get_length() < 0.1   # nothing drives it on


def test_collision_info_is_the_cars(car):
    """Car2 driven into Car1 ahead of it: Car2's collision names Car1, with a time stamp in ns
    of simulation time; reset() clears it."""
    import airsim
    car.reset()
    _ticks(car, 3)
    assert car.simGetCollisionInfo('Car2').has_collided is False
    _drive(car, 'Car2', airsim.CarControls(throttle=0.8), 80)
    info = car.simGetCollisionInfo('Car2')
    assert info.has_collided is True and info.object_name == 'Car1'
    assert 0 < info.time_stamp <= car.simGetTime() * 1e9 + 1
    assert car.getCarState('Car2').collision.object_name == 'Car1'
    car.reset()
    _ticks(car, 3)
    assert car.simGetCollisionInfo('Car2').has_collided is False


def _in_another_process(code):
    """Runs `code` with `c = airsim.CarClient()` in a new Python process on the same simulation;
    its printed words."""
    prelude = 'import airsim\nc = airsim.CarClient()\n'
    r = subprocess.run([sys.executable, '-c', prelude + code], env=dict(os.environ), capture_output=True, text=True,
                       timeout=180)
    assert r.returncode == 0, r.stdout + r.stderr
    return r.stdout.split()


def test_api_control_is_the_cars_across_processes(car):
    """AirSim's API control belongs to the car: one process takes it, another sees it and its
    controls drive the car; released by one, the other's controls have no lasting effect."""
    import airsim
    car.enableApiControl(False, 'Car2')
    _ticks(car, 1)
    assert _in_another_process("print(c.isApiControlEnabled('Car2')); c.enableApiControl(True, 'Car2'); "
                               "print(c.isApiControlEnabled('Car2'))") == ['False', 'True']
    _ticks(car, 1)
    assert car.isApiControlEnabled('Car2') is True   # taken by the other process
    car.setCarControls(airsim.CarControls(brake=0.5), 'Car2')
    _ticks(car, 1)
    assert car._client.state(car._car('Car2')['id'])['control']['brake'] == pytest.approx(0.5)
    assert _in_another_process("print(c.getCarControls('Car2').brake); c.enableApiControl(False, 'Car2')") == ['0.5']
    _ticks(car, 1)
    assert car.isApiControlEnabled('Car2') is False
    car.setCarControls(airsim.CarControls(throttle=1.0), 'Car2')
    _ticks(car, 1)
    assert car._client.state(car._car('Car2')['id'])['control']['throttle'] == 0


def test_a_vehicle_client_addresses_the_cars(car):
    """SimMode "Car": a VehicleClient's calls are the cars' (there is no drone to address)."""
    import airsim
    v = airsim.VehicleClient()
    assert isinstance(v, airsim.VehicleClient)
    p = v.simGetVehiclePose('Car1').position
    assert (p - car.simGetVehiclePose('Car1').position).get_length() < 1e-9
    assert v.isApiControlEnabled('Car2') == car.isApiControlEnabled('Car2')
