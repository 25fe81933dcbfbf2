"""AirSim's settings.json and AirSim's rules against a running simulation: the vehicles at
their settings poses from the player start, a camera with its resolution and mount, LiDARs
with their settings and data frame, AirSim's image types on a known scene, reset() to the
settings poses, armDisarm without API control, API control across processes, a camera over
the Image bound, AirSim's segmentation object ids."""
import json
import math
import os
import subprocess
import sys

import numpy as np
import pytest

from conftest import has_service

SETTINGS = {
    'SettingsVersion': 1.2, 'SimMode': 'Multirotor',
    'Vehicles': {
        'Drone1': {'VehicleType': 'SimpleFlight', 'X': 0, 'Y': 0, 'Z': 0,
                   'Cameras': {'probe': {'CaptureSettings': [{'ImageType': t, 'Width': 96, 'Height': 64,
                                                              'FOV_Degrees': 70} for t in (0, 1, 2, 3)],
                                         'X': 0.4, 'Y': 0.0, 'Z': 0.05, 'Roll': 0, 'Pitch': -90, 'Yaw': 0},
                               # 2000 x 1100 BGRA is more than an Image message holds (1920 x 1080).
                               'wide': {'CaptureSettings': [{'ImageType': 0, 'Width': 2000, 'Height': 1100}],
                                        'X': 0.4, 'Y': 0.0, 'Z': 0.05, 'Pitch': -90}},
                   'Sensors': {'LocalLidar': {'SensorType': 6, 'Enabled': True, 'NumberOfChannels': 1, 'Range': 30,
                                              'RotationsPerSecond': 20, 'PointsPerSecond': 4000,
                                              'VerticalFOVUpper': -90, 'VerticalFOVLower': -90,
                                              'X': 0, 'Y': 0, 'Z': 0.3, 'DataFrame': 'SensorLocalFrame'},
                               'WorldLidar': {'SensorType': 6, 'Enabled': True, 'NumberOfChannels': 1, 'Range': 30,
                                              'RotationsPerSecond': 20, 'PointsPerSecond': 4000,
                                              'VerticalFOVUpper': -90, 'VerticalFOVLower': -90,
                                              'X': 0, 'Y': 0, 'Z': 0.3, 'DataFrame': 'VehicleInertialFrame'}}},
        'Drone2': {'VehicleType': 'SimpleFlight', 'X': 4, 'Y': -3, 'Z': 0, 'Yaw': 90},
    }}


@pytest.fixture(scope='module')
def client(sim, tmp_path_factory):
    path = tmp_path_factory.mktemp('airsim') / 'settings.json'
    path.write_text(json.dumps(SETTINGS))
    os.environ['LOCKSTEP_AIRSIM_SETTINGS'] = str(path)
    import airsim
    c = airsim.MultirotorClient()
    yield c
    os.environ.pop('LOCKSTEP_AIRSIM_SETTINGS', None)


def _enu(c, name):
    a = c._s.mc.resolve(name)
    return c._client.state(a)['transform']


def _lift(client):
    """Drone1 hovering 10 m above its start (once); its start pose."""
    import airsim
    start = client.simGetVehiclePose('Drone1')
    if start.position.z_val < -5:
        return airsim.Pose(airsim.Vector3r(start.position.x_val, start.position.y_val, start.position.z_val + 10))
    k = airsim.KinematicsState()
    k.position = airsim.Vector3r(start.position.x_val, start.position.y_val, start.position.z_val - 10.0)
    k.orientation = airsim.to_quaternion(0, 0, 0)
    client.enableApiControl(True, 'Drone1')
    client.armDisarm(True, 'Drone1')
    client.simSetKinematics(k, True, 'Drone1')
    client.hoverAsync('Drone1').join()
    for _ in range(20):
        client._client.tick()
    return start


def test_vehicles_start_at_their_settings_poses(client):
    import airsim
    assert client.listVehicles() == ['Drone1', 'Drone2']
    d1, d2 = _enu(client, 'Drone1'), _enu(client, 'Drone2')
    # NED from the player start: X north (ENU +y), Y east (ENU +x); Drone2 is 4 m north and 3 m west of Drone1.
    assert (d2[1] - d1[1], d2[0] - d1[0]) == (pytest.approx(4.0, abs=0.02), pytest.approx(-3.0, abs=0.02))
    assert abs(d2[2] - d1[2]) < 0.3   # Z 0 for both: each dropped onto the ground below (a kerb apart at most)
    yaw1 = airsim.to_eularian_angles(client.simGetVehiclePose('Drone1').orientation)[2]
    yaw2 = airsim.to_eularian_angles(client.simGetVehiclePose('Drone2').orientation)[2]
    assert (math.degrees(yaw1), math.degrees(yaw2)) == (pytest.approx(0, abs=1), pytest.approx(90, abs=1))
    # Each vehicle's NED frame starts at its own start, as AirSim's.
    p = client.getMultirotorState('Drone2').kinematics_estimated.position
    assert (p.x_val, p.y_val) == (pytest.approx(0, abs=0.05), pytest.approx(0, abs=0.05))
    # At rest when the script gets them: takeoff is accepted at once (AirSim refuses it while moving).
    s = client.getMultirotorState('Drone1').kinematics_estimated.linear_velocity
    assert s.get_length() < 0.05


def test_a_settings_camera_has_its_resolution_and_mount(client):
    if not has_service('render'):
        pytest.skip('needs render')
    import airsim
    r = client.simGetImages([airsim.ImageRequest('probe', airsim.ImageType.Scene, False, False)], 'Drone1')[0]
    assert (r.width, r.height) == (96, 64)
    assert len(r.image_data_uint8) == 96 * 64 * 3
    info = client.simGetCameraInfo('probe', 'Drone1')
    assert info.fov == pytest.approx(70)
    pitch, roll, yaw = airsim.to_eularian_angles(info.pose.orientation)
    assert math.degrees(pitch) == pytest.approx(-90, abs=0.5)
    body = client.simGetVehiclePose('Drone1').position
    assert (info.pose.position - body).x_val == pytest.approx(0.4, abs=0.01)
    assert (info.pose.position - body).z_val == pytest.approx(0.05, abs=0.01)
    # The default cameras are there too, at AirSim's 256 x 144.
    r = client.simGetImages([airsim.ImageRequest('0', airsim.ImageType.Scene)], 'Drone1')[0]
    assert (r.width, r.height) == (256, 144) and r.image_data_uint8[:4] == b'\x89PNG'
    # The plotting calls draw into the cameras (debug shapes); a bad colour names the call.
    client.simPlotLineStrip([airsim.Vector3r(0, 0, -1), airsim.Vector3r(5, 0, -1)], duration=1.0)
    with pytest.raises(airsim.ClientError, match='simPlotPoints'):
        client.simPlotPoints([airsim.Vector3r(0, 0, -1)], color_rgba=[2, 0, 0, 1])


def test_airsim_image_types_on_a_known_scene(client):
    """The probe camera looks straight down from 10 m over the flat ground: DepthPlanar 10,
    DepthPerspective 10 / cos, DepthVis 10/100 grey, compressed PNGs as RGBA."""
    if not (has_service('render') and has_service('sensors')):
        pytest.skip('needs render and sensors')
    import airsim
    import cv2
    start = _lift(client)
    reqs = [airsim.ImageRequest('probe', t, True, False) for t in (1, 2)] + \
        [airsim.ImageRequest('probe', 3, False, False), airsim.ImageRequest('probe', 3, False, True)]
    client.simGetImages(reqs, 'Drone1')   # spawns the cameras
    client._client.tick()                 # then one frame for all of them
    planar, persp, vis, vis_png = client.simGetImages(reqs, 'Drone1')
    assert planar.frame == persp.frame == vis.frame
    assert (planar.width, planar.height, persp.width, vis.width) == (96, 64, 96, 96)
    # The truth: the LiDAR 30 cm under the body measures its height over the ground; the camera is 5 cm
    # under the body, 25 cm above the LiDAR.
    lidar = np.array(client.getLidarData('LocalLidar', 'Drone1').point_cloud, np.float32).reshape(-1, 3)
    expect = float(np.median(lidar[:, 2])) + 0.25
    assert expect == pytest.approx(10.0, abs=0.5)
    d = np.array(planar.image_data_float, np.float32).reshape(planar.height, planar.width)
    c = d[planar.height // 2 - 2:planar.height // 2 + 2, planar.width // 2 - 2:planar.width // 2 + 2]
    assert float(np.median(c)) == pytest.approx(expect, abs=0.05)
    assert float(np.ptp(d[planar.height // 2 - 4:planar.height // 2 + 4, planar.width // 2 - 4:planar.width // 2 + 4])) \
        < 0.03   # a plane
    p = np.array(persp.image_data_float, np.float32).reshape(persp.height, persp.width)
    f = persp.width / 2 / math.tan(math.radians(70) / 2)
    u, v = persp.width // 4, persp.height // 2
    ray = math.sqrt(1 + ((u + 0.5 - persp.width / 2) / f) ** 2 + ((v + 0.5 - persp.height / 2) / f) ** 2)
    assert p[v, u] == pytest.approx(d[v, u] * ray, rel=1e-3)
    g = np.frombuffer(vis.image_data_uint8, np.uint8).reshape(vis.height, vis.width, 3)
    assert int(g[vis.height // 2, vis.width // 2, 0]) == pytest.approx(round(float(np.median(c)) / 100 * 255), abs=1)
    png = cv2.imdecode(np.frombuffer(vis_png.image_data_uint8, np.uint8), cv2.IMREAD_UNCHANGED)
    assert png.shape == (vis.height, vis.width, 4) and png[0, 0, 3] == 255
    assert planar.time_stamp > 0 and planar.camera_position.z_val < start.position.z_val - 9


def test_lidars_have_their_settings_and_data_frame(client):
    if not has_service('sensors'):
        pytest.skip('needs sensors')
    _lift(client)
    # Straight down from 30 cm under the body (clear of it): one channel at -90 deg, 30 m range.
    local = client.getLidarData('LocalLidar', 'Drone1')
    world = client.getLidarData('WorldLidar', 'Drone1')
    pl = np.array(local.point_cloud, dtype=np.float32).reshape(-1, 3)
    pw = np.array(world.point_cloud, dtype=np.float32).reshape(-1, 3)
    assert len(pl) > 10 and len(pw) > 10
    body = client.simGetVehiclePose('Drone1').position
    h = float(np.median(pl[:, 2]))
    # SensorLocalFrame: FRD of the sensor, the ground below is +z (down) at the sensor's height (~10 m up).
    assert 5.0 < h < 15.0
    assert np.abs(pl[:, :2]).max() < 0.05
    # VehicleInertialFrame: the vehicle's NED frame from its home: the ground at z = body z + 0.3 + h.
    assert float(np.median(pw[:, 2])) == pytest.approx(body.z_val + 0.3 + h, abs=0.02)
    assert (world.pose.position - body).z_val == pytest.approx(0.3, abs=1e-3)   # LidarData.pose: the LiDAR's
    assert world.time_stamp > 1e6   # ns


def test_arm_without_api_control_returns_false_and_reset_returns_vehicles(client):
    client.enableApiControl(False, 'Drone2')
    assert client.armDisarm(True, 'Drone2') is False
    assert not client.isApiControlEnabled('Drone2')
    # API control is the vehicle's: another client of the process sees it.
    import airsim
    other = airsim.MultirotorClient()
    client.enableApiControl(True, 'Drone2')
    assert other.isApiControlEnabled('Drone2')
    assert other.armDisarm(True, 'Drone2') is True
    z0 = client.getMultirotorState('Drone2').kinematics_estimated.position.z_val
    assert other.takeoffAsync(vehicle_name='Drone2').join()
    assert other.moveByVelocityAsync(1, 0, 0, 0, vehicle_name='Drone2').join()   # duration 0: AirSim returns at once
    assert client.getMultirotorState('Drone2').kinematics_estimated.position.z_val < z0 - 1.5
    before = _enu(client, 'Drone1')
    client.reset()
    p = client.getMultirotorState('Drone2').kinematics_estimated.position
    assert (p.x_val, p.y_val, p.z_val) == (pytest.approx(0, abs=0.05), pytest.approx(0, abs=0.05),
                                           pytest.approx(z0, abs=0.05))   # back at its start, at rest
    assert not client.isApiControlEnabled('Drone2')
    assert client.listVehicles() == ['Drone1', 'Drone2']   # the same vehicles: no new run
    assert _enu(client, 'Drone1')[0] == pytest.approx(before[0], abs=0.05)


def test_a_move_that_cannot_complete_times_out_and_says_so(client, caplog, monkeypatch):
    """A target under the ground: join() returns False at timeout_sec (AirSim's), and while it
    waits the log says where the vehicle is stuck."""
    import logging
    from lockstep.airsim import client as client_module
    monkeypatch.setattr(client_module._Future, '_REPORT_S', 0.2)
    logger = logging.getLogger('lockstep.airsim')
    logger.addHandler(caplog.handler)
    try:
        client.enableApiControl(True, 'Drone2')
        f = client.moveToPositionAsync(0, 0, 5, 1, timeout_sec=20, vehicle_name='Drone2')   # 5 m down: in the ground
        assert f.join() is False
    finally:
        logger.removeHandler(caplog.handler)
    assert "moveToPositionAsync on vehicle 'Drone2' still running" in caplog.text and 'not getting anywhere' in caplog.text


def _in_another_process(code):
    """Runs `code` with `c = airsim.MultirotorClient()` in a new Python process on the same
    simulation; its printed words."""
    prelude = 'import airsim\nc = airsim.MultirotorClient()\n'
    r = subprocess.run([sys.executable, '-c', prelude + code], env=dict(os.environ), capture_output=True, text=True,
                       timeout=180)
    assert r.returncode == 0, r.stdout + r.stderr
    return r.stdout.split()


def test_api_control_is_the_vehicles_across_processes(client):
    """AirSim's API control belongs to the vehicle: one process takes it, another sees it; without
    it, as simple_flight, arming is refused and a move steers nothing but waits out its duration
    (True) or its timeout (False)."""
    client.enableApiControl(False, 'Drone2')
    client._client.tick()
    assert _in_another_process("print(c.isApiControlEnabled('Drone2')); c.enableApiControl(True, 'Drone2'); "
                               "print(c.isApiControlEnabled('Drone2'))") == ['False', 'True']
    client._client.tick()
    assert client.isApiControlEnabled('Drone2') is True   # taken by the other process
    client.enableApiControl(False, 'Drone2')
    client._client.tick()
    out = _in_another_process(
        "p0 = c.simGetVehiclePose('Drone2').position\n"
        "print(c.isApiControlEnabled('Drone2'), c.armDisarm(True, 'Drone2'))\n"
        "print(c.moveByVelocityAsync(3, 0, -2, 1, vehicle_name='Drone2').join())\n"
        "print(c.moveToPositionAsync(10, 0, -5, 3, timeout_sec=1, vehicle_name='Drone2').join())\n"
        "print('%.4f' % (c.simGetVehiclePose('Drone2').position - p0).get_length())\n")
    assert out[:4] == ['False', 'False', 'True', 'False']
    assert float(out[4]) < 0.02   # m: neither move steered the drone


def test_surface_normals_are_world_normals_from_any_camera(client):
    """AirSim's SurfaceNormals are Unreal's world normals (X north, Y east, Z up) as (n + 1) / 2:
    the flat ground is (127, 127, 255) RGB seen from the front camera and from the one looking down."""
    if not has_service('render'):
        pytest.skip('needs render')
    import airsim
    _lift(client)
    reqs = [airsim.ImageRequest('0', airsim.ImageType.SurfaceNormals, False, False),
            airsim.ImageRequest('probe', airsim.ImageType.SurfaceNormals, False, False)]
    client.simGetImages(reqs, 'Drone1')   # spawns the cameras
    client._client.tick()
    front, down = client.simGetImages(reqs, 'Drone1')
    f = np.frombuffer(front.image_data_uint8, np.uint8).reshape(front.height, front.width, 3)
    patch = f[-6:, front.width // 2 - 8:front.width // 2 + 8].reshape(-1, 3)   # the ground 18 m ahead
    assert (patch == (255, 127, 127)).all(axis=1).mean() > 0.8
    d = np.frombuffer(down.image_data_uint8, np.uint8).reshape(down.height, down.width, 3)
    assert tuple(int(v) for v in d[down.height // 2, down.width // 2]) == (255, 127, 127)


def test_optical_flow_of_a_yawing_drone_is_airsims(client):
    """Yawing right (NED, clockwise from above), the front camera sees the world move left: AirSim's
    OpticalFlow vx (the float read-back's one channel) is negative, about yaw rate x dt / FOV of the
    image per frame; OpticalFlowVis shows leftward motion red."""
    if not has_service('render'):
        pytest.skip('needs render')
    import airsim
    _lift(client)
    reqs = [airsim.ImageRequest('0', airsim.ImageType.OpticalFlow, True, False),
            airsim.ImageRequest('0', airsim.ImageType.OpticalFlowVis, False, False)]
    client.simGetImages(reqs, 'Drone1')   # spawns the cameras
    client.enableApiControl(True, 'Drone1')
    f = client.rotateByYawRateAsync(30, 3, 'Drone1')
    for _ in range(30):
        client._client.tick()
    flow, vis = client.simGetImages(reqs, 'Drone1')
    rate = client.getMultirotorState('Drone1').kinematics_estimated.angular_velocity.z_val
    f.join()
    assert len(flow.image_data_float) == flow.width * flow.height   # vx only, as AirSim's read-back
    vx = np.array(flow.image_data_float, np.float32).reshape(flow.height, flow.width)
    expect = -rate * 0.05 / math.radians(90)   # a 90 deg FOV image turns by rate x dt per frame (centre)
    assert rate > 0.3 and float(np.median(vx[flow.height // 2 - 4:flow.height // 2 + 4])) == pytest.approx(expect, rel=0.25)
    v = np.frombuffer(vis.image_data_uint8, np.uint8).reshape(vis.height, vis.width, 3).astype(int)
    centre = v[vis.height // 2, vis.width // 2]
    value = math.log(abs(expect) + 0.999) / math.log(1.099)   # dim: a sixtieth of the image per frame
    assert centre[2] == pytest.approx(255 * value, rel=0.25) and centre[0] <= 2 and centre[1] <= centre[2] / 4   # B G R: red


def test_api_control_taken_back_resumes_the_running_move(client):
    """AirSim 1.8: enableApiControl(False) cancels nothing; moveToPositionAsync's loop keeps
    sending its goals (refused meanwhile) and, control taken back, reaches its target."""
    client.reset()
    client.enableApiControl(True, 'Drone2')
    assert client.armDisarm(True, 'Drone2')
    assert client.takeoffAsync(vehicle_name='Drone2').join()
    p0 = client.getMultirotorState('Drone2').kinematics_estimated.position
    goal = (p0.x_val + 8, p0.y_val, p0.z_val - 3)
    f = client.moveToPositionAsync(*goal, 3, timeout_sec=60, vehicle_name='Drone2')
    for _ in range(10):
        client._client.tick()
    client.enableApiControl(False, 'Drone2')
    for _ in range(6):
        client._client.tick()
    p1 = client.getMultirotorState('Drone2').kinematics_estimated.position
    assert p1.x_val - p0.x_val < 7   # still on its way
    client.enableApiControl(True, 'Drone2')
    assert f.join() is True
    p = client.getMultirotorState('Drone2').kinematics_estimated.position
    assert (p - airsim_vector(goal)).get_length() < 0.5


def airsim_vector(t):
    import airsim
    return airsim.Vector3r(*t)


def test_a_camera_over_the_image_bound_arrives_whole(client):
    """A settings camera of 2000 x 1100 (more than msg::Image's 1920 x 1080 BGRA) comes as a
    LargeImage on its own topic between the render process and this one."""
    if not has_service('render'):
        pytest.skip('needs render')
    import airsim
    try:
        r = client.simGetImages([airsim.ImageRequest('wide', airsim.ImageType.Scene, False, False)], 'Drone1')[0]
        assert (r.width, r.height) == (2000, 1100)
        img = np.frombuffer(r.image_data_uint8, np.uint8)
        assert img.size == 2000 * 1100 * 3
        assert float(img.reshape(1100, 2000, 3).std()) > 1.0   # a rendered scene, not an empty buffer
    finally:
        client._s.sensors.drop(lambda key: key[2] == 'wide')   # 2.2 Mpx a frame: not for the rest of the module


def test_segmentation_and_infrared_show_airsims_object_ids(client):
    """Segmentation: AirSim's palette colour of each object's id (seg_rgbs.txt, as BGR bytes);
    Infrared: the id as grey. Ids are AirSim's defaults (5 + the name's letters, mod 256) until
    simSetSegmentationObjectID sets them (a regular expression over the town's objects); -1 hides."""
    if not has_service('render'):
        pytest.skip('needs render')
    import airsim
    _lift(client)
    assert client.simGetSegmentationObjectID('ground') == (5 + sum(map(ord, 'ground'))) % 256
    assert client.simGetSegmentationObjectID('no_such_object') == -1
    assert client.simListSceneObjects('building_.*') and 'ground' in client.simListSceneObjects()
    assert math.isfinite(client.simGetObjectPose('ground').position.x_val)
    under = '(ground|road|sidewalk|verge|markings).*'
    assert client.simSetSegmentationObjectID(under, 42, True) is True
    assert client.simSetSegmentationObjectID('no_such_object', 42) is False
    reqs = [airsim.ImageRequest('probe', airsim.ImageType.Segmentation, False, False),
            airsim.ImageRequest('probe', airsim.ImageType.Infrared, False, False)]
    client.simGetImages(reqs, 'Drone1')   # spawns the cameras
    client._client.tick()

    def centre():
        seg, ir = client.simGetImages(reqs, 'Drone1')
        s = np.frombuffer(seg.image_data_uint8, np.uint8).reshape(seg.height, seg.width, 3)
        i = np.frombuffer(ir.image_data_uint8, np.uint8).reshape(ir.height, ir.width, 3)
        return tuple(int(v) for v in s[seg.height // 2, seg.width // 2]), tuple(int(v) for v in i[ir.height // 2, ir.width // 2])

    assert centre() == ((106, 31, 92), (42, 42, 42))   # palette[42] is RGB (92, 31, 106)
    assert client.simGetSegmentationObjectID('ground') == 42
    client.simSetSegmentationObjectID(under, -1, True)
    assert centre() == ((0, 0, 0), (0, 0, 0))
    client.simSetSegmentationObjectID(under, 7, True)
    assert centre() == ((195, 176, 115), (7, 7, 7))   # palette[7] is RGB (115, 176, 195)


def test_flush_persistent_markers_erases_what_was_plotted(client):
    """simFlushPersistentMarkers is Unreal's FlushPersistentDebugLines: the persistent marker
    and the one with a duration are gone from the next frame; a marker plotted after it shows."""
    if not has_service('render'):
        pytest.skip('needs render')
    import airsim
    _lift(client)
    req = airsim.ImageRequest('probe', airsim.ImageType.Scene, False, False)
    client.simGetImages([req], 'Drone1')   # the camera exists before the shapes are drawn
    body = client.simGetVehiclePose('Drone1').position
    # 5 m under the probe camera (0.4 m ahead of the body, looking down), and 1.5 m east and west of that.
    at = [airsim.Vector3r(body.x_val + 0.4, body.y_val + dy, body.z_val + 5) for dy in (0.0, 1.5, -1.5)]

    def colours():
        client._client.tick()
        frame = client._client.frame()
        for _ in range(10):
            r = client.simGetImages([req], 'Drone1')[0]
            if r.frame >= frame:
                break
            client._client.tick()
        assert r.frame >= frame
        img = np.frombuffer(r.image_data_uint8, np.uint8).reshape(r.height, r.width, 3).astype(int)
        b, g, rr = img[:, :, 0], img[:, :, 1], img[:, :, 2]
        return {'red': int(((rr > 200) & (g < 80) & (b < 80)).sum()), 'green': int(((g > 200) & (rr < 80) & (b < 80)).sum()),
                'blue': int(((b > 200) & (rr < 80) & (g < 80)).sum())}

    client.simPlotPoints([at[0]], [1.0, 0.0, 0.0, 1.0], 10, is_persistent=True)
    client.simPlotPoints([at[1]], [0.0, 1.0, 0.0, 1.0], 10, duration=600)
    n = colours()
    assert n['red'] >= 50 and n['green'] >= 50 and n['blue'] == 0   # 10 x 10 px each
    client.simFlushPersistentMarkers()
    client.simPlotPoints([at[2]], [0.0, 0.0, 1.0, 1.0], 10, is_persistent=True)
    n = colours()
    assert n['red'] == 0 and n['green'] == 0 and n['blue'] >= 50
    client.simFlushPersistentMarkers()
    assert colours()['blue'] == 0


def test_car_client_drives_a_ground_sim_car(client):
    """AirSim's CarClient on ground_sim: with no car, a PhysXCar on the map's first spawn point.
    As AirSim's car: API control starts off and without it the keyboard's controls (none
    pressed) replace setCarControls'; with it, throttle moves the car forward along its
    heading (NED from its start, forward speed positive); a change of API control starts from
    CarControls(); arming is always True."""
    if not has_service('ground_sim'):
        pytest.skip('needs ground_sim')
    import airsim
    car = airsim.CarClient()
    assert car.isApiControlEnabled() is False
    car.setCarControls(airsim.CarControls(throttle=0.5))
    for _ in range(40):
        car._client.tick()
    assert abs(car.getCarState().speed) < 0.5   # 2 s at throttle 0.5 would be several m/s
    assert car.getCarControls().throttle == 0
    client.enableApiControl(False, 'Drone1')   # the default drone ('' names it to a MultirotorClient)
    client._client.tick()
    car.enableApiControl(True)
    assert car.isApiControlEnabled() is True and car.armDisarm(True) is True
    client._client.tick()
    assert client.isApiControlEnabled('Drone1') is False   # the car's, not a drone's
    car.setCarControls(airsim.CarControls(throttle=0.5))
    for _ in range(40):
        car._client.tick()
    s = car.getCarState()
    assert s.speed > 1.0
    assert s.kinematics_estimated.position.get_length() > 1.0
    assert s.maxrpm > 0 and s.timestamp > 0
    assert car.getCarControls().throttle == 0.5
    car.enableApiControl(False)
    assert car.getCarControls().throttle == 0
    car._client.tick()
    a = car._car('')
    assert car._client.state(a['id'])['control']['throttle'] == 0   # back to the keyboard: nothing pressed
    car.enableApiControl(True)
    assert car.getCarControls().throttle == 0   # CarControls() after the change
    car.setCarControls(airsim.CarControls(brake=1.0))
