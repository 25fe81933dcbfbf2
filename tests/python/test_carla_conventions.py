"""CARLA's data conventions in the drop-in carla module (docs/compatibility.md, *Data
conventions*): frames, signs, units and layouts of every sensor data class, each checked
against what CARLA's own code (LibCarla sensor/data, RayCastLidar.cpp, Radar.cpp,
InertialMeasurementUnit.cpp, ImageConverter, ColorCodedFlow) gives. The first half feeds
the data classes wire samples of known content; the second half runs the sensors service
(skipped when it is not built) and checks the data against the actors it sees."""
import math
import struct
import zlib

import numpy as np
import pytest

import carla
from lockstep.carla import sensor_data as sd

from conftest import has_service


# --- wire samples of known content ---------------------------------------------------------

class FakeSample:
    """What lockstep's native SensorSample offers the data classes."""

    def __init__(self, type_, fields, array=None, frame=7, sensor=99):
        self.type = type_
        self._fields = fields
        self._array = array
        self.frame = frame
        self.sim_time = frame * 0.05
        self.sensor = sensor

    def fields(self):
        return dict(self._fields)

    def array(self):
        v = self._array.view()
        v.setflags(write=False)
        return v

    def raw(self):
        v = np.ascontiguousarray(self._array).view(np.uint8).reshape(-1)
        v.setflags(write=False)
        return v


POSE = (1.0, 2.0, 3.0, 1.0, 0.0, 0.0, 0.0)


def point_cloud(points, semantic=False):
    if semantic:
        dt = np.dtype({'names': ['x', 'y', 'z', 'CosAngle', 'ObjIdx', 'ObjTag'],
                       'formats': ['<f4'] * 4 + ['<u4'] * 2, 'offsets': [0, 4, 8, 12, 16, 20], 'itemsize': 24})
        a = np.array([tuple(p) for p in points], dtype=dt)
    else:
        a = np.array(points, dtype=np.float32).reshape(-1, 4)
    f = {'transform': POSE, 'point_count': len(points), 'semantic': semantic, 'channels': [len(points)]}
    return FakeSample('point_cloud', f, a)


def image(bgra, encoding='bgra8'):
    a = np.array(bgra, dtype=np.uint8)
    f = {'transform': POSE, 'width': a.shape[1], 'height': a.shape[0], 'fov': math.radians(90), 'encoding': encoding}
    return FakeSample('image', f, a)


class FakeActor:
    def __init__(self, attributes):
        self.attributes = attributes
        self.type_id = 'sensor.camera.dvs'

    def get_transform(self):
        return carla.Transform(carla.Location(1, 2, 3))


class FakeClient:
    def __init__(self, states):
        self.states = states

    def state(self, actor):
        return self.states.get(actor)

    def actor(self, actor):
        return None


class FakeWorld:
    def __init__(self, actors=None, states=None):
        self.actors = actors or {}
        self._client = FakeClient(states or {})

    def get_actor(self, actor):
        return self.actors.get(actor)

    def _declaration(self, blueprint):
        return None


def test_lidar_raw_data_and_iteration_are_in_carlas_frame_y_right():
    # FLU (10, 2, 1): 2 m to the left. CARLA's sensor frame has y right: (10, -2, 1).
    m = sd.make_sensor_data(point_cloud([(10, 2, 1, 0.9), (5, -3, -1, 0.5)]), None)
    assert isinstance(m, carla.LidarMeasurement)
    raw = np.frombuffer(m.raw_data, dtype=np.dtype('f4')).reshape(-1, 4)
    np.testing.assert_array_equal(raw, np.array([[10, -2, 1, 0.9], [5, 3, -1, 0.5]], dtype=np.float32))
    pts = [(d.point.x, d.point.y, d.point.z, d.intensity) for d in m]
    np.testing.assert_allclose(pts, raw, rtol=0, atol=1e-6)
    assert m[1].point.y == pytest.approx(3.0)
    assert len(m) == 2 and m.get_point_count(0) == 2 and m.channels == 1


def test_semantic_lidar_has_carlas_six_fields_in_its_frame():
    m = sd.make_sensor_data(point_cloud([(10, 2, 1, 0.75, 42, 14)], semantic=True), None)
    assert isinstance(m, carla.SemanticLidarMeasurement)
    dt = np.dtype([('x', np.float32), ('y', np.float32), ('z', np.float32), ('CosAngle', np.float32),
                   ('ObjIdx', np.uint32), ('ObjTag', np.uint32)])  # CARLA's open3d_lidar.py layout
    raw = np.frombuffer(m.raw_data, dtype=dt)
    assert raw.itemsize == 24 and len(raw) == 1
    assert (raw['x'][0], raw['y'][0], raw['z'][0]) == (10, -2, 1)
    assert (raw['CosAngle'][0], raw['ObjIdx'][0], raw['ObjTag'][0]) == (0.75, 42, 14)
    d = next(iter(m))
    assert (d.point.x, d.point.y, d.point.z) == (10, -2, 1)
    assert (d.cos_inc_angle, d.object_idx, d.object_tag) == (0.75, 42, 14)


def test_lidar_save_to_disk_is_carlas_ascii_ply(tmp_path):
    m = sd.make_sensor_data(point_cloud([(10, 2, 1, 0.9)]), None)
    path = m.save_to_disk(str(tmp_path / 'cloud'))
    assert path.endswith('cloud.ply')
    text = open(path).read()
    assert text == ('ply\nformat ascii 1.0\nelement vertex 1\nproperty float32 x\nproperty float32 y\n'
                    'property float32 z\nproperty float32 I\nend_header\n10.0000 -2.0000 1.0000 0.9000\n')


def test_radar_azimuth_is_positive_to_the_right():
    # Wire (FLU): azimuth +0.1 rad = to the left. CARLA's GetAzimuthAndElevation: right positive.
    f = {'transform': POSE, 'detections': [(-3.0, 0.1, 0.02, 20.0), (1.5, -0.2, -0.01, 30.0)]}
    m = sd.make_sensor_data(FakeSample('radar', f), None)
    raw = np.frombuffer(m.raw_data, dtype=np.dtype('f4')).reshape(-1, 4)  # CARLA's manual_control.py reads it so
    np.testing.assert_allclose(raw, [[-3, -0.1, 0.02, 20], [1.5, 0.2, -0.01, 30]], rtol=1e-6)
    d = list(m)
    assert d[0].azimuth == pytest.approx(-0.1) and d[1].azimuth == pytest.approx(0.2)
    assert (d[0].velocity, d[0].altitude, d[0].depth) == pytest.approx((-3, 0.02, 20))
    assert m.get_detection_count() == 2 and len(m) == 2


def _body_rates_from_carla_matrices(q, w_flu, dt=1e-6):
    """CARLA's gyroscope as Unreal/PhysX define it: the body angular velocity in Unreal's
    coordinates, [w]x = R^T dR/dt with R from carla.Transform.get_matrix() (CARLA's own
    rotation convention) at the wire pose q and at q rotated by the FLU body rate w."""
    from lockstep.carla.geometry import from_wire_pose
    wn = math.sqrt(sum(c * c for c in w_flu))
    half = wn * dt / 2
    dq = (math.cos(half),) + tuple(c / wn * math.sin(half) for c in w_flu)
    a0, b0, c0, d0 = q
    a1, b1, c1, d1 = dq
    q2 = (a0 * a1 - b0 * b1 - c0 * c1 - d0 * d1, a0 * b1 + b0 * a1 + c0 * d1 - d0 * c1,
          a0 * c1 - b0 * d1 + c0 * a1 + d0 * b1, a0 * d1 + b0 * c1 - c0 * b1 + d0 * a1)
    r1 = np.array(from_wire_pose((0, 0, 0) + tuple(q)).get_matrix())[:3, :3]
    r2 = np.array(from_wire_pose((0, 0, 0) + tuple(q2)).get_matrix())[:3, :3]
    s = r1.T @ (r2 - r1) / dt
    return np.array([s[2, 1], s[0, 2], s[1, 0]])


@pytest.mark.parametrize('w', [(0.3, 0, 0), (0, 0.3, 0), (0, 0, 0.3), (0.2, -0.1, 0.4)])
def test_imu_gyroscope_is_the_angular_velocity_in_carlas_sensor_frame(w):
    q = (math.cos(0.2), 0.3 * math.sin(0.2), -0.2 * math.sin(0.2), math.sqrt(0.87) * math.sin(0.2))
    f = {'accelerometer': (0.5, -2.0, 9.81), 'gyroscope': w, 'compass': 1.25, 'orientation': q}
    m = sd.make_sensor_data(FakeSample('imu', f), None)
    expected = _body_rates_from_carla_matrices(q, w)
    np.testing.assert_allclose([m.gyroscope.x, m.gyroscope.y, m.gyroscope.z], expected, atol=1e-5)
    # Roll right (FLU +x) is a negative rate about Unreal's x; a right turn (FLU -z) positive about z.
    assert (m.accelerometer.x, m.accelerometer.y, m.accelerometer.z) == pytest.approx((0.5, 2.0, 9.81))
    assert m.compass == 1.25


@pytest.mark.parametrize('w', [(0.3, 0, 0), (0, 0.3, 0), (0, 0, 0.3), (0.2, -0.1, 0.4)])
def test_actor_angular_velocity_is_carlas_world_rates_in_degrees(w):
    # World-frame rates: [w]x = dR/dt R^T with CARLA's matrices, in deg/s.
    from lockstep.carla.geometry import from_wire_pose
    dt = 1e-6
    wn = math.sqrt(sum(c * c for c in w))
    half = wn * dt / 2
    dq = (math.cos(half),) + tuple(c / wn * math.sin(half) for c in w)
    q = (1.0, 0.0, 0.0, 0.0)  # world rates: rotate the identity by the world rate
    r1 = np.array(from_wire_pose((0, 0, 0) + q).get_matrix())[:3, :3]
    r2 = np.array(from_wire_pose((0, 0, 0) + dq).get_matrix())[:3, :3]
    s = (r2 - r1) @ r1.T / dt
    expected = np.degrees([s[2, 1], s[0, 2], s[1, 0]])
    states = {5: {'transform': (0, 0, 0) + q, 'angular_velocity': w, 'velocity': (0, 0, 0)}}
    actor = carla.Actor(FakeWorld(states=states), {'id': 5, 'blueprint': 'vehicle.audi.tt'})
    v = actor.get_angular_velocity()
    np.testing.assert_allclose([v.x, v.y, v.z], expected, atol=1e-3)


def test_image_convert_rewrites_raw_data_with_carlas_formulas(tmp_path):
    # Depth: (R + G 256 + B 65536) / (256^3 - 1) -> uint8(x * 255 + 0.5), gray, alpha 255.
    px = [[[255, 255, 255, 0], [0, 0, 0, 0], [64, 0, 0, 0], [0, 0, 255, 0]]]  # BGRA
    im = sd.make_sensor_data(image(px, 'depth_carla_bgra8'), None)
    before = bytes(im.raw_data)
    im.convert(carla.ColorConverter.Depth)
    raw = np.frombuffer(im.raw_data, dtype=np.uint8).reshape(1, 4, 4)
    assert bytes(im.raw_data) != before
    # 1.0 -> 255; 0 -> 0; B 64 -> 0.25 -> 64; R 255 -> 255 / 16777215 -> 0
    np.testing.assert_array_equal(raw[0, :, 0], [255, 0, 64, 0])
    np.testing.assert_array_equal(raw[0, :, 0], raw[0, :, 1])
    np.testing.assert_array_equal(raw[0, :, 0], raw[0, :, 2])
    np.testing.assert_array_equal(raw[0, :, 3], [255] * 4)
    # LogarithmicDepth: clamp(1 + ln(x) / 5.70378, 0, 1): 1 -> 255, 0 -> 0, 0.25 -> 193.
    im = sd.make_sensor_data(image(px, 'depth_carla_bgra8'), None)
    im.convert(carla.ColorConverter.LogarithmicDepth)
    raw = np.frombuffer(im.raw_data, dtype=np.uint8).reshape(1, 4, 4)
    np.testing.assert_array_equal(raw[0, :, 2], [255, 0, 193, 0])
    # CityScapesPalette: the red channel's tag -> CARLA's palette (RGB), written BGRA.
    seg = [[[0, 0, 14, 0], [0, 0, 1, 0], [0, 0, 24, 0], [0, 0, 0, 0]]]
    im = sd.make_sensor_data(image(seg, 'semantic_bgra8'), None)
    im.convert(carla.ColorConverter.CityScapesPalette)
    raw = np.frombuffer(im.raw_data, dtype=np.uint8).reshape(1, 4, 4)
    np.testing.assert_array_equal(raw[0], [[142, 0, 0, 255], [128, 64, 128, 255], [50, 234, 157, 255], [0, 0, 0, 255]])
    assert im[0] == carla.Color(0, 0, 142, 255)  # iteration sees the converted pixels too
    # Raw changes nothing.
    im = sd.make_sensor_data(image(px), None)
    im.convert(carla.ColorConverter.Raw)
    assert bytes(im.raw_data) == bytes(np.array(px, dtype=np.uint8).reshape(-1))
    with pytest.raises(ValueError, match='color converter'):
        im.convert(7)
    # A one-channel image (gray8) reads as gray BGRA pixels.
    g = FakeSample('image', {'transform': POSE, 'width': 2, 'height': 1, 'fov': 1.0, 'encoding': 'gray8'},
                   np.array([[7, 200]], dtype=np.uint8))
    assert list(sd.make_sensor_data(g, None)) == [carla.Color(7, 7, 7, 255), carla.Color(200, 200, 200, 255)]


def _read_png(path):
    data = open(path, 'rb').read()
    assert data[:8] == b'\x89PNG\r\n\x1a\n'
    pos, idat, ihdr = 8, b'', None
    while pos < len(data):
        n, tag = struct.unpack('>I4s', data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        if tag == b'IHDR':
            ihdr = struct.unpack('>IIBBBBB', body)
        elif tag == b'IDAT':
            idat += body
        pos += 12 + n
    w, h, depth, color_type = ihdr[:4]
    channels = {0: 1, 2: 3, 6: 4}[color_type]
    rows = np.frombuffer(zlib.decompress(idat), dtype=np.uint8).reshape(h, 1 + w * channels)
    assert (rows[:, 0] == 0).all()  # filter 'none'
    return rows[:, 1:].reshape(h, w, channels) if channels > 1 else rows[:, 1:].reshape(h, w)


def test_image_save_to_disk_writes_what_carla_writes(tmp_path):
    px = [[[255, 255, 255, 255], [0, 0, 0, 255], [64, 0, 0, 255], [10, 20, 30, 255]]]
    im = sd.make_sensor_data(image(px, 'depth_carla_bgra8'), None)
    raw_png = _read_png(im.save_to_disk(str(tmp_path / 'raw')))  # '.png' added, RGBA
    np.testing.assert_array_equal(raw_png[0, 3], [30, 20, 10, 255])
    depth_png = _read_png(im.save_to_disk(str(tmp_path / 'depth.png'), carla.ColorConverter.Depth))
    assert depth_png.ndim == 2  # CARLA writes the converted view as 8-bit gray
    # (30 + 20 * 256 + 10 * 65536) / 16777215 = 0.03937: 10.04 -> 10; log: 0.4329 -> 110.
    np.testing.assert_array_equal(depth_png[0], [255, 0, 64, 10])
    log_png = _read_png(im.save_to_disk(str(tmp_path / 'log.png'), carla.ColorConverter.LogarithmicDepth))
    np.testing.assert_array_equal(log_png[0], [255, 0, 193, 110])
    assert im.save_to_disk(str(tmp_path / '%06d.png')).endswith('000007.png')


def test_optical_flow_image_and_carlas_color_coding():
    flow = np.array([[[1, 0], [0, 0], [-1, 0], [0, 1]]], dtype=np.float32)
    f = {'transform': POSE, 'width': 4, 'height': 1, 'fov': math.radians(90), 'encoding': 'flow_f32x2'}
    m = sd.make_sensor_data(FakeSample('image', f, flow), None)
    assert isinstance(m, carla.OpticalFlowImage)
    np.testing.assert_array_equal(np.frombuffer(m.raw_data, dtype=np.float32), flow.reshape(-1))
    assert (m[3].x, m[3].y) == (0, 1) and len(m) == 4
    cc = m.get_color_coded_flow()
    assert (cc.width, cc.height, cc.fov) == (4, 1, pytest.approx(90))
    out = np.frombuffer(cc.raw_data, dtype=np.uint8).reshape(1, 4, 4)
    # ColorCodedFlow: hue 180 + angle (deg), value from the norm, BGRA with alpha 0.
    # (1, 0): hue 180 -> cyan (CARLA's float32 H / 60 is 3.0000002: green 254); (0, 0): black;
    # (-1, 0): hue ~0 -> red; (0, 1): hue 270 -> (127, 0, 255).
    np.testing.assert_array_equal(out[0], [[255, 254, 0, 0], [0, 0, 0, 0], [0, 0, 255, 0], [255, 0, 127, 0]])
    assert len(cc) == 16


def _dvs_wire(events):
    dt = np.dtype({'names': ['x', 'y', 'pol', 't'], 'formats': ['<u2', '<u2', '?', '<i8'], 'offsets': [0, 2, 4, 8],
                   'itemsize': 16})
    return np.array([(x, y, p, t) for x, y, t, p in events], dtype=dt)


def test_dvs_event_array_is_carlas_13_byte_layout():
    events = [(1, 2, 1000, True), (3, 0, 2000, False), (0, 2, 3000, False)]
    f = {'transform': POSE, 'width': len(events), 'height': 1, 'fov': math.radians(90), 'encoding': 'dvs_events'}
    world = FakeWorld(actors={99: FakeActor({'image_size_x': '4', 'image_size_y': '3'})})
    m = sd.make_sensor_data(FakeSample('image', f, _dvs_wire(events), sensor=99), world)
    assert isinstance(m, carla.DVSEventArray)
    assert (m.width, m.height, len(m)) == (4, 3, 3)
    # CARLA's manual_control.py reads the events so.
    raw = np.frombuffer(m.raw_data, dtype=np.dtype([('x', np.uint16), ('y', np.uint16), ('t', np.int64),
                                                    ('pol', np.bool_)]))
    assert len(m.raw_data) == 13 * 3
    assert raw.tolist() == [(1, 2, 1000, True), (3, 0, 2000, False), (0, 2, 3000, False)]
    assert m.to_array() == [[1, 2, 1000, 1], [3, 0, 2000, -1], [0, 2, 3000, -1]]
    assert (m.to_array_x(), m.to_array_y(), m.to_array_t(), m.to_array_pol()) == (
        [1, 3, 0], [2, 0, 2], [1000, 2000, 3000], [1, -1, -1])
    img = m.to_image()
    assert len(img) == 12
    assert img[2 * 4 + 1] == carla.Color(0, 0, 255, 0)  # positive: blue
    assert img[0 * 4 + 3] == carla.Color(255, 0, 0, 0)  # negative: red
    assert img[0] == carla.Color(0, 0, 0, 0)
    e = m[0]
    assert (e.x, e.y, e.t, e.pol) == (1, 2, 1000, True)


@pytest.mark.parametrize('tag,type_id', [(3, 'static.building'), (1, 'static.road'), (6, 'static.pole'),
                                         (24, 'static.roadline'), (20, 'static.static'), (0, 'static.unknown'),
                                         (22, 'static.unknown'), (9, 'static.vegetation')])
def test_collision_with_static_geometry_gives_carlas_static_actor(tag, type_id):
    f = {'actor': 5, 'other_actor': 0, 'other_kind': 2, 'other_semantic_tag': tag, 'normal_impulse': (1.0, 2.0, 3.0)}
    e = sd.make_sensor_data(FakeSample('collision', f), FakeWorld(actors={5: 'car'}))
    assert e.actor == 'car'
    assert e.other_actor is not None and e.other_actor.id == 0
    assert e.other_actor.type_id == type_id
    assert (e.normal_impulse.x, e.normal_impulse.y, e.normal_impulse.z) == (1.0, -2.0, 3.0)  # N s, CARLA's frame
    ob = sd.make_sensor_data(FakeSample('obstacle', {'actor': 5, 'other_actor': 0, 'other_kind': 2,
                                                     'other_semantic_tag': tag, 'distance': 4.0}), FakeWorld())
    assert ob.other_actor.type_id == type_id and ob.distance == 4.0


# --- the sensors service, end to end ------------------------------------------------------

needs_sensors = pytest.mark.skipif(not has_service('sensors'), reason='the sensors service is not built')


@pytest.fixture(scope='module')
def world(sim):
    client = carla.Client('localhost', 2000)
    client.set_timeout(30)
    return client.get_world()


def _latest(world, sensor, ticks=3):
    got = []
    sensor.listen(got.append)
    try:
        for _ in range(ticks):
            world.tick()
    finally:
        sensor.stop()
    assert got, 'no data from %s' % sensor.type_id
    return got[-1]


def _in_box(world_points, actor, margin):
    """Which points (N, 3 in CARLA's world frame) lie in the actor's bounding box (+margin)."""
    inv = np.array(actor.get_transform().get_inverse_matrix())
    local = (inv[:3, :3] @ world_points.T).T + inv[:3, 3]
    bb = actor.bounding_box
    c = np.array([bb.location.x, bb.location.y, bb.location.z])
    e = np.array([bb.extent.x, bb.extent.y, bb.extent.z]) + margin
    return np.all(np.abs(local - c) <= e, axis=1)


@pytest.fixture(scope='module')
def car_on_the_right(world):
    """A car 7 m to the right (CARLA +y) of the sensor spot (47.75, -1.75), its lane."""
    lib = world.get_blueprint_library()
    car = world.try_spawn_actor(lib.find('vehicle.tesla.model3') if lib.filter('vehicle.tesla.model3') else
                                lib.filter('vehicle.*')[0], carla.Transform(carla.Location(60.0, 5.25, 0.3)))
    assert car is not None
    for _ in range(20):
        world.tick()  # settles on its wheels
    yield car
    car.destroy()


@needs_sensors
@pytest.mark.parametrize('semantic', [False, True])
def test_lidar_cloud_lands_on_the_car_to_its_right(world, car_on_the_right, semantic):
    car = car_on_the_right
    bp = world.get_blueprint_library().find('sensor.lidar.ray_cast_semantic' if semantic else 'sensor.lidar.ray_cast')
    for k, v in (('range', '40'), ('channels', '32'), ('points_per_second', '200000'), ('rotation_frequency', '20'),
                 ('upper_fov', '10'), ('lower_fov', '-30')):
        bp.set_attribute(k, v)
    if not semantic:
        bp.set_attribute('dropoff_general_rate', '0')
    lidar = world.spawn_actor(bp, carla.Transform(carla.Location(60.0, -1.75, 1.2)))
    try:
        m = _latest(world, lidar)
        if semantic:
            p = np.frombuffer(m.raw_data, dtype=np.dtype([('x', 'f4'), ('y', 'f4'), ('z', 'f4'), ('c', 'f4'),
                                                          ('idx', 'u4'), ('tag', 'u4')]))
            mine = p['idx'] == car.id
            every = np.stack([p['x'], p['y'], p['z']], axis=1)
            local = every[mine]
            assert mine.sum() > 20
            assert set(p['tag'][mine].tolist()) == {14}  # CARLA's Car
        else:
            every = np.frombuffer(m.raw_data, dtype=np.dtype('f4')).reshape(-1, 4)[:, :3]
            local = every
        # lidar_to_camera.py's way: the sensor's matrix takes raw_data points to the world.
        mat = np.array(m.transform.get_matrix())
        pts = (mat[:3, :3] @ local.T).T + mat[:3, 3]
        hit = _in_box(pts, car, 0.3)
        assert hit.sum() > 20, 'points on the car: %d of %d' % (hit.sum(), len(pts))
        assert (local[hit][:, 1] > 0).all(), 'the car is on the right: y > 0 in CARLA\'s sensor frame'
        if semantic:
            assert hit.all()
        # Iteration agrees with raw_data.
        first = next(iter(m))
        assert (first.point.x, first.point.y, first.point.z) == pytest.approx(tuple(float(c) for c in every[0]))
    finally:
        lidar.destroy()


@needs_sensors
def test_radar_detections_land_on_the_car_with_carlas_azimuth(world, car_on_the_right):
    car = car_on_the_right
    bp = world.get_blueprint_library().find('sensor.other.radar')
    for k, v in (('horizontal_fov', '40'), ('vertical_fov', '2'), ('range', '50'), ('points_per_second', '20000')):
        bp.set_attribute(k, v)
    # 20 m behind the car along the road, looking 10 deg right of the road: the car is about
    # 9 deg right of the radar's axis.
    radar = world.spawn_actor(bp, carla.Transform(carla.Location(40.0, -1.75, 0.8), carla.Rotation(yaw=10)))
    try:
        m = _latest(world, radar)
        rot = m.transform.rotation
        pts = []
        for d in m:
            # CARLA's manual_control.py draws a detection at yaw + azimuth, pitch + altitude.
            fw = carla.Vector3D(x=d.depth)
            t = carla.Transform(carla.Location(), carla.Rotation(pitch=rot.pitch + math.degrees(d.altitude),
                                                                 yaw=rot.yaw + math.degrees(d.azimuth), roll=rot.roll))
            v = t.transform(fw)
            pts.append((m.transform.location.x + v.x, m.transform.location.y + v.y, m.transform.location.z + v.z))
        pts = np.array(pts)
        hit = _in_box(pts, car, 0.3)
        assert hit.sum() > 20, 'detections on the car: %d of %d' % (hit.sum(), len(pts))
        az = np.frombuffer(m.raw_data, dtype=np.dtype('f4')).reshape(-1, 4)[:, 1]
        assert (az[hit] > 0).all(), 'the car is right of the axis: azimuth > 0'
    finally:
        radar.destroy()


@needs_sensors
def test_imu_at_rest_reads_gravity_up_and_compass_from_north_clockwise(world):
    bp = world.get_blueprint_library().find('sensor.other.imu')
    assert bp.get_attribute('noise_gyro_bias_stability').as_float() == 0.0  # no random walk, as CARLA
    imu = world.spawn_actor(bp, carla.Transform(carla.Location(60.0, -1.75, 5.0), carla.Rotation(yaw=30)))
    try:
        m = _latest(world, imu, ticks=4)
        assert (m.accelerometer.x, m.accelerometer.y, m.accelerometer.z) == pytest.approx((0, 0, 9.81), abs=1e-6)
        assert (m.gyroscope.x, m.gyroscope.y, m.gyroscope.z) == (0, 0, 0)
        # North is CARLA's -y: facing yaw 30 (30 deg clockwise from +x, east) is 120 deg from north.
        assert m.compass == pytest.approx(math.radians(120), abs=1e-6)
    finally:
        imu.destroy()


@needs_sensors
def test_gnss_matches_the_maps_geolocation_of_its_location(world):
    gnss = world.spawn_actor(world.get_blueprint_library().find('sensor.other.gnss'),
                             carla.Transform(carla.Location(150.0, 60.0, 2.0)))
    try:
        m = _latest(world, gnss)
        assert m.transform.location.distance(carla.Location(150.0, 60.0, 2.0)) < 1e-6
        g = world.get_map().transform_to_geolocation(m.transform.location)
        assert (m.latitude, m.longitude, m.altitude) == pytest.approx((g.latitude, g.longitude, g.altitude), abs=1e-9)
    finally:
        gnss.destroy()


@needs_sensors
def test_a_right_turn_reads_a_positive_yaw_rate(world):
    lib = world.get_blueprint_library()
    if not has_service('ground_sim'):
        pytest.skip('ground_sim is not built')
    car = world.try_spawn_actor(lib.filter('vehicle.*')[0], carla.Transform(carla.Location(47.75, -1.75, 0.3)))
    assert car is not None
    imu = world.spawn_actor(lib.find('sensor.other.imu'), carla.Transform(), attach_to=car)
    got = []
    imu.listen(got.append)
    try:
        for _ in range(10):
            world.tick()
        car.apply_control(carla.VehicleControl(throttle=0.7, steer=0.5))  # steer > 0: right
        yaw0 = car.get_transform().rotation.yaw
        for _ in range(40):
            world.tick()
        dyaw = (car.get_transform().rotation.yaw - yaw0 + 180) % 360 - 180
        assert dyaw > 5, 'CARLA yaw grows turning right'
        assert got[-1].gyroscope.z > 0.05
        assert car.get_angular_velocity().z > 3  # deg/s
        assert got[-1].gyroscope.z == pytest.approx(math.radians(car.get_angular_velocity().z), rel=0.2)
    finally:
        imu.stop()
        imu.destroy()
        car.destroy()


@needs_sensors
def test_a_sensor_attached_to_a_car_is_mounted_from_carlas_vehicle_origin(world):
    """CARLA's attachment transform is relative to the vehicle's origin (the base of its box):
    a sensor at z=1.4 looking down is 1.4 m above the road, for the client and the services."""
    if not has_service('ground_sim'):
        pytest.skip('ground_sim is not built')
    lib = world.get_blueprint_library()
    car = world.try_spawn_actor(lib.filter('vehicle.*')[0], carla.Transform(carla.Location(47.75, -1.75, 0.3)))
    assert car is not None
    bp = lib.find('sensor.other.obstacle')
    bp.set_attribute('distance', '10')
    bp.set_attribute('hit_radius', '0.05')
    det = world.spawn_actor(bp, carla.Transform(carla.Location(x=1.5, z=1.4), carla.Rotation(pitch=-90)), attach_to=car)
    try:
        for _ in range(20):  # settle on the road
            world.tick()
        local = car.get_transform().inverse_transform(det.get_transform().location)
        assert (local.x, local.y, local.z) == pytest.approx((1.5, 0.0, 1.4), abs=0.02)
        e = _latest(world, det)
        assert e.other_actor is not None and e.other_actor.type_id == 'static.road'
        assert e.distance == pytest.approx(1.4, abs=0.15)  # the car's origin is within 0.25 m of the road
    finally:
        det.destroy()
        car.destroy()


@needs_sensors
def test_an_obstacle_detector_looking_down_sees_carlas_static_road(world):
    bp = world.get_blueprint_library().find('sensor.other.obstacle')
    bp.set_attribute('distance', '10')
    bp.set_attribute('hit_radius', '0.1')
    det = world.spawn_actor(bp, carla.Transform(carla.Location(60.0, -1.75, 4.0), carla.Rotation(pitch=-90)))
    try:
        e = _latest(world, det)
        assert e.other_actor is not None and e.other_actor.id == 0
        assert e.other_actor.type_id == 'static.road'  # the road mesh, CARLA's Roads tag
        assert e.distance == pytest.approx(4.0, abs=0.3)
    finally:
        det.destroy()



def test_int_attributes_are_read_as_carla_reads_them_with_atoi():
    # lidar_to_camera.py sets channels to str(64.0); CARLA's ActorAttribute reads ints with atoi.
    decl = {'id': 'sensor.lidar.ray_cast', 'tags': '', 'kind': 'sensor',
            'attributes': [{'id': 'channels', 'type': 'int', 'default': '32', 'min': 1, 'max': 256,
                            'recommended_values': ['32'], 'modifiable': True, 'restricted': False}]}
    bp = carla.ActorBlueprint(decl)
    bp.set_attribute('channels', '64.0')
    assert bp.get_attribute('channels').as_int() == 64
    assert bp.spawn_attributes()['channels'] == '64'  # what the sensors service is sent
    with pytest.raises(ValueError, match='channels'):
        bp.set_attribute('channels', 'many')


@pytest.mark.skipif(not has_service('render'), reason='the render service is not built')
def test_listen_to_gbuffer_delivers_the_render_passes_and_black_for_the_rest(world):
    bp = world.get_blueprint_library().find('sensor.camera.rgb')
    bp.set_attribute('image_size_x', '64')
    bp.set_attribute('image_size_y', '48')
    cam = world.spawn_actor(bp, carla.Transform(carla.Location(60.0, -1.75, 2.0)))
    got = {}
    ids = [carla.GBufferTextureID.SceneColor, carla.GBufferTextureID.SceneDepth, carla.GBufferTextureID.GBufferA,
           carla.GBufferTextureID.Velocity, carla.GBufferTextureID.GBufferB]
    try:
        cam.enable_gbuffers(True)
        for t in ids:
            cam.listen_to_gbuffer(t, lambda image, t=t: got.setdefault(t, []).append(image))
        assert cam.is_listening_gbuffer(carla.GBufferTextureID.SceneDepth)
        for _ in range(40):  # the companions spawn on their own threads, as CARLA's call returns at once
            world.tick()
            if all(got.get(t) for t in ids):
                break
        for t in ids:
            assert got.get(t), 'texture %d: nothing' % t
            im = got[t][-1]
            assert isinstance(im, carla.Image) and (im.width, im.height) == (64, 48)
            assert len(im.raw_data) == 64 * 48 * 4
        depth = np.frombuffer(got[carla.GBufferTextureID.SceneDepth][-1].raw_data, dtype=np.uint8).reshape(48, 64, 4)
        assert depth[..., :3].any()  # CARLA's depth encoding of the scene
        black = np.frombuffer(got[carla.GBufferTextureID.GBufferB][-1].raw_data, dtype=np.uint8).reshape(48, 64, 4)
        assert not black[..., :3].any()
        cam.stop_gbuffer(carla.GBufferTextureID.SceneDepth)
        assert not cam.is_listening_gbuffer(carla.GBufferTextureID.SceneDepth)
        with pytest.raises(ValueError, match='G-buffer'):
            cam.listen_to_gbuffer(13, print)
    finally:
        cam.destroy()
    world.tick()
    assert not [a for a in world.get_actors() if a.attributes.get('role_name', '').startswith('_gbuffer_')]
