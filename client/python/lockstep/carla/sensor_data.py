"""carla.Image, LidarMeasurement, IMUMeasurement, ... over lockstep sensor samples.
Images and point clouds are numpy views of the received sample (no copy)."""
import math
import os
import struct

import numpy as np

from .constants import SEMANTIC_PALETTE
from .geometry import Location, Vector3D, from_enu_vector, from_wire_pose

__all__ = ['ColorConverter', 'SensorData', 'Image', 'LidarMeasurement', 'LidarDetection', 'SemanticLidarMeasurement',
           'SemanticLidarDetection', 'RadarMeasurement', 'RadarDetection', 'IMUMeasurement', 'GnssMeasurement',
           'CollisionEvent', 'LaneInvasionEvent', 'ObstacleDetectionEvent', 'make_sensor_data']


class ColorConverter:
    Raw = 0
    Depth = 1
    LogarithmicDepth = 2
    CityScapesPalette = 3


_PALETTE = np.zeros((256, 3), dtype=np.uint8)
for _e in SEMANTIC_PALETTE:
    _PALETTE[_e['id']] = _e['rgb']


class SensorData:
    def __init__(self, sample, world):
        self._sample = sample
        self._world = world
        self._fields = sample.fields()
        self.frame = sample.frame
        self.frame_number = sample.frame
        self.timestamp = sample.sim_time
        self.sensor_id = sample.sensor
        t = self._fields.get('transform')
        self.transform = from_wire_pose(t) if t is not None else None

    def __repr__(self):
        return '%s(frame=%d, timestamp=%f)' % (type(self).__name__, self.frame, self.timestamp)


class Image(SensorData):
    def __init__(self, sample, world):
        super().__init__(sample, world)
        self.width = self._fields['width']
        self.height = self._fields['height']
        self.fov = math.degrees(self._fields['fov'])
        self.encoding = self._fields['encoding']

    @property
    def raw_data(self):
        """BGRA bytes (CARLA's layout) as a read-only numpy uint8 buffer, no copy."""
        return self._sample.raw()

    def to_numpy(self):
        """(height, width, 4) uint8 BGRA, or (height, width) float32 metres for depth_f32; no copy."""
        return self._sample.array()

    def _converted(self, color_converter):
        a = self.to_numpy()
        if color_converter in (None, ColorConverter.Raw):
            return a
        if self.encoding == 'depth_f32':
            metres = a
        elif self.encoding == 'depth_carla_bgra8':
            b, g, r = a[..., 0].astype(np.float64), a[..., 1].astype(np.float64), a[..., 2].astype(np.float64)
            metres = 1000.0 * (r + g * 256 + b * 65536) / (256 ** 3 - 1)
        else:
            metres = None
        out = np.empty((self.height, self.width, 4), dtype=np.uint8)
        out[..., 3] = 255
        if color_converter == ColorConverter.CityScapesPalette:
            rgb = _PALETTE[a[..., 2]]
            out[..., 0], out[..., 1], out[..., 2] = rgb[..., 2], rgb[..., 1], rgb[..., 0]
            return out
        if metres is None:
            raise ValueError('ColorConverter %d needs a depth image, this one is %s' % (color_converter, self.encoding))
        n = np.clip(metres / 1000.0, 0, 1)
        if color_converter == ColorConverter.LogarithmicDepth:
            n = np.clip(1.0 + np.log(np.maximum(n, 1e-12)) / 5.70378, 0, 1)
        g = (n * 255).astype(np.uint8)
        out[..., 0] = out[..., 1] = out[..., 2] = g
        return out

    def convert(self, color_converter):
        self._converted_cache = self._converted(color_converter)

    def save_to_disk(self, path, color_converter=ColorConverter.Raw):
        """Writes a PNG (CARLA's default format); %d / %06d in the path take the frame."""
        if '%' in path:
            path = path % self.frame
        if not os.path.splitext(path)[1]:
            path += '.png'
        a = self._converted(color_converter)
        if a.ndim == 2:
            a = np.clip(a, 0, 1000).astype(np.float32)
            a = (a / max(float(a.max()), 1e-6) * 255).astype(np.uint8)
            rgb = np.repeat(a[..., None], 3, axis=2)
        else:
            rgb = a[..., [2, 1, 0]]
        os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
        write_png(path, np.ascontiguousarray(rgb))
        return path

    def __len__(self):
        return self.width * self.height

    def __iter__(self):
        from .geometry import Color
        a = self.to_numpy().reshape(-1, 4)
        return (Color(int(p[2]), int(p[1]), int(p[0]), int(p[3])) for p in a)


def write_png(path, rgb):
    """Minimal PNG writer (zlib from the standard library): rgb is (h, w, 3) uint8."""
    import zlib
    h, w = rgb.shape[:2]
    raw = np.concatenate([np.zeros((h, 1), dtype=np.uint8), rgb.reshape(h, w * 3)], axis=1).tobytes()

    def chunk(tag, data):
        c = struct.pack('>I', len(data)) + tag + data
        return c + struct.pack('>I', zlib.crc32(tag + data) & 0xffffffff)

    with open(path, 'wb') as f:
        f.write(b'\x89PNG\r\n\x1a\n')
        f.write(chunk(b'IHDR', struct.pack('>IIBBBBB', w, h, 8, 2, 0, 0, 0)))
        f.write(chunk(b'IDAT', zlib.compress(raw, 3)))
        f.write(chunk(b'IEND', b''))


class LidarDetection:
    def __init__(self, x, y, z, intensity):
        self.point = Location(x, y, z)
        self.intensity = intensity

    def __repr__(self):
        return 'LidarDetection(x=%f, y=%f, z=%f, intensity=%f)' % (self.point.x, self.point.y, self.point.z, self.intensity)


class SemanticLidarDetection:
    def __init__(self, row):
        self.point = Location(float(row['x']), float(row['y']), float(row['z']))
        self.cos_inc_angle = float(row['CosAngle'])
        self.object_idx = int(row['ObjIdx'])
        self.object_tag = int(row['ObjTag'])


class LidarMeasurement(SensorData):
    """Points in the sensor frame; Lockstep's sensor frame is FLU, so y is negated here to
    give CARLA's left-handed sensor frame."""

    def __init__(self, sample, world):
        super().__init__(sample, world)
        self.channels = len(self._fields['channels'])
        self._per_channel = list(self._fields['channels'])
        self.horizontal_angle = 0.0

    @property
    def raw_data(self):
        return self._sample.raw()

    def to_numpy(self):
        """(N, 4) float32 x, y, z, intensity in Lockstep's sensor frame (FLU), no copy."""
        return self._sample.array()

    def get_point_count(self, channel):
        return self._per_channel[channel]

    def __len__(self):
        return self._fields['point_count']

    def __iter__(self):
        for x, y, z, i in self.to_numpy():
            yield LidarDetection(float(x), -float(y), float(z), float(i))

    def save_to_disk(self, path):
        if '%' in path:
            path = path % self.frame
        if not os.path.splitext(path)[1]:
            path += '.ply'
        pts = np.array(self.to_numpy(), dtype=np.float32).reshape(-1, 4)
        pts[:, 1] *= -1
        os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
        with open(path, 'wb') as f:
            f.write(('ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float32 x\nproperty float32 y\n'
                     'property float32 z\nproperty float32 I\nend_header\n' % len(pts)).encode())
            f.write(pts.astype('<f4').tobytes())
        return path


class SemanticLidarMeasurement(LidarMeasurement):
    def __iter__(self):
        for row in self.to_numpy():
            yield SemanticLidarDetection(row)


class RadarDetection:
    def __init__(self, velocity, azimuth, altitude, depth):
        self.velocity, self.azimuth, self.altitude, self.depth = velocity, azimuth, altitude, depth


class RadarMeasurement(SensorData):
    def __init__(self, sample, world):
        super().__init__(sample, world)
        self._dets = [RadarDetection(*d) for d in self._fields['detections']]
        self.raw_data = np.array(self._fields['detections'], dtype=np.float32).reshape(-1, 4)

    def get_detection_count(self):
        return len(self._dets)

    def __len__(self):
        return len(self._dets)

    def __iter__(self):
        return iter(self._dets)


class IMUMeasurement(SensorData):
    def __init__(self, sample, world):
        super().__init__(sample, world)
        self.accelerometer = from_enu_vector(self._fields['accelerometer'])
        g = self._fields['gyroscope']
        self.gyroscope = Vector3D(g[0], -g[1], -g[2])  # FLU -> CARLA's left-handed body rates
        self.compass = self._fields['compass']


class GnssMeasurement(SensorData):
    def __init__(self, sample, world):
        super().__init__(sample, world)
        self.latitude = self._fields['latitude']
        self.longitude = self._fields['longitude']
        self.altitude = self._fields['altitude']


class CollisionEvent(SensorData):
    def __init__(self, sample, world):
        super().__init__(sample, world)
        self.actor = world.get_actor(self._fields['actor']) if world else None
        other = self._fields['other_actor']
        self.other_actor = world.get_actor(other) if (world and other) else None
        self.normal_impulse = from_enu_vector(self._fields['normal_impulse'])


class LaneInvasionEvent(SensorData):
    def __init__(self, sample, world):
        super().__init__(sample, world)
        from .map import LaneMarking
        self.actor = world.get_actor(self._fields['actor']) if world else None
        self.crossed_lane_markings = [LaneMarking.from_wire(*c) for c in self._fields['crossed']]


class ObstacleDetectionEvent(SensorData):
    def __init__(self, sample, world):
        super().__init__(sample, world)
        self.actor = world.get_actor(self._fields['actor']) if world else None
        other = self._fields['other_actor']
        self.other_actor = world.get_actor(other) if (world and other) else None
        self.distance = self._fields['distance']


_CLASSES = {'image': Image, 'imu': IMUMeasurement, 'gnss': GnssMeasurement, 'radar': RadarMeasurement,
            'collision': CollisionEvent, 'lane_invasion': LaneInvasionEvent, 'obstacle': ObstacleDetectionEvent}


def make_sensor_data(sample, world):
    t = sample.type
    if t == 'point_cloud':
        return (SemanticLidarMeasurement if sample.fields()['semantic'] else LidarMeasurement)(sample, world)
    cls = _CLASSES.get(t)
    if cls is None:
        data = SensorData(sample, world)
        data.__dict__.update(data._fields)
        return data
    return cls(sample, world)
