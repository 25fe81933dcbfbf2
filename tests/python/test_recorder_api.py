"""CARLA's recorder API (Client.start_recorder .. stop_replayer) and AirSim's recording, on a
simulation with the recorder service: the texts CARLA's scripts print and parse, and playback
(replay_file) that puts every actor where the recording had it, frame by frame."""
import json
import math
import os
import re
import subprocess
import sys
import tempfile

import pytest

import carla
import lockstep

from conftest import has_service

pytestmark = pytest.mark.skipif(not has_service('ground_sim'), reason='needs the ground_sim service')

# The recordings folder of this test (the simulation started by conftest inherits it).
RECORDINGS = tempfile.mkdtemp(prefix='lockstep-recordings-')
os.environ['LOCKSTEP_RECORDINGS_DIR'] = RECORDINGS

# What the log keeps (docs/recorder.md): positions to 1 mm, angles to 1e-4 rad.
POSITION_TOLERANCE = 1e-3   # m
ANGLE_TOLERANCE = 1e-4      # rad, between the two orientations (three angles to 1e-4 rad)


@pytest.fixture(scope='module')
def client(sim):
    c = carla.Client('localhost', 2000)
    c.set_timeout(30)
    return c


def _angle(q1, q2):
    d = abs(sum(a * b for a, b in zip(q1, q2)))
    return 2 * math.acos(min(1.0, d))


def _by_role(native):
    """{role_name: state} of the scene's actors (role names rec* and the hero)."""
    roles = {a['id']: a['attributes'].get('role_name', '') for a in native.actors()}
    out = {}
    for aid, st in native.states().items():
        role = roles.get(aid, '')
        if role.startswith('rec') or role == 'hero':
            out[role] = st
    return out


def _lights(native):
    return {l['id']: l['state'] for l in native.traffic_lights()}


def _spawn_scene(world):
    """Cars on autopilot, walkers walking, a drone falling, with role names rec*."""
    bps = world.get_blueprint_library()
    spawns = world.get_map().get_spawn_points()
    actors = []
    tm = world._carla_client.get_trafficmanager()
    tm.set_synchronous_mode(True)
    for i in range(3):
        bp = bps.find('vehicle.tesla.model3')
        bp.set_attribute('role_name', 'rec_car%d' % i if i else 'hero')
        v = world.try_spawn_actor(bp, spawns[i * 3])
        if v is not None:
            v.set_autopilot(True)
            actors.append(v)
    walker_bp = bps.filter('walker.pedestrian.*')[0]
    ctrl_bp = bps.find('controller.ai.walker')
    for i in range(2):
        loc = world.get_random_location_from_navigation()
        walker_bp.set_attribute('role_name', 'rec_walker%d' % i)
        w = world.try_spawn_actor(walker_bp, carla.Transform(loc + carla.Location(z=1)))
        if w is None:
            continue
        actors.append(w)
        c = world.spawn_actor(ctrl_bp, carla.Transform(), attach_to=w)
        world.tick()
        c.start()
        c.go_to_location(world.get_random_location_from_navigation())
        actors.append(c)
    drone_bp = bps.find('drone.generic_quad')
    drone_bp.set_attribute('role_name', 'rec_drone')
    p = spawns[-1]
    actors.append(world.spawn_actor(drone_bp, carla.Transform(p.location + carla.Location(x=3, z=6), p.rotation)))
    world.tick()
    return actors


def _record(client, world, name, frames):
    """Records `frames` frames of a scene into `name`; returns (path, [states by role per frame],
    [light states per frame], the scene's actors)."""
    native = world._client
    actors = _spawn_scene(world)
    for _ in range(5):
        world.tick()
    path = client.start_recorder(name)
    states, lights = [], []
    first = None
    for k in range(frames):
        f = world.tick()
        if first is None:
            first = f
        if k == frames // 2:
            # A light changed by a client is recorded too.
            tl = [a for a in world.get_actors().filter('traffic.traffic_light*')][0]
            tl.set_state(carla.TrafficLightState.Green if tl.get_state() != carla.TrafficLightState.Green
                         else carla.TrafficLightState.Red)
        states.append(_by_role(native))
        lights.append(_lights(native))
    client.stop_recorder()
    world.tick()
    return path, states, lights, actors


def _destroy(client, actors):
    for a in actors:
        if isinstance(a, carla.WalkerAIController):
            a.stop()
    client.apply_batch_sync([carla.command.DestroyActor(a.id) for a in reversed(actors)])


def test_start_recorder_answers_the_file_path_as_carla(client, world):
    path = client.start_recorder('answer.log')
    assert path == os.path.join(RECORDINGS, 'answer.log')  # start_recording.py prints "Recording on file: <path>"
    world.tick()
    client.stop_recorder()
    world.tick()
    assert os.path.getsize(path) > 0
    absolute = os.path.join(RECORDINGS, 'sub', 'abs.log')
    os.makedirs(os.path.dirname(absolute), exist_ok=True)
    assert client.start_recorder(absolute, True) == absolute
    world.tick()
    client.stop_recorder()
    world.tick()


def test_playback_puts_every_actor_where_the_recording_had_it(client, world):
    frames = 40
    path, rec_states, rec_lights, actors = _record(client, world, 'playback.log', frames)
    roles = set(rec_states[-1])
    assert {'rec_car1', 'rec_car2', 'rec_drone'} <= roles and any(r.startswith('rec_walker') for r in roles), roles
    moved = max(math.dist(rec_states[0][r]['transform'][:3], rec_states[-1][r]['transform'][:3]) for r in roles)
    assert moved > 1.0  # something moved
    _destroy(client, actors)
    world.tick()
    assert not _by_role(world._client)

    text = client.replay_file('playback.log', 0.0, 0.0, 0)
    m = re.fullmatch(r'Replaying File: (.+)\nTotal time recorded: (\S+)\nReplaying from 0 s - (\S+) s \((\S+) s\) at '
                     r'1\.0x\nIgnoring Spectator camera\n', text)
    assert m and m.group(1) == path and m.group(2) == m.group(3) == m.group(4), text
    # The log's duration, as show_recorder_file_info reads it (the frame carrying the stop may be in).
    duration = float(re.search(r'Duration: (\S+) seconds', client.show_recorder_file_info('playback.log', False)).group(1))
    dt = world.get_settings().fixed_delta_seconds
    assert float(m.group(2)) == pytest.approx(duration, abs=1e-9)
    assert round(duration / dt) in (frames - 1, frames)
    worst = {'vehicle': 0.0, 'walker': 0.0, 'drone': 0.0}
    worst_angle = 0.0
    light_frames = 0
    for k in range(frames):
        world.tick()
        now = _by_role(world._client)
        assert set(now) == set(rec_states[k]), (k, set(now) ^ set(rec_states[k]))
        for role, rec in rec_states[k].items():
            got = now[role]
            assert got['kind'] == rec['kind']
            worst[rec['kind']] = max(worst[rec['kind']], math.dist(got['transform'][:3], rec['transform'][:3]))
            if rec['kind'] != 'drone':
                worst_angle = max(worst_angle, _angle(got['transform'][3:], rec['transform'][3:]))
        lights = _lights(world._client)
        assert lights == rec_lights[k], k
        light_frames += 1
    print('playback error: positions %s m, orientation %.2e rad' % (worst, worst_angle))
    assert worst['vehicle'] <= POSITION_TOLERANCE and worst['walker'] <= POSITION_TOLERANCE, worst
    assert worst_angle <= ANGLE_TOLERANCE
    assert worst['drone'] <= 0.02, worst  # drones: air_sim steps its physics from the set pose (docs)
    # The tick after the last frame: the replay ends, the actors stay, with their physics and
    # CARLA's autopilot back.
    world.tick()
    world.tick()
    after = _by_role(world._client)
    assert set(after) == set(rec_states[-1])
    cars = [s for s in after.values() if s['kind'] == 'vehicle']
    assert cars and all(s['autopilot'] and not s['kinematic'] for s in cars)
    _destroy(client, [world.get_actor(s['id']) for s in after.values()])
    world.tick()


def test_replay_from_a_start_time_at_a_time_factor_without_the_hero(client, world):
    frames = 30
    _, rec_states, _, actors = _record(client, world, 'factor.log', frames)
    _destroy(client, actors)
    world.tick()
    client.set_replayer_time_factor(2.0)
    client.set_replayer_ignore_hero(True)
    try:
        dt = world.get_settings().fixed_delta_seconds
        text = client.replay_file('factor.log', 10 * dt, 0.0, 0)
        assert ' at 2.0x\n' in text and 'Ignoring Hero vehicle\n' in text, text
        for j in range(5):
            world.tick()
            now = _by_role(world._client)
            # Tick j shows the log's frame 10 + 2 j (a factor of 2 and above: whole frames).
            assert 'hero' not in now  # CARLA: an ignored hero is not created
            for role, rec in rec_states[10 + 2 * j].items():
                if rec['kind'] == 'vehicle' and role != 'hero':
                    assert math.dist(now[role]['transform'][:3], rec['transform'][:3]) <= POSITION_TOLERANCE, (j, role)
        client.stop_replayer(False)
        world.tick()
    finally:
        client.set_replayer_time_factor(1.0)
        client.set_replayer_ignore_hero(False)
    _destroy(client, [world.get_actor(s['id']) for s in _by_role(world._client).values()])
    world.tick()


def test_replay_file_answers_carlas_text_for_a_missing_file_and_refuses_bad_values(client, world):
    missing = os.path.join(RECORDINGS, 'nope.log')
    assert client.replay_file('nope.log', 0, 0, 0) == 'Replaying File: %s\nFile %s not found on server\n' % (
        missing, missing)
    with pytest.raises(lockstep.CommandRejected, match='time factor'):
        client.set_replayer_time_factor(-1.0)
    with pytest.raises(lockstep.CommandRejected, match='start is NaN'):
        client.replay_file('nope.log', float('nan'), 0, 0)


def test_show_recorder_calls_answer_text(client, world):
    path = client.start_recorder('show.log')
    for _ in range(5):
        world.tick()
    client.stop_recorder()
    world.tick()
    info = client.show_recorder_file_info('show.log', False)
    assert 'Frames: ' in info and 'Duration: ' in info, info
    assert isinstance(client.show_recorder_file_info(path, True), str)
    assert isinstance(client.show_recorder_collisions('show.log', 'a', 'a'), str)
    assert isinstance(client.show_recorder_actors_blocked('show.log', 30.0, 100.0), str)
    with pytest.raises(ValueError, match='one character'):
        client.show_recorder_collisions('show.log', 'vv', 'a')


def test_airsim_recording_writes_airsim_rec_txt_from_the_log(sim, tmp_path):
    import airsim
    settings = tmp_path / 'settings.json'
    settings.write_text(json.dumps({'SettingsVersion': 1.2, 'SimMode': 'Multirotor',
                                    'Recording': {'RecordInterval': 0.1, 'Folder': str(tmp_path / 'rec')}}))
    script = tmp_path / 'rec.py'
    script.write_text('\n'.join([
        'import airsim',
        'c = airsim.MultirotorClient()',
        'c.confirmConnection()',
        'c.enableApiControl(True)',
        'assert not c.isRecording()',
        'c.startRecording()',
        'assert c.isRecording()',
        'c.armDisarm(True)',
        'c.takeoffAsync().join()',
        'c.stopRecording()',
        'assert not c.isRecording()',
        'c.armDisarm(False)',
    ]))
    env = dict(os.environ, LOCKSTEP_AIRSIM_SETTINGS=str(settings))
    r = subprocess.run([sys.executable, str(script)], env=env, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stdout + r.stderr
    folders = os.listdir(tmp_path / 'rec')
    assert len(folders) == 1
    folder = tmp_path / 'rec' / folders[0]
    assert sorted(os.listdir(folder)) == ['airsim_rec.log', 'airsim_rec.txt']
    lines = (folder / 'airsim_rec.txt').read_text().splitlines()
    assert lines[0] == 'VehicleName\tTimeStamp\tPOS_X\tPOS_Y\tPOS_Z\tQ_W\tQ_X\tQ_Y\tQ_Z\tImageFile'
    rows = [l.split('\t') for l in lines[1:]]
    assert len(rows) >= 5 and all(len(r) == 10 and r[9] == '' for r in rows)
    stamps = [int(r[1]) for r in rows]
    assert all(b - a == 100 for a, b in zip(stamps, stamps[1:]))  # RecordInterval 0.1 s of simulation time
    assert float(rows[-1][4]) < float(rows[0][4]) - 1.0  # it took off: z (down) decreased


def test_airsim_recording_settings_are_checked():
    from lockstep.airsim import settings as settings_mod
    s = settings_mod.parse(json.dumps({'Recording': {'RecordOnMove': True, 'RecordInterval': 0.2, 'Enabled': True,
                                                     'Cameras': [{'CameraName': '0', 'ImageType': 3}]}}))
    r = s.recording
    assert (r.record_on_move, r.record_interval, r.enabled, r.folder) == (True, 0.2, True, '')
    assert r.cameras == [{'camera_name': '0', 'image_type': 3, 'pixels_as_float': False, 'vehicle_name': '',
                          'compress': True}]
    assert settings_mod.parse('{}').recording.record_interval == 0.05  # AirSim's default
    with pytest.raises(settings_mod.SettingsError, match='Recording.RecordInterval'):
        settings_mod.parse(json.dumps({'Recording': {'RecordInterval': 'fast'}}))
    with pytest.raises(settings_mod.SettingsError, match=r'Recording.Cameras\[0\].ImageType'):
        settings_mod.parse(json.dumps({'Recording': {'Cameras': [{'ImageType': 42}]}}))
