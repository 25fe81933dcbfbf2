"""CARLA's world as a script sees it: the collision check at spawn (try_spawn_actor on an
occupied spawn point returns None, no ghost actor), world.debug shapes drawn into the
render service's cameras for their life time, vehicle lights lit at night (set_light_state,
TrafficManager.update_vehicle_lights), and `lockstep serve`."""
import contextlib
import fcntl
import os
import signal
import subprocess
import sys
import tempfile

import numpy as np
import pytest

import carla
import lockstep

from conftest import BIN, has_service

needs_ground = pytest.mark.skipif(not has_service('ground_sim'), reason='ground_sim is not built')
needs_render = pytest.mark.skipif(not has_service('render'), reason='the render service is not built')

W, H = 160, 120


@pytest.fixture(scope='module')
def world(sim):
    client = carla.Client('localhost', 2000)
    client.set_timeout(30)
    w = client.get_world()
    assert w.get_settings().synchronous_mode
    return w


class Camera:
    """An RGB camera with a fixed exposure whose images are kept by frame."""

    def __init__(self, world, transform):
        bp = world.get_blueprint_library().find('sensor.camera.rgb')
        bp.set_attribute('image_size_x', str(W))
        bp.set_attribute('image_size_y', str(H))
        bp.set_attribute('fov', '90')
        bp.set_attribute('exposure_mode', 'manual')  # no eye adaptation from image to image
        self.actor = world.spawn_actor(bp, transform)
        self.frames = {}
        self.actor.listen(lambda img: self.frames.__setitem__(img.frame, np.array(img.to_numpy()[:, :, :3])))

    def destroy(self):
        self.actor.stop()
        self.actor.destroy()


def _far_spawn_points(world, n):
    """n spawn points at least 30 m from each other."""
    out = []
    for sp in world.get_map().get_spawn_points():
        if all(sp.location.distance(o.location) > 30 for o in out):
            out.append(sp)
        if len(out) == n:
            return out
    pytest.skip('the town has fewer than %d spread spawn points' % n)


@needs_ground
def test_a_spawn_on_an_occupied_spawn_point_fails_as_carlas_and_leaves_no_ghost(world):
    sp = _far_spawn_points(world, 1)[0]
    bp = world.get_blueprint_library().find('vehicle.audi.tt')
    before = {a.id for a in world.get_actors().filter('vehicle.*')}
    first = world.try_spawn_actor(bp, sp)
    assert first is not None
    try:
        # No tick yet: the first car is only a spawn for the next tick, and still takes the spot.
        assert world.try_spawn_actor(bp, sp) is None
        with pytest.raises(RuntimeError, match='Spawn failed because of collision at spawn position'):
            world.spawn_actor(bp, sp)
        client = carla.Client('localhost', 2000)
        responses = client.apply_batch_sync([carla.command.SpawnActor(bp, sp)], True)
        assert len(responses) == 1 and responses[0].has_error()
        assert 'collision at spawn position' in responses[0].error
        world.tick()
        world.tick()
        now = {a.id for a in world.get_actors().filter('vehicle.*')} - before
        assert now == {first.id}, 'exactly the accepted car, no ghost'
        assert world.try_spawn_actor(bp, sp) is None, 'the car is in the state now'
    finally:
        first.destroy()
    world.tick()
    again = world.try_spawn_actor(bp, sp)
    assert again is not None, 'free again once the car is gone'
    again.destroy()
    world.tick()


def _green(img):
    """Pixels of pure green (the drawn box's colour): BGR (0, 255, 0)."""
    return (img[:, :, 0] == 0) & (img[:, :, 1] == 255) & (img[:, :, 2] == 0)


@needs_render
def test_a_debug_box_is_drawn_into_the_camera_for_its_life_time(world):
    sp = _far_spawn_points(world, 2)[1]
    fwd = sp.get_forward_vector()
    eye = carla.Transform(sp.location + carla.Location(z=2.0), carla.Rotation(yaw=sp.rotation.yaw))
    cam = Camera(world, eye)
    try:
        world.tick()
        k0 = world.tick()
        assert k0 in cam.frames
        assert _green(cam.frames[k0]).sum() == 0
        # A 2 m box 12 m straight ahead, green edges 0.2 m thick, for 0.5 s (10 frames at 0.05 s).
        centre = eye.location + carla.Location(x=fwd.x * 12, y=fwd.y * 12, z=fwd.z * 12)
        world.debug.draw_box(carla.BoundingBox(centre, carla.Vector3D(1, 1, 1)), eye.rotation, thickness=0.2,
                             color=carla.Color(0, 255, 0), life_time=0.5)
        # CARLA's HUD shapes and strings are not in camera images.
        world.debug.draw_hud_box(carla.BoundingBox(centre, carla.Vector3D(2, 2, 2)), eye.rotation,
                                 color=carla.Color(0, 0, 255), life_time=0.5)
        world.debug.draw_string(centre, 'hello', color=carla.Color(0, 0, 255), life_time=0.5)
        k1 = world.tick()
        img = cam.frames[k1]
        green = _green(img)
        assert green.sum() > 50, 'the box edges are drawn'
        ys, xs = np.nonzero(green)
        # A 2 m box at 12 m with a 90 deg lens: about 13 px either side of the image centre.
        assert abs(xs.mean() - W / 2) < 4 and abs(ys.mean() - H / 2) < 4
        assert xs.min() > W / 2 - 20 and xs.max() < W / 2 + 20
        before = cam.frames[k0]
        far = np.ones((H, W), bool)
        far[H // 2 - 25:H // 2 + 25, W // 2 - 25:W // 2 + 25] = False
        assert (np.abs(img.astype(int) - before.astype(int)).max(axis=2)[far] == 0).all(), 'nothing else changes'
        blue = (img[:, :, 0] == 255) & (img[:, :, 1] == 0) & (img[:, :, 2] == 0)
        assert blue.sum() == 0, 'no HUD shape or string in a camera'
        # Issued at frame k0's time: drawn while the frame's time is before k0 + 0.5 s.
        last = k1
        for _ in range(12):
            last = world.tick()
            expected = (last - k0) * 0.05 < 0.5 - 1e-6
            assert (_green(cam.frames[last]).sum() > 50) == expected, 'frame %d, %d after the draw' % (last, last - k0)
        assert _green(cam.frames[last]).sum() == 0
    finally:
        cam.destroy()


@needs_render
def test_debug_calls_take_carlas_arguments(world):
    d = world.debug
    loc = carla.Location(1, 2, 3)
    assert d.draw_point(loc) is None
    d.draw_point(loc, size=0.075, life_time=0.06, persistent_lines=False, color=carla.Color(255, 0, 0))
    d.draw_line(loc, carla.Location(4, 5, 6), thickness=0.05, color=carla.Color(1, 2, 3), life_time=1.0)
    d.draw_arrow(loc, carla.Location(4, 5, 6), arrow_size=0.3, life_time=1.0)
    d.draw_string(loc, 'x', draw_shadow=True)
    d.draw_hud_point(loc)
    d.draw_hud_line(loc, carla.Location(0, 0, 0))
    d.draw_hud_arrow(loc, carla.Location(0, 0, 0))
    with pytest.raises(lockstep.CommandRejected, match='size'):
        d.draw_line(loc, carla.Location(0, 0, 0), thickness=-1.0)
    assert isinstance(d, carla.DebugHelper)
    world.tick()


def _night(world):
    w = world.get_weather()
    w.sun_altitude_angle = -90.0
    w.cloudiness = 0.0
    w.fog_density = 0.0
    w.precipitation = 0.0
    world.set_weather(w)


@contextlib.contextmanager
def _car_at_night(world, index, blueprint):
    """A car on the index-th far spawn point under a moonless sky; weather restored after."""
    old = world.get_weather()
    _night(world)
    sp = _far_spawn_points(world, index + 1)[index]
    car = world.spawn_actor(world.get_blueprint_library().find(blueprint), sp)
    try:
        yield car, sp
    finally:
        car.destroy()
        world.set_weather(old)
        world.tick()


@needs_render
@needs_ground
def test_at_night_a_cars_low_beams_light_the_road_in_front_of_it(world):
    with _car_at_night(world, 2, 'vehicle.lincoln.mkz_2020') as (car, sp):
        fwd = sp.get_forward_vector()
        # 10 m ahead of the car, 3 m up, looking back at it and the road before it.
        eye = carla.Transform(sp.location + carla.Location(x=fwd.x * 10, y=fwd.y * 10, z=3.0),
                              carla.Rotation(pitch=-15, yaw=sp.rotation.yaw + 180))
        cam = Camera(world, eye)
        try:
            _low_beams_light_the_road(world, car, cam)
        finally:
            cam.destroy()


def _low_beams_light_the_road(world, car, cam):
    """Low beams on raise the lower half of the image; off again, it is as dark as before."""
    for _ in range(5):
        off_frame = world.tick()
    off = cam.frames[off_frame].astype(float)
    car.set_light_state(carla.VehicleLightState.Position | carla.VehicleLightState.LowBeam)
    world.tick()
    on_frame = world.tick()
    assert car.get_light_state() & carla.VehicleLightState.LowBeam
    on = cam.frames[on_frame].astype(float)
    lower = slice(H // 2, H)  # the road between the camera and the car, and the car's front
    assert on[lower].mean() > off[lower].mean() + 2.0, (on[lower].mean(), off[lower].mean())
    car.set_light_state(carla.VehicleLightState.NONE)
    world.tick()
    dark = cam.frames[world.tick()].astype(float)
    assert abs(dark[lower].mean() - off[lower].mean()) < 0.5, 'off again'


@needs_ground
def test_update_vehicle_lights_lets_the_traffic_manager_light_a_car_at_night(world):
    with _car_at_night(world, 3, 'vehicle.audi.tt') as (car, _):
        tm = carla.Client('localhost', 2000).get_trafficmanager()
        car.set_autopilot(True, tm.get_port())
        for _ in range(3):
            world.tick()
        assert car.get_light_state() == carla.VehicleLightState.NONE, "CARLA's TM leaves the lights alone by default"
        tm.update_vehicle_lights(car, True)
        for _ in range(3):
            world.tick()
        bits = car.get_light_state()
        assert bits & carla.VehicleLightState.Position and bits & carla.VehicleLightState.LowBeam, bits


def _another_domain():
    """A second DDS domain of this process's own, by the lock files conftest.py uses."""
    import conftest
    for d in range(1, 201):
        if d == conftest.DOMAIN:
            continue
        f = open(os.path.join(tempfile.gettempdir(), 'lockstep-test-domain-%d.lock' % d), 'w')
        try:
            fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
            return d, f
        except OSError:
            f.close()
    raise RuntimeError('no free DDS domain')


# What a CARLA user's script sees of `lockstep serve`, in a process of its own (as a user runs it).
_SERVE_CLIENT = """
import carla
client = carla.Client('localhost', 2000)
client.set_timeout(60)
world = client.get_world()
s = world.get_settings()
first = world.wait_for_tick(10).frame
second = world.wait_for_tick(10).frame
kinds = sorted(k for _, k, alive, _ in world._client.run_status()['members'] if alive)
print('MAP', world.get_map().name, 'SYNC', s.synchronous_mode, 'RTF', s.real_time_factor, 'TICKING', second > first,
      'KINDS', ','.join(kinds))
"""


def test_lockstep_serve_starts_a_simulator_a_carla_client_connects_to(tmp_path):
    """`lockstep serve --map ...`: every built service, asynchronous, real time, until Ctrl-C."""
    town = os.path.join(os.path.dirname(BIN), 'maps', 'generated', 'LockstepTown1.xodr')
    domain, lock = _another_domain()
    log = open(str(tmp_path / 'serve.log'), 'w')
    proc = subprocess.Popen([os.path.join(BIN, 'lockstep'), 'serve', '--map', town, '--domain', str(domain)],
                            stdout=log, stderr=subprocess.STDOUT)
    try:
        env = dict(os.environ, LOCKSTEP_DOMAIN=str(domain), LOCKSTEP_CONNECT_TIMEOUT='60')
        r = subprocess.run([sys.executable, '-c', _SERVE_CLIENT], env=env, capture_output=True, text=True, timeout=300)
        assert r.returncode == 0, r.stdout + r.stderr + open(log.name).read()[-2000:]
        line = [l for l in r.stdout.splitlines() if l.startswith('MAP ')][-1].split()
        assert line[1].endswith('LockstepTown1'), line
        assert line[3] == 'False', 'asynchronous, as CARLA starts'
        assert float(line[5]) == 1.0, 'real time'
        assert line[7] == 'True', 'free-running'
        built = {k for k in ('air_sim', 'ground_sim', 'sensors', 'render') if has_service(k)}
        assert set(line[9].split(',')) >= built
    finally:
        proc.send_signal(signal.SIGINT)
        try:
            rc = proc.wait(60)
        except subprocess.TimeoutExpired:
            proc.kill()
            rc = proc.wait()
        log.close()
    lock.close()
    assert rc == 0, open(log.name).read()[-2000:]
