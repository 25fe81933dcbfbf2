"""carla and airsim calls against a running simulation: ticks, settings, blueprints from
the services' declarations, spawn errors with the service's reason, maps, drones, and
sensors in synchronous mode delivering every frame once and in order."""
import math
import os

import numpy as np
import pytest

import airsim
import carla
import lockstep

from conftest import has_service


@pytest.fixture(scope='module')
def world(sim):
    client = carla.Client('localhost', 2000)
    client.set_timeout(30)
    w = client.get_world()
    s = w.get_settings()
    assert s.synchronous_mode
    return w


def test_tick_returns_consecutive_frames(world):
    frames = [world.tick() for _ in range(10)]
    assert frames == list(range(frames[0], frames[0] + 10))
    snap = world.get_snapshot()
    assert snap.frame == frames[-1]
    assert snap.timestamp.delta_seconds == pytest.approx(0.05)
    assert snap.timestamp.elapsed_seconds == pytest.approx(frames[-1] * 0.05)


def test_settings_round_trip(world):
    s = world.get_settings()
    s.fixed_delta_seconds = 0.02
    world.apply_settings(s)
    assert world.get_settings().fixed_delta_seconds == pytest.approx(0.02)
    s.fixed_delta_seconds = 0.05
    world.apply_settings(s)
    bad = world.get_settings()
    bad.real_time_factor = -1.0  # Lockstep's own setting; CARLA's fixed_delta_seconds takes any step > 0
    with pytest.raises(lockstep.CommandRejected, match='real_time_factor'):
        world.apply_settings(bad)


def test_blueprint_library_comes_from_the_services(world):
    lib = world.get_blueprint_library()
    drones = lib.filter('drone.*')
    assert len(drones) >= 1  # declared by air_sim
    bp = lib.find('drone.generic_quad')
    assert bp.has_attribute('role_name')
    with pytest.raises(IndexError, match='not found'):
        lib.find('vehicle.nobody.declares')
    with pytest.raises(IndexError, match='no attribute'):
        bp.get_attribute('no_such_attribute')


def test_bad_calls_raise_with_the_services_reason(world):
    t = carla.Transform(carla.Location(47.75, -1.75, 0.2))
    lib = world.get_blueprint_library()
    bp = lib.find('drone.generic_quad')
    # Unknown blueprint and unknown attribute: the coordinator's reason reaches Python.
    with pytest.raises(lockstep.CommandRejected, match='unknown blueprint') as e:
        world._client.spawn('vehicle.does_not.exist', (0, 0, 0, 1, 0, 0, 0))
    assert 'vehicle.does_not.exist' in e.value.reason
    with pytest.raises(lockstep.CommandRejected, match='no_such_attribute'):
        world._client.spawn('drone.generic_quad', (0, 0, 0, 1, 0, 0, 0), {'no_such_attribute': '1'})
    # A bad attribute value is refused by set_attribute, like CARLA.
    numeric = [a for a in bp if a.type in ('float', 'int') and a.is_modifiable and math.isfinite(a._decl['max'])]
    if numeric:
        with pytest.raises(IndexError, match=numeric[0].id):
            bp.set_attribute(numeric[0].id, str(numeric[0]._decl['max'] + 1000))
        with pytest.raises(ValueError, match=numeric[0].id):
            bp.set_attribute(numeric[0].id, 'abc')
    # A destroyed actor.
    drone = world.spawn_actor(bp, t)
    world.tick()
    assert drone.is_alive
    assert drone.destroy()
    world.tick()
    assert not drone.is_alive
    with pytest.raises(lockstep.CommandRejected, match='unknown actor') as e:
        world._client.destroy(drone.id)
    assert 'unknown actor' in e.value.reason
    with pytest.raises(lockstep.CommandRejected, match='unknown actor'):
        drone.set_transform(t)


def test_nan_control_is_rejected(world):
    if has_service('ground_sim'):
        lib = world.get_blueprint_library()
        car = world.spawn_actor(lib.filter('vehicle.*')[0], world.get_map().get_spawn_points()[5])
        try:
            with pytest.raises(lockstep.CommandRejected, match='NaN'):
                car.apply_control(carla.VehicleControl(throttle=float('nan')))
        finally:
            car.destroy()
    bp = world.get_blueprint_library().find('drone.generic_quad')
    bp.set_attribute('role_name', 'nan_test')
    drone = world.spawn_actor(bp, carla.Transform(carla.Location(43.25, 1.75, 0.2)))
    world.tick()
    try:
        c = airsim.MultirotorClient()
        c.enableApiControl(True, 'nan_test')
        with pytest.raises(lockstep.CommandRejected, match='NaN'):
            c.moveToPositionAsync(float('nan'), 0, -3, 2, vehicle_name='nan_test')
    finally:
        drone.destroy()


def test_map_and_waypoints(world):
    m = world.get_map()
    assert m.name == 'LockstepTown1'
    points = m.get_spawn_points()
    assert len(points) > 10
    wp = m.get_waypoint(points[0].location)
    assert wp.lane_type == carla.LaneType.Driving
    assert wp.transform.location.distance(points[0].location) < 3.0
    nxt = wp.next(5.0)
    assert nxt and all(abs(n.transform.location.distance(wp.transform.location) - 5.0) < 1.0 for n in nxt)
    assert len(m.get_topology()) > 0
    assert '<OpenDRIVE' in m.to_opendrive()  # the generated town's .xodr (test_carla_compat_api.py)


def test_weather(world):
    world.set_weather(carla.WeatherParameters.WetCloudyNoon)
    assert world.get_weather().precipitation_deposits == 50
    with pytest.raises(lockstep.CommandRejected, match='cloudiness'):
        world.set_weather(carla.WeatherParameters(cloudiness=500))
    world.set_weather(carla.WeatherParameters.ClearNoon)


def test_unsupported_calls_name_themselves(world):
    with pytest.raises(carla.LockstepUnsupported, match='World.load_map_layer'):
        world.load_map_layer(carla.MapLayer.Buildings)


def test_airsim_drone_flies_in_ned_from_its_spawn(world):
    bp = world.get_blueprint_library().find('drone.generic_quad')
    bp.set_attribute('role_name', 'ned')
    start = carla.Transform(carla.Location(47.75, -1.75, 0.2))
    drone = world.spawn_actor(bp, start)
    for _ in range(20):  # 1 s: it drops the 0.2 m and settles (AirSim refuses takeoff while moving)
        world.tick()
    try:
        c = airsim.MultirotorClient()
        assert 'ned' in c.listVehicles()
        c.enableApiControl(True, 'ned')
        assert c.armDisarm(True, 'ned')
        assert c.takeoffAsync(vehicle_name='ned').join()
        # Along the road (east), clear of the town's buildings and trees.
        assert c.moveToPositionAsync(0.5, 10, -6, 3, vehicle_name='ned').join()
        p = c.getMultirotorState(vehicle_name='ned').kinematics_estimated.position
        assert (p.x_val, p.y_val, p.z_val) == (pytest.approx(0.5, abs=0.5), pytest.approx(10, abs=0.5),
                                               pytest.approx(-6, abs=0.5))
        # The same place through the carla API: x east = start.x + 10, carla y = start.y - 0.5 (north is -y).
        loc = drone.get_location()
        assert (loc.x, loc.y, loc.z) == (pytest.approx(57.75, abs=0.5), pytest.approx(-2.25, abs=0.5),
                                         pytest.approx(6.2, abs=0.5))
        frame = c._client.frame()
        c.simContinueForFrames(7)
        assert c._client.frame() == frame + 7
        assert c.simIsPause()
    finally:
        drone.destroy()


def test_a_rejected_drone_command_raises_air_sims_reason(world):
    bp = world.get_blueprint_library().find('drone.generic_quad')
    bp.set_attribute('role_name', 'falling')
    drone = world.spawn_actor(bp, carla.Transform(carla.Location(43.25, -1.75, 3.0)))
    world.tick()
    world.tick()  # falling by now
    try:
        c = airsim.MultirotorClient()
        c.enableApiControl(True, 'falling')
        c.armDisarm(True, 'falling')
        with pytest.raises(lockstep.CommandRejected, match='cannot take off while moving'):
            c.takeoffAsync(vehicle_name='falling').join()
    finally:
        drone.destroy()


def test_airsim_second_pass_calls(world):
    """moveToZ, moveByRollPitchYawrateZ, moveToGPS, simSetWind, simSetKinematics and the controller gains reach
    air_sim and move the drone the way AirSim's would."""
    bp = world.get_blueprint_library().find('drone.generic_quad')
    bp.set_attribute('role_name', 'second')
    drone = world.spawn_actor(bp, carla.Transform(carla.Location(43.25, 1.75, 0.2)))
    for _ in range(20):
        world.tick()
    c = airsim.MultirotorClient()
    try:
        c.enableApiControl(True, 'second')
        c.armDisarm(True, 'second')
        assert c.takeoffAsync(vehicle_name='second').join()

        def pos():
            p = c.getMultirotorState(vehicle_name='second').kinematics_estimated.position
            return p.x_val, p.y_val, p.z_val
        x0, y0, _ = pos()
        assert c.moveToZAsync(-7, 2, vehicle_name='second').join()
        x, y, z = pos()
        assert (x, y, z) == (pytest.approx(x0, abs=0.5), pytest.approx(y0, abs=0.5), pytest.approx(-7, abs=0.5))

        # A yaw rate of +0.5 rad/s (clockwise seen from above, NED) for 1 s, level, at 7 m.
        yaw0 = airsim.to_eularian_angles(c.simGetVehiclePose('second').orientation)[2]
        c.moveByRollPitchYawrateZAsync(0, 0, 0.5, -7, 1, vehicle_name='second').join()
        yaw1 = airsim.to_eularian_angles(c.simGetVehiclePose('second').orientation)[2]
        assert 0.2 < (yaw1 - yaw0 + math.pi) % (2 * math.pi) - math.pi < 0.8

        # 10 m east through the map's geo-reference.
        gps = c.getGpsData(vehicle_name='second').gnss.geo_point
        x0, y0, _ = pos()
        lon = gps.longitude + math.degrees(10 / (6378137.0 * math.cos(math.radians(gps.latitude))))
        assert c.moveToGPSAsync(gps.latitude, lon, gps.altitude, 3, vehicle_name='second').join()
        x, y, _ = pos()
        assert (x, y) == (pytest.approx(x0, abs=1.0), pytest.approx(y0 + 10, abs=1.0))

        # Wind from the south (blowing north) pushes a level drone that holds no position.
        c.simSetWind(airsim.Vector3r(6, 0, 0))
        x0, _, _ = pos()
        c.moveByRollPitchYawrateZAsync(0, 0, 0, -7, 2, vehicle_name='second').join()
        assert c.getMultirotorState(vehicle_name='second').kinematics_estimated.linear_velocity.x_val > 0.3
        c.simSetWind(airsim.Vector3r(0, 0, 0))

        # simSetKinematics: a pose and a velocity at once.
        k = airsim.KinematicsState()
        k.position = airsim.Vector3r(0, 0, -9)
        k.orientation = airsim.to_quaternion(0, 0, 0)
        k.linear_velocity = airsim.Vector3r(0, 2, 0)
        c.simSetKinematics(k, True, 'second')
        # One tick through the airsim client, whose tick waits for the frame's air state: after
        # world.tick() (the carla client's) the airsim client could still hold the frame before.
        c.simContinueForFrames(1)
        s = c.getMultirotorState(vehicle_name='second').kinematics_estimated
        # From 7 m up to 9 m in one tick: the pose was set.
        assert (s.position.x_val, s.position.z_val) == (pytest.approx(0, abs=1.0), pytest.approx(-9, abs=0.3))
        assert s.linear_velocity.y_val == pytest.approx(2, abs=0.5)

        c.setVelocityControllerGains(vehicle_name='second')  # AirSim's defaults
        with pytest.raises(airsim.LockstepUnsupported, match='setAngleLevelControllerGains with kd'):
            c.setAngleLevelControllerGains(airsim.AngleLevelControllerGains(roll_gains=airsim.PIDGains(2.5, 0, 1)),
                                           vehicle_name='second')
        assert c.hoverAsync(vehicle_name='second').join()
    finally:
        c.simSetWind(airsim.Vector3r(0, 0, 0))
        drone.destroy()


def _per_frame_sensors(world):
    lib = world.get_blueprint_library()
    wanted = ['sensor.camera.rgb', 'sensor.camera.depth', 'sensor.lidar.ray_cast', 'sensor.other.imu',
              'sensor.other.gnss', 'sensor.camera.semantic_segmentation', 'sensor.other.barometer']
    have = [w for w in wanted if len(lib.filter(w))]
    out = []
    while len(out) < 6:
        out.append(have[len(out) % len(have)])
    return out


def test_carla_and_airsim_clients_of_a_script_are_one_session(world):
    """A script's carla.Client and airsim.MultirotorClient share the process's DDS session: after
    world.tick() the airsim client reads that very frame. Two sessions could still hold the frame
    before for a moment (python.world once failed so)."""
    bp = world.get_blueprint_library().find('drone.generic_quad')
    bp.set_attribute('role_name', 'shared_session')
    drone = world.spawn_actor(bp, carla.Transform(carla.Location(43.25, 1.75, 0.2)))
    try:
        c = airsim.MultirotorClient()
        assert c._client is world._client
        assert lockstep.session() is world._client
        for _ in range(50):
            world.tick()
            elapsed = world.get_snapshot().timestamp.elapsed_seconds
            assert c.getMultirotorState(vehicle_name='shared_session').timestamp == int(elapsed * 1e9)
    finally:
        drone.destroy()


def test_six_sensors_over_500_ticks_deliver_every_frame_once_and_in_order(world, tmp_path):
    names = _per_frame_sensors(world)
    lib = world.get_blueprint_library()
    base = carla.Transform(carla.Location(47.75, -1.75, 2.0))
    sensors, seen = [], {}
    for i, name in enumerate(names):
        bp = lib.find(name)
        if bp.has_attribute('image_size_x'):
            bp.set_attribute('image_size_x', '64')
            bp.set_attribute('image_size_y', '48')
        s = world.spawn_actor(bp, carla.Transform(base.location + carla.Location(x=i)))
        sensors.append(s)
        seen[s.id] = []
    world.tick()  # the spawn frame
    images = []

    def make_cb(sid):
        def cb(data):
            seen[sid].append(data.frame)
            if isinstance(data, carla.Image) and len(images) < 2:
                images.append(data)
        return cb

    for s in sensors:
        s.listen(make_cb(s.id))
    try:
        first = None
        for _ in range(500):
            k = world.tick()
            first = first or k
            for s in sensors:
                assert seen[s.id] and seen[s.id][-1] == k, '%s: frame %d missing at tick return' % (s.type_id, k)
        for s in sensors:
            assert seen[s.id] == list(range(first, first + 500)), s.type_id
        if images:
            img = images[0]
            a = img.to_numpy()
            assert a.shape[:2] == (img.height, img.width)
            assert not a.flags.writeable and a.base is not None  # a view of the received sample
            path = img.save_to_disk(str(tmp_path / '%06d.png'))
            assert os.path.getsize(path) > 0
    finally:
        for s in sensors:
            s.stop()
            s.destroy()


def test_a_client_that_joins_later_sees_the_actors_blueprints_and_attributes(world):
    """Client A spawns; client B, another process started afterwards, finds the actor by
    role_name in get_actors() (the coordinator's lockstep/actors list)."""
    import subprocess
    import sys
    lib = world.get_blueprint_library()
    bp = lib.find('drone.generic_quad')
    bp.set_attribute('role_name', 'hero')
    hero = world.spawn_actor(bp, carla.Transform(carla.Location(47.75, 5.25, 0.2)))
    spawned = [hero]
    if has_service('ground_sim'):
        car_bp = lib.find('vehicle.tesla.model3')
        car_bp.set_attribute('role_name', 'late_car')
        car_bp.set_attribute('color', '10,20,30')
        car = world.try_spawn_actor(car_bp, world.get_map().get_spawn_points()[3])
        if car is not None:
            spawned.append(car)
    world.tick()
    gone = world.spawn_actor(bp, carla.Transform(carla.Location(43.25, 5.25, 0.2)))
    world.tick()
    gone.destroy()
    world.tick()
    script = ("import carla\n"
              "w = carla.Client('localhost', 2000).get_world()\n"
              "for a in w.get_actors():\n"
              "    print(a.id, a.type_id, a.attributes.get('role_name', ''), a.attributes.get('color', ''))\n")
    try:
        out = subprocess.run([sys.executable, '-c', script], capture_output=True, text=True, timeout=120)
        assert out.returncode == 0, out.stderr
        rows = [line.split(' ') for line in out.stdout.splitlines()]
        heroes = [r for r in rows if r[2] == 'hero']
        assert [(int(r[0]), r[1]) for r in heroes] == [(hero.id, 'drone.generic_quad')], out.stdout
        assert str(gone.id) not in [r[0] for r in rows]
        if len(spawned) > 1:
            cars = [r for r in rows if r[2] == 'late_car']
            assert [(int(r[0]), r[1], r[3]) for r in cars] == [(spawned[1].id, 'vehicle.tesla.model3', '10,20,30')]
    finally:
        for a in spawned:
            a.destroy()
        world.tick()


def test_get_actors_of_ids_keeps_the_order_asked_for(world):
    # CARLA's World.get_actors(ids) answers in the order of the ids (its cached actor list);
    # generate_traffic.py pairs each walker controller with its walker by that order.
    lib = world.get_blueprint_library()
    drones = []
    for i in range(3):
        bp = lib.find('drone.generic_quad')
        bp.set_attribute('role_name', 'order%d' % i)
        drones.append(world.spawn_actor(bp, carla.Transform(carla.Location(60.0 + 4 * i, -30.0, 5.0))))
    world.tick()
    ids = [drones[2].id, drones[0].id, 987654, drones[1].id]
    assert [a.id for a in world.get_actors(ids)] == [drones[2].id, drones[0].id, drones[1].id]
    for d in drones:
        d.destroy()


def test_the_first_tick_after_spawn_and_listen_brings_the_data_of_that_frame(world):
    # CARLA: spawn a sensor, listen, tick: the tick's frame has the sensor's data
    # (synchronous_mode.py waits 2 s for exactly that frame). The sensor exists from the
    # tick that carries its spawn, so that tick's data is expected and awaited.
    lib = world.get_blueprint_library()
    ids = [bp.id for bp in lib.filter('sensor.*')]
    wanted = [b for b in ('sensor.other.imu', 'sensor.camera.rgb', 'sensor.lidar.ray_cast') if b in ids] or ids[:1]
    for blueprint in wanted:
        sensor = world.spawn_actor(lib.find(blueprint), carla.Transform(carla.Location(50.0, -20.0, 3.0)))
        frames = []
        sensor.listen(lambda data: frames.append(data.frame))
        frame = world.tick()
        assert frames == [frame], (blueprint, frames, frame)
        assert world.tick() == frame + 1 and frames == [frame, frame + 1], blueprint
        sensor.destroy()


def test_vehicle_light_state_is_carlas_flag_type():
    # manual_control.py: lights ^= carla.VehicleLightState.Position, then
    # set_light_state(carla.VehicleLightState(lights)); CARLA's enum takes any bits.
    bits = carla.VehicleLightState.NONE
    bits ^= carla.VehicleLightState.Position
    bits |= carla.VehicleLightState.LowBeam
    state = carla.VehicleLightState(int(bits))
    assert int(state) == 3 and state & carla.VehicleLightState.LowBeam
    assert not state & carla.VehicleLightState.Brake
    assert int(carla.VehicleLightState(0xFFFFFFFF)) == int(carla.VehicleLightState.All)
