"""AirSim's settings.json, read where AirSim reads it: $LOCKSTEP_AIRSIM_SETTINGS, else
~/Documents/AirSim/settings.json (AirSim's default path). The simulation's AirSim side
is set up from it when the first airsim client of a run connects: the vehicles it names
at their poses (NED metres and degrees from the player start), their cameras and sensors,
the clock speed, the wind and the origin geo point (docs/compatibility.md, settings.json).

As AirSim: a key AirSim does not know is accepted with a warning; a key of AirSim's that
Lockstep does not use is accepted with a warning saying so; a bad value raises
SettingsError naming the key (AirSim refuses to start on one)."""
import json
import logging
import math
import os

__all__ = ['SettingsError', 'Settings', 'load', 'settings_path']

log = logging.getLogger('lockstep.airsim')


class SettingsError(ValueError):
    """A settings.json value AirSim would refuse: the message names the file and the key."""


# AirSim's ImageType numbers (types.py).
IMAGE_TYPES = range(-1, 10)
# AirSim's sensor types (SensorBase::SensorType).
SENSOR_TYPES = {1: 'Barometer', 2: 'Imu', 3: 'Gps', 4: 'Magnetometer', 5: 'Distance', 6: 'Lidar'}
LIDAR_FRAMES = ('SensorLocalFrame', 'VehicleInertialFrame')
SIM_MODES = ('', 'Multirotor', 'Car', 'ComputerVision')
VEHICLE_TYPES = {'simpleflight': 'Multirotor', 'px4multirotor': 'Multirotor', 'arducopter': 'Multirotor',
                 'arducoptersolo': 'Multirotor', 'physxcar': 'Car', 'ardurover': 'Car', 'computervision': 'ComputerVision'}

# Keys Lockstep reads, and AirSim's keys it accepts without using (the warning says so).
_TOP_USED = {'SettingsVersion', 'SeeDocsAt', 'SimMode', 'ClockSpeed', 'Vehicles', 'CameraDefaults', 'Wind',
             'OriginGeopoint', 'ViewMode', 'Recording', 'ClockType'}
_TOP_AIRSIM = {'LocalHostIp', 'ApiServerPort', 'RecordUIVisible', 'LogMessagesVisible', 'ShowLosDebugLines',
               'RpcEnabled', 'EngineSound', 'PhysicsEngineName', 'SpeedUnitFactor', 'SpeedUnitLabel',
               'CameraDirector', 'TimeOfDay', 'SubWindows', 'SegmentationSettings', 'PawnPaths',
               'EnableCollisionPassthrogh', 'EnableCollisions', 'MoveWorldOrigin', 'InitialViewMode',
               'ExternalCameras', 'DefaultSensors', 'NoiseSettings', 'LevelName'}
_VEHICLE_USED = {'VehicleType', 'AutoCreate', 'X', 'Y', 'Z', 'Roll', 'Pitch', 'Yaw', 'Cameras', 'Sensors',
                 'DefaultVehicleState', 'AllowAPIAlways', 'EnableTrace'}
_VEHICLE_AIRSIM = {'PawnPath', 'EnableCollisionPassthrogh', 'EnableCollisions', 'RC', 'IsFpvVehicle', 'Parameters',
                   'UdpIp', 'UdpPort', 'ControlIp', 'ControlPort', 'LocalHostIp', 'Model', 'LockStep',
                   'UseSerial', 'UseTcp', 'TcpPort', 'Logs', 'SerialBaudRate', 'SerialPort', 'ControlPortLocal',
                   'ControlPortRemote', 'SitlIp', 'SitlPort', 'QgcHostIp', 'QgcPort', 'UdpPortLocal'}
_CAMERA_USED = {'CaptureSettings', 'X', 'Y', 'Z', 'Roll', 'Pitch', 'Yaw'}
_CAMERA_AIRSIM = {'NoiseSettings', 'Gimbal', 'UnrealEngine', 'ExternalCamera'}
_CAPTURE_USED = {'ImageType', 'Width', 'Height', 'FOV_Degrees'}
_CAPTURE_AIRSIM = {'AutoExposureSpeed', 'AutoExposureBias', 'AutoExposureMaxBrightness', 'AutoExposureMinBrightness',
                   'MotionBlurAmount', 'TargetGamma', 'ProjectionMode', 'OrthoWidth', 'IgnoreMarked',
                   'LumensOfLight', 'ChromaticAberration'}
_SENSOR_USED = {'SensorType', 'Enabled', 'X', 'Y', 'Z', 'Roll', 'Pitch', 'Yaw', 'NumberOfChannels', 'Range',
                'RotationsPerSecond', 'PointsPerSecond', 'VerticalFOVUpper', 'VerticalFOVLower',
                'HorizontalFOVStart', 'HorizontalFOVEnd', 'DataFrame', 'MinDistance', 'MaxDistance'}
_SENSOR_AIRSIM = {'DrawDebugPoints', 'ExternalController', 'GenerateNoise', 'MinSegmentationID',
                  'UpdateFrequency', 'StartupDelay', 'PressureFactorSigma', 'PressureFactorTau', 'UncorrelatedNoiseSigma',
                  'EphTimeConstant', 'EpvTimeConstant', 'EphInitial', 'EpvInitial', 'EphFinal', 'EpvFinal',
                  'EphMin3d', 'EphMin2d', 'NoiseSigma', 'ScaleFactor', 'NoiseBias', 'DynamicsFrequency',
                  'AngularRandomWalk', 'TauGyroBias', 'GyroBiasStability', 'VelocityRandomWalk', 'TauAccelBias',
                  'AccelBiasStability', 'Mean', 'Stddev'}
_RECORDING_USED = {'RecordOnMove', 'RecordInterval', 'Folder', 'Enabled', 'Cameras'}
_RECORDING_CAMERA_USED = {'CameraName', 'ImageType', 'PixelsAsFloat', 'VehicleName', 'Compress'}
_GEO_USED = {'Latitude', 'Longitude', 'Altitude'}
_VEC_USED = {'X', 'Y', 'Z'}


def settings_path():
    """Where AirSim's settings are read: $LOCKSTEP_AIRSIM_SETTINGS, else AirSim's own
    ~/Documents/AirSim/settings.json."""
    env = os.environ.get('LOCKSTEP_AIRSIM_SETTINGS')
    if env:
        return env
    return os.path.join(os.path.expanduser('~'), 'Documents', 'AirSim', 'settings.json')


class CaptureSetting:
    def __init__(self, image_type=0, width=256, height=144, fov_degrees=90.0):
        self.image_type, self.width, self.height, self.fov_degrees = image_type, width, height, fov_degrees


class CameraSetting:
    """A camera of settings.json: its mount (X Y Z m, Roll Pitch Yaw deg, body FRD; None where
    the key is absent: the vehicle's default camera keeps its own) and its capture settings
    by image type (-1 = every type)."""

    def __init__(self, name):
        self.name = name
        self.x = self.y = self.z = None
        self.roll = self.pitch = self.yaw = None
        self.capture = {}   # image_type -> CaptureSetting

    def capture_for(self, image_type, defaults=None):
        for source in (self.capture, (defaults.capture if defaults else {})):
            if image_type in source:
                return source[image_type]
            if -1 in source:
                return source[-1]
        return CaptureSetting(image_type)


class SensorSetting:
    def __init__(self, name, sensor_type):
        self.name, self.sensor_type = name, sensor_type
        self.enabled = True
        self.x = self.y = self.z = None
        self.roll = self.pitch = self.yaw = None
        self.params = {}

    @property
    def kind(self):
        return SENSOR_TYPES[self.sensor_type]


class RecordingSetting:
    """settings.json's Recording block, AirSim's defaults (RecordingSetting in AirSimSettings.hpp).
    Lockstep records with its recorder (docs/compatibility.md): `cameras` are read and checked
    but no image files are written."""

    def __init__(self):
        self.record_on_move = False
        self.record_interval = 0.05   # s
        self.folder = ''              # '' = AirSim's ~/Documents/AirSim
        self.enabled = False
        self.cameras = [{'camera_name': '0', 'image_type': 0, 'pixels_as_float': False, 'vehicle_name': '',
                         'compress': True}]


class VehicleSetting:
    def __init__(self, name, vehicle_type='SimpleFlight'):
        self.name, self.vehicle_type = name, vehicle_type
        self.x = self.y = self.z = 0.0            # m, NED from the player start
        self.roll = self.pitch = self.yaw = 0.0   # deg
        self.yaw_given = False                    # no Yaw: a car takes the player start's heading (AirSim's)
        self.auto_create = True
        self.cameras = {}
        self.sensors = {}
        self.default_state = 'Armed'
        self.allow_api_always = True

    @property
    def mode(self):
        return VEHICLE_TYPES.get(self.vehicle_type.lower(), 'Multirotor')


class Settings:
    """settings.json, checked. `text` is the file's text (getSettingsString)."""

    def __init__(self):
        self.path = None
        self.text = '{}'
        self.sim_mode = ''
        self.clock_speed = 1.0
        self.clock_type = ''
        self.view_mode = ''
        self.vehicles = {}
        self.camera_defaults = CameraSetting('CameraDefaults')
        self.wind = (0.0, 0.0, 0.0)             # m/s, world NED
        self.origin_geopoint = None             # (lat deg, lon deg, alt m) or None: the map's
        self.recording = RecordingSetting()
        self.warnings = []

    def default_vehicle(self):
        """AirSim with no Vehicles: one vehicle of the sim mode, 'SimpleFlight' for multirotors."""
        if self.sim_mode == 'Car':
            return VehicleSetting('PhysXCar', 'PhysXCar')
        if self.sim_mode == 'ComputerVision':
            return VehicleSetting('ComputerVision', 'ComputerVision')
        return VehicleSetting('SimpleFlight', 'SimpleFlight')

    def all_vehicles(self):
        return list(self.vehicles.values()) if self.vehicles else [self.default_vehicle()]


class _Reader:
    def __init__(self, path):
        self.path = path
        self.warnings = []

    def fail(self, key, why):
        raise SettingsError('%s: %s: %s' % (self.path, key, why))

    def warn(self, text):
        self.warnings.append(text)
        log.warning('%s: %s', self.path, text)

    def keys(self, obj, where, used, airsim):
        if not isinstance(obj, dict):
            self.fail(where or '(top level)', 'expected an object, got %s' % type(obj).__name__)
        for k in obj:
            if k in used:
                continue
            name = '%s.%s' % (where, k) if where else k
            if k in airsim:
                self.warn("'%s' is AirSim's but Lockstep does not use it (ignored)" % name)
            else:
                self.warn("unknown key '%s' (ignored, as AirSim does)" % name)

    def number(self, obj, key, where, default=None, lo=-math.inf, hi=math.inf, integer=False):
        if key not in obj:
            return default
        v = obj[key]
        name = '%s.%s' % (where, key) if where else key
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            self.fail(name, 'expected a number, got %r' % (v,))
        if integer and v != int(v):
            self.fail(name, 'expected an integer, got %r' % (v,))
        if not lo <= v <= hi:
            self.fail(name, '%r is out of range [%s, %s]' % (v, lo, hi))
        return int(v) if integer else float(v)

    def boolean(self, obj, key, where, default):
        if key not in obj:
            return default
        v = obj[key]
        if not isinstance(v, bool):
            self.fail('%s.%s' % (where, key), 'expected true or false, got %r' % (v,))
        return v

    def string(self, obj, key, where, default, choices=None):
        if key not in obj:
            return default
        v = obj[key]
        name = '%s.%s' % (where, key) if where else key
        if not isinstance(v, str):
            self.fail(name, 'expected a string, got %r' % (v,))
        if choices is not None and v not in choices:
            self.fail(name, '%r is not one of %s' % (v, ', '.join(repr(c) for c in choices if c)))
        return v

    def pose(self, obj, where, target, defaults=(None,) * 6):
        for key, d in zip(('X', 'Y', 'Z', 'Roll', 'Pitch', 'Yaw'), defaults):
            v = self.number(obj, key, where, d)
            setattr(target, key.lower(), v)

    def capture(self, obj, where, camera):
        if not isinstance(obj, list):
            self.fail(where, 'expected a list of capture settings, got %s' % type(obj).__name__)
        for i, c in enumerate(obj):
            w = '%s[%d]' % (where, i)
            self.keys(c, w, _CAPTURE_USED, _CAPTURE_AIRSIM)
            it = self.number(c, 'ImageType', w, 0, -1, 9, integer=True)
            base = camera.capture.get(it, CaptureSetting(it))
            camera.capture[it] = CaptureSetting(it, self.number(c, 'Width', w, base.width, 1, 16384, integer=True),
                                                self.number(c, 'Height', w, base.height, 1, 16384, integer=True),
                                                self.number(c, 'FOV_Degrees', w, base.fov_degrees, 0.001, 179.9))

    def camera(self, obj, where, name):
        self.keys(obj, where, _CAMERA_USED, _CAMERA_AIRSIM)
        cam = CameraSetting(name)
        self.pose(obj, where, cam)
        if 'CaptureSettings' in obj:
            self.capture(obj['CaptureSettings'], where + '.CaptureSettings', cam)
        return cam

    def sensor(self, obj, where, name):
        self.keys(obj, where, _SENSOR_USED, _SENSOR_AIRSIM)
        if 'SensorType' not in obj:
            self.fail(where + '.SensorType', 'missing (1 barometer, 2 IMU, 3 GPS, 4 magnetometer, 5 distance, 6 LiDAR)')
        t = self.number(obj, 'SensorType', where, None, integer=True)
        if t not in SENSOR_TYPES:
            self.fail(where + '.SensorType', '%r is not one of %s' % (t, sorted(SENSOR_TYPES)))
        s = SensorSetting(name, t)
        s.enabled = self.boolean(obj, 'Enabled', where, True)
        self.pose(obj, where, s)
        p = s.params
        if t == 6:
            p['channels'] = self.number(obj, 'NumberOfChannels', where, 16, 1, 256, integer=True)
            p['range'] = self.number(obj, 'Range', where, 100.0, 0.1, 10000)
            p['rotations_per_second'] = self.number(obj, 'RotationsPerSecond', where, 10.0, 0.001, 1000)
            p['points_per_second'] = self.number(obj, 'PointsPerSecond', where, 100000, 1, 1e8, integer=True)
            p['upper'] = self.number(obj, 'VerticalFOVUpper', where, -15.0, -90, 90)
            p['lower'] = self.number(obj, 'VerticalFOVLower', where, -45.0, -90, 90)
            p['h_start'] = self.number(obj, 'HorizontalFOVStart', where, 0.0, -360, 360)
            p['h_end'] = self.number(obj, 'HorizontalFOVEnd', where, 359.0, -360, 360)
            p['data_frame'] = self.string(obj, 'DataFrame', where, 'VehicleInertialFrame', LIDAR_FRAMES)
            if p['lower'] > p['upper']:
                self.fail(where + '.VerticalFOVLower', '%s is above VerticalFOVUpper %s' % (p['lower'], p['upper']))
        elif t == 5:
            p['min_distance'] = self.number(obj, 'MinDistance', where, 0.2, 0, 1e4)
            p['max_distance'] = self.number(obj, 'MaxDistance', where, 40.0, 0.01, 1e4)
        return s

    def recording(self, obj):
        self.keys(obj, 'Recording', _RECORDING_USED, set())
        rec = RecordingSetting()
        rec.record_on_move = self.boolean(obj, 'RecordOnMove', 'Recording', rec.record_on_move)
        rec.record_interval = self.number(obj, 'RecordInterval', 'Recording', rec.record_interval, 0, 3600)
        rec.folder = self.string(obj, 'Folder', 'Recording', rec.folder)
        rec.enabled = self.boolean(obj, 'Enabled', 'Recording', rec.enabled)
        if 'Cameras' in obj:
            cams = obj['Cameras']
            if not isinstance(cams, list):
                self.fail('Recording.Cameras', 'expected a list of cameras, got %s' % type(cams).__name__)
            rec.cameras = []
            for i, c in enumerate(cams):
                w = 'Recording.Cameras[%d]' % i
                self.keys(c, w, _RECORDING_CAMERA_USED, set())
                name = c.get('CameraName', '0')
                if isinstance(name, int) and not isinstance(name, bool):
                    name = str(name)  # AirSim takes a camera number too
                if not isinstance(name, str):
                    self.fail(w + '.CameraName', 'expected a string, got %r' % (name,))
                rec.cameras.append({'camera_name': name,
                                    'image_type': self.number(c, 'ImageType', w, 0, 0, 9, integer=True),
                                    'pixels_as_float': self.boolean(c, 'PixelsAsFloat', w, False),
                                    'vehicle_name': self.string(c, 'VehicleName', w, ''),
                                    'compress': self.boolean(c, 'Compress', w, True)})
        return rec

    def vehicle(self, obj, where, name, sim_mode):
        self.keys(obj, where, _VEHICLE_USED, _VEHICLE_AIRSIM)
        default_type = 'PhysXCar' if sim_mode == 'Car' else 'SimpleFlight'
        vtype = self.string(obj, 'VehicleType', where, default_type)
        if vtype.lower() not in VEHICLE_TYPES:
            self.fail(where + '.VehicleType', '%r is not one of SimpleFlight, PX4Multirotor, ArduCopter, PhysXCar, '
                      'ArduRover, ComputerVision' % vtype)
        v = VehicleSetting(name, vtype)
        self.pose(obj, where, v, (0.0,) * 6)
        v.yaw_given = 'Yaw' in obj
        v.auto_create = self.boolean(obj, 'AutoCreate', where, True)
        v.default_state = self.string(obj, 'DefaultVehicleState', where, 'Armed', ('Armed', 'Disarmed', 'Inactive', ''))
        v.allow_api_always = self.boolean(obj, 'AllowAPIAlways', where, True)
        self.boolean(obj, 'EnableTrace', where, False)
        cams = obj.get('Cameras', {})
        if not isinstance(cams, dict):
            self.fail(where + '.Cameras', 'expected an object of cameras by name')
        for cname, c in cams.items():
            v.cameras[cname] = self.camera(c, '%s.Cameras.%s' % (where, cname), cname)
        sensors = obj.get('Sensors', {})
        if not isinstance(sensors, dict):
            self.fail(where + '.Sensors', 'expected an object of sensors by name')
        for sname, s in sensors.items():
            v.sensors[sname] = self.sensor(s, '%s.Sensors.%s' % (where, sname), sname)
        return v


def parse(text, path='settings.json'):
    """The Settings of a settings.json text; raises SettingsError naming the key."""
    r = _Reader(path)
    try:
        obj = json.loads(text) if text.strip() else {}
    except ValueError as e:
        raise SettingsError('%s: not valid JSON: %s' % (path, e)) from None
    s = Settings()
    s.path, s.text = path, text
    r.keys(obj, '', _TOP_USED, _TOP_AIRSIM)
    s.sim_mode = r.string(obj, 'SimMode', '', '', SIM_MODES)
    s.clock_speed = r.number(obj, 'ClockSpeed', '', 1.0, 1e-3, 1e3)
    s.clock_type = r.string(obj, 'ClockType', '', '', ('', 'ScalableClock', 'SteppableClock'))
    s.view_mode = r.string(obj, 'ViewMode', '', '')
    if 'Recording' in obj:
        s.recording = r.recording(obj['Recording'])
    if 'Wind' in obj:
        r.keys(obj['Wind'], 'Wind', _VEC_USED, set())
        s.wind = tuple(r.number(obj['Wind'], k, 'Wind', 0.0, -200, 200) for k in ('X', 'Y', 'Z'))
    if 'OriginGeopoint' in obj:
        g = obj['OriginGeopoint']
        r.keys(g, 'OriginGeopoint', _GEO_USED, set())
        s.origin_geopoint = (r.number(g, 'Latitude', 'OriginGeopoint', 47.641468, -90, 90),
                             r.number(g, 'Longitude', 'OriginGeopoint', -122.140165, -180, 180),
                             r.number(g, 'Altitude', 'OriginGeopoint', 122.0, -1e4, 1e5))
    if 'CameraDefaults' in obj:
        s.camera_defaults = r.camera(obj['CameraDefaults'], 'CameraDefaults', 'CameraDefaults')
    vehicles = obj.get('Vehicles', {})
    if not isinstance(vehicles, dict):
        r.fail('Vehicles', 'expected an object of vehicles by name')
    for name, v in vehicles.items():
        s.vehicles[name] = r.vehicle(v, 'Vehicles.%s' % name, name, s.sim_mode)
    modes = {v.mode for v in s.vehicles.values()}
    if s.sim_mode == '' and len(modes) > 1:
        r.fail('SimMode', 'missing, and the vehicles are of several modes (%s)' % ', '.join(sorted(modes)))
    if s.sim_mode and modes and modes != {s.sim_mode}:
        bad = [v.name for v in s.vehicles.values() if v.mode != s.sim_mode]
        r.fail('Vehicles.%s.VehicleType' % bad[0], 'a %s vehicle in SimMode %r' % (s.vehicles[bad[0]].mode, s.sim_mode))
    if not s.sim_mode:
        s.sim_mode = modes.pop() if modes else 'Multirotor'
    s.warnings = r.warnings
    return s


# What AirSim writes to a missing settings.json at start (and getSettingsString then returns).
DEFAULT_TEXT = ('{\n  "SeeDocsAt": "https://github.com/Microsoft/AirSim/blob/main/docs/settings.md",\n'
                '  "SettingsVersion": 1.2\n}')


def load(path=None):
    """The settings at `path` (default settings_path()); AirSim's defaults when there is no file
    (its text AirSim's default file's; the file is not written)."""
    path = path or settings_path()
    if not os.path.exists(path):
        s = Settings()
        s.sim_mode = 'Multirotor'
        s.text = DEFAULT_TEXT
        return s
    with open(path, encoding='utf-8-sig') as f:
        text = f.read()
    return parse(text, path)
