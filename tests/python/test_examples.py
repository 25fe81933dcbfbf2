"""Our examples run to completion through the drop-in `carla` and `airsim` imports,
started the way a user starts them: `lockstep python examples/<name>.py`."""
import os
import subprocess

from conftest import BIN, SOURCE



def run(sim, script, *args, timeout=240):
    r = subprocess.run([os.path.join(BIN, 'lockstep'), 'python', os.path.join(SOURCE, 'examples', script)] + list(args),
                       capture_output=True, text=True, timeout=timeout, cwd=sim.dir)
    assert r.returncode == 0, 'exit %d\n--- stdout\n%s\n--- stderr\n%s\n--- simulation\n%s' % (
        r.returncode, r.stdout[-3000:], r.stderr[-3000:], sim.output()[-3000:])
    return r.stdout


def test_drone_hello(sim):
    out = run(sim, 'drone_hello.py')
    assert 'done: landed state 0' in out


def test_tutorial(sim):
    out = run(sim, 'tutorial.py', '--ticks', '60', '--out', os.path.join(sim.dir, 'tutorial'))
    assert 'destroying actors' in out


def test_spawn_traffic(sim):
    out = run(sim, 'spawn_traffic.py', '-n', '10', '-w', '5', '--ticks', '100')
    assert 'destroyed' in out


def test_sync_sensors(sim):
    import carla
    lib = carla.Client().get_world().get_blueprint_library()
    names = [n for n in ('sensor.camera.rgb', 'sensor.other.imu', 'sensor.camera.depth', 'sensor.lidar.ray_cast',
                         'sensor.other.gnss') if len(lib.filter(n))]
    out = run(sim, 'sync_sensors.py', '--ticks', '50', '--sensors', ','.join(names))
    assert 'every sensor delivered every frame once' in out


def test_drone_follow_car(sim):
    out = run(sim, 'drone_follow_car.py', '--ticks', '200')
    assert 'drone-to-target distance' in out


def test_cars_and_drones(sim):
    out = run(sim, 'cars_and_drones.py', '--ticks', '100')
    assert '100/100 ticks with ground and air state of the same frame' in out


def test_showcase(sim):
    import json
    out_dir = os.path.join(sim.dir, 'showcase')
    out = run(sim, 'showcase.py', '--connect', '--ticks', '40', '--out', out_dir, '--cars', '3', '--walkers', '2')
    assert 'Lockstep showcase' in out
    assert 'lockstep python -m lockstep.benchmarks corl2017' in out   # the summary says how to run a benchmark
    summary = json.load(open(os.path.join(out_dir, 'summary.json')))
    assert summary['ticks'] == 40
    assert summary['ground_air_frame_alignment'] == '40/40 ticks'
    assert all(summary['sensor_frames_in_order_once'].values())
    # Continuous sensors: one frame per tick since listen() (40 ticks and the takeoff's), none lost or repeated.
    assert summary['every_frame_once'] and all(summary['every_frame_once'].values()), summary['every_frame_once']
    assert summary['frames_since_listen'] > 40
    assert os.path.getsize(os.path.join(out_dir, 'town.png')) > 0
    assert len(open(os.path.join(out_dir, 'ticks.csv')).readlines()) == 41
    assert summary['cars'] == 4 and summary['walkers'] >= 1
    assert summary['drone_height_above_ego_m'] > 2.5, 'the drone did not take off to follow the ego'
