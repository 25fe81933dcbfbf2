"""The airsim module against AirSim 1.8's own API (tests/python/airsim_reference.py): every
client method exists, docs/compatibility.md's method table lists each one once with its
state, the calls marked "no" raise LockstepUnsupported naming themselves, the message types
have AirSim's fields, and settings.json is read as AirSim reads it. No simulation needed."""
import inspect
import math
import os
import re
import sys

import pytest

sys.path.insert(0, os.path.dirname(__file__))
import airsim  # noqa: E402
import airsim_reference as ref  # noqa: E402
from lockstep.airsim import settings as settings_mod  # noqa: E402

DOC = os.path.join(os.environ.get('LOCKSTEP_SOURCE', os.path.join(os.path.dirname(__file__), '..', '..')),
                   'docs', 'compatibility.md')


def doc_table():
    """call -> state ('yes', 'partly', 'no') from the AirSim method table of compatibility.md."""
    text = open(DOC).read()
    section = text.split('## airsim method table', 1)[1].split('\n## ', 1)[0]
    rows = {}
    for line in section.splitlines():
        m = re.match(r'^\| `(\w+)` \| (\w+) \| (\w+) \|', line)
        if m:
            assert m.group(1) not in rows, 'compatibility.md lists %s twice' % m.group(1)
            rows[m.group(1)] = (m.group(2), m.group(3))
    return rows


def test_the_reference_counts_airsims_methods():
    assert len(set(ref.VEHICLE_CLIENT)) == len(ref.VEHICLE_CLIENT)
    assert len(set(ref.MULTIROTOR_CLIENT)) == len(ref.MULTIROTOR_CLIENT)
    assert len(ref.VEHICLE_CLIENT) + len(ref.MULTIROTOR_CLIENT) + len(ref.CAR_CLIENT) == 132  # the count the issue gives


@pytest.mark.parametrize('cls,names', [('VehicleClient', ref.VEHICLE_CLIENT),
                                       ('MultirotorClient', ref.VEHICLE_CLIENT + ref.MULTIROTOR_CLIENT),
                                       ('CarClient', ref.VEHICLE_CLIENT + ref.CAR_CLIENT)])
def test_every_airsim_method_exists(cls, names):
    c = getattr(airsim, cls)
    missing = [n for n in names if not callable(getattr(c, n, None))]
    assert not missing


def test_the_method_table_of_the_docs_is_airsims():
    rows = doc_table()
    want = {(n, 'VehicleClient') for n in ref.VEHICLE_CLIENT} | {(n, 'MultirotorClient') for n in ref.MULTIROTOR_CLIENT} \
        | {(n, 'CarClient') for n in ref.CAR_CLIENT}
    assert {(k, v[1]) for k, v in rows.items()} == want
    assert all(v[0] in ('yes', 'partly', 'no') for v in rows.values())


def _raises_unsupported_always(f):
    """The method's body (after its docstring) is one _unsupported(...) call: it can only raise."""
    import ast
    import textwrap
    tree = ast.parse(textwrap.dedent(inspect.getsource(f)))
    body = tree.body[0].body
    if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant):
        body = body[1:]
    return (len(body) == 1 and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Call)
            and getattr(body[0].value.func, 'id', '') == '_unsupported')


def test_the_table_says_no_exactly_for_the_calls_that_only_raise():
    """The table is the code's: a call whose body only raises LockstepUnsupported is "no", and
    a "yes" or "partly" call does something (AirSim's method names from airsim_reference)."""
    rows = doc_table()
    wrong = []
    for name, (state, cls_name) in rows.items():
        f = getattr(getattr(airsim, cls_name), name)
        if _raises_unsupported_always(f) != (state == 'no'):
            wrong.append('%s: table says %s' % (name, state))
    assert not wrong


def test_settings_string_without_a_file_is_airsims_default(tmp_path):
    import json
    s = settings_mod.load(str(tmp_path / 'none.json'))
    assert json.loads(s.text) == {'SeeDocsAt': 'https://github.com/Microsoft/AirSim/blob/main/docs/settings.md',
                                  'SettingsVersion': 1.2}


def _dummy_args(f):
    """Arguments for a call that must raise before it needs any of them."""
    sig = inspect.signature(f)
    return [None for p in list(sig.parameters.values()) if p.default is inspect.Parameter.empty]


def test_calls_marked_no_raise_naming_themselves():
    rows = doc_table()
    no = [n for n, (state, _) in rows.items() if state == 'no']
    assert no
    for name in no:
        cls = getattr(airsim, rows[name][1])
        c = cls.__new__(cls)
        f = getattr(c, name)
        with pytest.raises(airsim.LockstepUnsupported, match=name):
            f(*_dummy_args(f))


@pytest.mark.parametrize('name', sorted(ref.TYPES))
def test_types_have_airsims_fields(name):
    obj = getattr(airsim, name)() if name not in ('ImageRequest',) else airsim.ImageRequest('0', 0)
    assert set(ref.TYPES[name]) <= set(vars(obj)), set(ref.TYPES[name]) - set(vars(obj))
    assert repr(obj).startswith('<%s>' % name)
    assert airsim.to_dict(obj)  # AirSim's helpers take every type


@pytest.mark.parametrize('name', sorted(ref.CONSTANTS))
def test_constants_are_airsims(name):
    cls = getattr(airsim, name)
    assert {k: getattr(cls, k) for k in ref.CONSTANTS[name]} == ref.CONSTANTS[name]


def test_helpers_exist():
    assert all(callable(getattr(airsim, h, None)) for h in ref.HELPERS)


def test_quaternion_arithmetic_is_airsims():
    q = airsim.to_quaternion(0.1, -0.2, 0.3)
    r = airsim.to_quaternion(-0.4, 0.25, 1.0)
    s = q + r
    assert (s.w_val, s.x_val) == (q.w_val + r.w_val, q.x_val + r.x_val)
    assert q.dot(q) == pytest.approx(1.0)
    assert (q / 2).w_val == q.w_val / 2
    p = q * r
    assert (p / r).w_val == pytest.approx(q.w_val) and (p / r).z_val == pytest.approx(q.z_val)
    assert q.conjugate().x_val == -q.x_val and q.star().z_val == -q.z_val
    i = q * q.inverse()
    assert (i.w_val, i.x_val, i.y_val, i.z_val) == pytest.approx((1, 0, 0, 0))
    c = q.cross(r)
    assert c.w_val == pytest.approx(0.0)   # the vector part of (qr - rq) / 2
    assert (q * 3).sgn().get_length() == pytest.approx(1.0) if hasattr(q, '__rmul__') else True
    # rotate: AirSim's (other * self * other^-1), a unit quaternion only.
    v = airsim.Quaternionr(1, 0, 0, 0)
    yaw90 = airsim.to_quaternion(0, 0, math.pi / 2)
    w = v.rotate(yaw90)
    assert (w.x_val, w.y_val, w.z_val) == pytest.approx((0, 1, 0), abs=1e-9)
    with pytest.raises(ValueError):
        v.rotate(airsim.Quaternionr(0, 0, 0, 2))
    with pytest.raises(TypeError):
        q + 1
    # external_physics_engine.py adds quaternions and passes the sum to simSetVehiclePose.
    assert (q + q).get_length() == pytest.approx(2.0)


def test_plotted_shapes_live_as_unreals_draw_debug():
    """Unreal's GetDebugLineLifeTime under AirSim's simPlot* calls: is_persistent lasts until
    simFlushPersistentMarkers whatever the duration; else the duration when > 0; else one frame:
    shown in the frame of its tick (life over one step), gone from the next (at most two steps)."""
    from lockstep.airsim.client import _plot_life
    dt = 0.05
    assert _plot_life(5.0, True, dt) == 0.0
    assert _plot_life(-1.0, True, dt) == 0.0
    assert _plot_life(2.5, False, dt) == 2.5
    for d in (-1.0, 0.0, None):
        assert dt < _plot_life(d, False, dt) <= 2 * dt


def _encoded(it, arr, as_float=False):
    from lockstep.airsim.client import _encode
    r = airsim.ImageResponse()
    r.pixels_as_float, r.compress = as_float, False
    _encode(r, it, arr)
    return r


def test_optical_flow_is_airsims():
    """AirSim's optical flow material: (current - previous) clip position / 2, so the motion as a
    fraction of the image, x right, y up; its float read-back keeps the R channel (vx) only, its
    byte read-back clamps to 0..1 (x 255.999, truncated), B G R. The render's flow is CARLA's:
    x right, y down, [-2, 2] spans the image."""
    import numpy as np
    f = np.zeros((2, 3, 2), np.float32)
    f[0, 0] = (0.4, -0.6)     # right by a fifth of the width, up by 0.3 of the height
    f[0, 1] = (-0.4, 0.6)     # left and down
    r = _encoded(airsim.ImageType.OpticalFlow, f, as_float=True)
    assert len(r.image_data_float) == 6
    assert r.image_data_float[:3] == [pytest.approx(0.2), pytest.approx(-0.2), 0.0]
    b = np.frombuffer(_encoded(airsim.ImageType.OpticalFlow, f).image_data_uint8, np.uint8).reshape(2, 3, 3)
    assert b[0, 0].tolist() == [0, 76, 51] and b[0, 1].tolist() == [0, 0, 0] and b[1, 2].tolist() == [0, 0, 0]
    # Vis: hue 180 deg + the angle, value log(|v| + 0.999) / log(1.099): right cyan, left red,
    # up (180 + 90 deg) violet, down yellow-green; no motion black; B G R bytes.
    f = np.zeros((1, 5, 2), np.float32)
    f[0, 0], f[0, 1], f[0, 2], f[0, 3] = (0.4, 0), (-0.4, 0), (0, -0.4), (0, 0.4)
    v = np.frombuffer(_encoded(airsim.ImageType.OpticalFlowVis, f).image_data_uint8, np.uint8).reshape(5, 3).tolist()
    assert v == [[255, 255, 0], [0, 0, 255], [255, 0, 128], [0, 255, 128], [0, 0, 0]]
    # A small motion is dim: |v| = 0.01 of the image.
    f = np.zeros((1, 1, 2), np.float32)
    f[0, 0] = (0.02, 0)
    g = np.frombuffer(_encoded(airsim.ImageType.OpticalFlowVis, f).image_data_uint8, np.uint8).tolist()
    assert g == [24, 24, 0]   # 255.999 x log(1.009) / log(1.099), truncated


def test_surface_normals_are_unreals_world_normals():
    """AirSim's NormalsMaterial: Unreal's world normal (X north, Y east, Z up) as (n + 1) / 2,
    whatever the camera looks at (AirSim issues 2047 and 2813): an upward face is (127, 127, 255)
    RGB from any camera; the render gives camera-frame normals."""
    import numpy as np
    from lockstep.airsim.client import _airsim_normals
    view_up, towards = [128, 255, 128, 255], [255, 128, 128, 255]   # B G R A of (0, 1, 0) and (0, 0, 1)
    level_north = airsim.to_quaternion(0, 0, 0)
    down = airsim.to_quaternion(-math.pi / 2, 0, 0)
    east = airsim.to_quaternion(0, 0, math.pi / 2)
    px = np.array([[view_up, towards, towards, [0, 0, 0, 0]]], np.uint8)
    assert _airsim_normals(px, level_north).tolist()[0][:2] == [[255, 127, 127], [127, 127, 0]]   # ground; a wall facing south
    assert _airsim_normals(px, down).tolist()[0][1] == [255, 127, 127]         # the ground seen from above
    assert _airsim_normals(px, east).tolist()[0][2:] == [[127, 0, 127], [0, 0, 0]]   # a wall facing west; the sky


def test_pfm_round_trip(tmp_path):
    import numpy as np
    img = np.arange(12, dtype=np.float32).reshape(3, 4)
    airsim.write_pfm(str(tmp_path / 'a.pfm'), img)
    back, scale = airsim.read_pfm(str(tmp_path / 'a.pfm'))
    assert scale == 1 and (back == img).all()
    with pytest.raises(Exception, match='float32'):
        airsim.write_pfm(str(tmp_path / 'b.pfm'), img.astype(np.float64))


def test_settings_read_as_airsim(tmp_path):
    s = settings_mod.parse('''{"SettingsVersion": 1.2, "SimMode": "Multirotor", "ClockSpeed": 2,
      "Wind": {"X": 1, "Y": 0, "Z": 0}, "OriginGeopoint": {"Latitude": 47.6, "Longitude": -122.1, "Altitude": 100},
      "CameraDefaults": {"CaptureSettings": [{"ImageType": 0, "Width": 640, "Height": 480}]},
      "Vehicles": {"A": {"VehicleType": "SimpleFlight", "X": 1, "Y": 2, "Z": -3, "Yaw": 90,
                         "Cameras": {"c": {"CaptureSettings": [{"ImageType": 1, "Width": 32, "Height": 16,
                                                                "FOV_Degrees": 60}], "X": 0.5, "Pitch": -10}},
                         "Sensors": {"L": {"SensorType": 6, "Enabled": true, "NumberOfChannels": 4, "Range": 20,
                                           "DataFrame": "SensorLocalFrame"}}},
                   "B": {"VehicleType": "SimpleFlight", "AutoCreate": false}}}''')
    assert (s.sim_mode, s.clock_speed, s.wind, s.origin_geopoint) == ('Multirotor', 2.0, (1.0, 0.0, 0.0),
                                                                        (47.6, -122.1, 100.0))
    a = s.vehicles['A']
    assert (a.x, a.y, a.z, a.yaw, a.auto_create, s.vehicles['B'].auto_create) == (1, 2, -3, 90, True, False)
    cam = a.cameras['c']
    cap = cam.capture_for(1, s.camera_defaults)
    assert (cap.width, cap.height, cap.fov_degrees, cam.x, cam.pitch, cam.y) == (32, 16, 60, 0.5, -10, None)
    assert cam.capture_for(0, s.camera_defaults).width == 640   # CameraDefaults for the other types
    lidar = a.sensors['L']
    assert (lidar.kind, lidar.params['channels'], lidar.params['range'], lidar.params['data_frame']) == \
        ('Lidar', 4, 20, 'SensorLocalFrame')
    assert lidar.params['upper'] == -15 and lidar.params['lower'] == -45   # AirSim's multirotor defaults
    assert settings_mod.parse('{"Vehicles": {"A": {"Sensors": {"L": {"SensorType": 6}}}}}') \
        .vehicles['A'].sensors['L'].params['data_frame'] == 'VehicleInertialFrame'   # AirSim's default frame


@pytest.mark.parametrize('text,key', [
    ('{"ClockSpeed": "fast"}', 'ClockSpeed'),
    ('{"SimMode": "Boat"}', 'SimMode'),
    ('{"Vehicles": {"D": {"X": "a"}}}', 'Vehicles.D.X'),
    ('{"Vehicles": {"D": {"VehicleType": "Zeppelin"}}}', 'Vehicles.D.VehicleType'),
    ('{"Vehicles": {"D": {"Sensors": {"L": {"SensorType": 6, "DataFrame": "World"}}}}}',
     'Vehicles.D.Sensors.L.DataFrame'),
    ('{"Vehicles": {"D": {"Sensors": {"L": {"SensorType": 9}}}}}', 'Vehicles.D.Sensors.L.SensorType'),
    ('{"Vehicles": {"D": {"Cameras": {"c": {"CaptureSettings": [{"Width": -4}]}}}}}',
     'Vehicles.D.Cameras.c.CaptureSettings[0].Width'),
    ('{"Vehicles": {"D": {"AutoCreate": "yes"}}}', 'Vehicles.D.AutoCreate'),
    ('{"Wind": {"X": null}}', 'Wind.X'),
    ('{"Vehicles": {', '(not valid JSON)'),
])
def test_a_bad_settings_value_names_its_key(text, key):
    with pytest.raises(settings_mod.SettingsError) as e:
        settings_mod.parse(text, 'settings.json')
    assert (key if key != '(not valid JSON)' else 'not valid JSON') in str(e.value)


def test_unknown_settings_keys_are_warned_not_refused():
    s = settings_mod.parse('{"NotAKey": 1, "RecordUIVisible": true, "Vehicles": {"D": {"Colour": 3}}}')
    assert any("'NotAKey'" in w for w in s.warnings)
    assert any("'Vehicles.D.Colour'" in w for w in s.warnings)
    assert any("'RecordUIVisible' is AirSim's" in w for w in s.warnings)


def test_settings_path_is_airsims(monkeypatch, tmp_path):
    monkeypatch.delenv('LOCKSTEP_AIRSIM_SETTINGS', raising=False)
    monkeypatch.setenv('HOME', str(tmp_path))
    assert settings_mod.settings_path() == str(tmp_path / 'Documents' / 'AirSim' / 'settings.json')
    assert settings_mod.load().vehicles == {}   # no file: AirSim's defaults
    (tmp_path / 'Documents' / 'AirSim').mkdir(parents=True)
    (tmp_path / 'Documents' / 'AirSim' / 'settings.json').write_text('{"ClockSpeed": 3}')
    assert settings_mod.load().clock_speed == 3
