"""carla.Image, LidarMeasurement, IMUMeasurement, ... over lockstep sensor samples, in
CARLA's data conventions (docs/compatibility.md, *Data conventions*).

The wire is Lockstep's: world ENU, sensor frames FLU (x forward, y left, z up). CARLA's
sensor frames are Unreal's (x forward, y right, z up, left-handed), so each class converts
where CARLA's data class is made: point clouds and accelerations have y negated, angles
about z (radar azimuth) change sign, and angular velocities, pseudovectors, become
(-x, y, -z). raw_data and iteration always agree. Camera images need no conversion."""
import math
import os
import re
import struct
import zlib

import numpy as np

from .constants import SEMANTIC_PALETTE
from .geometry import Color, Location, Vector3D, from_enu_vector, from_wire_pose

__all__ = ['ColorConverter', 'SensorData', 'Image', 'OpticalFlowImage', 'OpticalFlowPixel', 'DVSEvent', 'DVSEventArray',
           'LidarMeasurement', 'LidarDetection', 'SemanticLidarMeasurement', 'SemanticLidarDetection',
           'RadarMeasurement', 'RadarDetection', 'IMUMeasurement', 'GnssMeasurement', 'CollisionEvent',
           'LaneInvasionEvent', 'ObstacleDetectionEvent', 'GBufferTextureID', 'CAMEvent', 'CAMMessage', 'CustomV2XEvent',
           'CustomV2XData', 'make_sensor_data']


class ColorConverter:
    Raw = 0
    Depth = 1
    LogarithmicDepth = 2
    CityScapesPalette = 3


class GBufferTextureID:
    """CARLA's G-buffer texture ids (Sensor.listen_to_gbuffer)."""
    SceneColor = 0
    SceneDepth = 1
    SceneStencil = 2
    GBufferA = 3
    GBufferB = 4
    GBufferC = 5
    GBufferD = 6
    GBufferE = 7
    GBufferF = 8
    Velocity = 9
    SSAO = 10
    CustomDepth = 11
    CustomStencil = 12


# CARLA's CITYSCAPES_PALETTE_MAP (LibCarla/source/carla/image/CityScapesPalette.h, 0.9.14+),
# RGB per semantic tag; a tag past the end wraps around (tag % size), as CARLA's GetColor.
_PALETTE = np.zeros((len(SEMANTIC_PALETTE), 3), dtype=np.uint8)
for _e in SEMANTIC_PALETTE:
    _PALETTE[_e['id']] = _e['rgb']
# ATagger::GetTagAsString, for the "static.<tag>" type id of unregistered geometry.
_TAGGER_NAMES = ['None', 'Roads', 'Sidewalks', 'Buildings', 'Walls', 'Fences', 'Poles', 'TrafficLight', 'TrafficSigns',
                 'Vegetation', 'Terrain', 'Sky', 'Pedestrians', 'Rider', 'Car', 'Truck', 'Bus', 'Train', 'Motorcycle',
                 'Bicycle', 'Static', 'Dynamic', 'Other', 'Water', 'RoadLines', 'Ground', 'Bridge', 'RailTrack',
                 'GuardRail']
_F255 = np.float32(255.0)
_HALF = np.float32(0.5)
_DEPTH_SCALE = np.float32(256 * 256 * 256 - 1)
_LOG_DEPTH = np.float32(5.70378)


def _to_u8(x):
    """boost::gil's float32 -> uint8 channel conversion: uint8(x * 255 + 0.5)."""
    return (x.astype(np.float32) * _F255 + _HALF).astype(np.uint8)


def _gray_to_bgra(g):
    out = np.empty(g.shape + (4,), dtype=np.uint8)
    out[..., 0] = out[..., 1] = out[..., 2] = g
    out[..., 3] = 255
    return out


def _normalized_depth(bgra):
    """CARLA's ColorConverter::Depth: (R + G 256 + B 65536) / (256^3 - 1), in float32."""
    r = bgra[..., 2].astype(np.int64)
    g = bgra[..., 1].astype(np.int64)
    b = bgra[..., 0].astype(np.int64)
    return (r + g * 256 + b * 65536).astype(np.float32) / _DEPTH_SCALE


def _log_linear(normalized):
    """CARLA's ColorConverter::LogarithmicLinear: clamp(1 + log(x) / 5.70378, 0, 1)."""
    with np.errstate(divide='ignore', invalid='ignore'):
        v = np.float32(1.0) + np.log(normalized.astype(np.float32)) / _LOG_DEPTH
    return np.nan_to_num(np.clip(v, 0.0, 1.0), nan=0.0).astype(np.float32)


def _cityscapes(bgra):
    rgb = _PALETTE[bgra[..., 2].astype(np.intp) % len(_PALETTE)]
    return rgb


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
        if self.transform is None and world is not None:
            # Samples without a pose on the wire (IMU, GNSS, events): the sensor's transform
            # of the frame, as CARLA's SensorData.transform.
            actor = world.get_actor(sample.sensor)
            self.transform = actor.get_transform() if actor is not None else None

    def __repr__(self):
        return '%s(frame=%d, timestamp=%f)' % (type(self).__name__, self.frame, self.timestamp)


def _frame_path(path, frame):
    """save_to_disk paths: a printf-style integer pattern (%d, %06d) takes the frame."""
    return path % frame if re.search(r'%0?\d*d', path) else path


def _with_extension(path, ext):
    """CARLA's FileSystem::ValidateFilePath: the default extension when there is none, and
    the parent folders."""
    if not os.path.splitext(path)[1]:
        path += ext
    parent = os.path.dirname(os.path.abspath(path))
    os.makedirs(parent, exist_ok=True)
    return path


class Image(SensorData):
    """BGRA8 pixels (CARLA's layout). convert() rewrites them in place, as CARLA's."""

    def __init__(self, sample, world):
        super().__init__(sample, world)
        self.width = self._fields['width']
        self.height = self._fields['height']
        self.fov = math.degrees(self._fields['fov'])
        self.encoding = self._fields['encoding']
        self._pixels = None  # this image's own pixels once converted or written

    @property
    def raw_data(self):
        """BGRA bytes (CARLA's layout) as a read-only numpy uint8 buffer."""
        if self._pixels is not None:
            v = self._pixels.reshape(-1).view()
            v.setflags(write=False)
            return v
        return self._sample.raw()

    def to_numpy(self):
        """(height, width, 4) uint8 BGRA of the current pixels (no copy before a convert), or
        (height, width) float32 metres for a depth_f32 image."""
        if self._pixels is not None:
            v = self._pixels.view()
            v.setflags(write=False)
            return v
        return self._sample.array()

    def _bgra(self):
        a = self.to_numpy()
        if a.ndim == 2 and a.dtype == np.uint8:  # gray8: gray BGRA
            return _gray_to_bgra(a)
        if a.ndim == 2:  # depth_f32 (metres): CARLA's 24-bit encoding of metres / 1000
            n = np.clip(np.asarray(a, dtype=np.float64) / 1000.0, 0.0, 1.0)
            v = np.round(n * (256 ** 3 - 1)).astype(np.int64)
            out = np.empty(a.shape + (4,), dtype=np.uint8)
            out[..., 2] = v & 255
            out[..., 1] = (v >> 8) & 255
            out[..., 0] = (v >> 16) & 255
            out[..., 3] = 255
            return out
        return a

    def _converted(self, color_converter):
        """The BGRA pixels CARLA's ConvertInPlace writes for color_converter."""
        cc = int(color_converter)
        a = self._bgra()
        if cc == ColorConverter.Raw:
            return a
        if cc == ColorConverter.Depth:
            return _gray_to_bgra(_to_u8(_normalized_depth(a)))
        if cc == ColorConverter.LogarithmicDepth:
            return _gray_to_bgra(_to_u8(_log_linear(_normalized_depth(a))))
        if cc == ColorConverter.CityScapesPalette:
            rgb = _cityscapes(a)
            out = np.empty(a.shape, dtype=np.uint8)
            out[..., 0], out[..., 1], out[..., 2], out[..., 3] = rgb[..., 2], rgb[..., 1], rgb[..., 0], 255
            return out
        raise ValueError('invalid color converter: %r' % (color_converter,))

    def convert(self, color_converter):
        """Converts the image in place (raw_data, iteration and save_to_disk see the result),
        with CARLA's formulas: Depth and LogarithmicDepth decode R + G 256 + B 65536 and write
        gray; CityScapesPalette colours the red channel's tag."""
        if int(color_converter) == ColorConverter.Raw:
            return
        self._pixels = np.ascontiguousarray(self._converted(color_converter))

    def save_to_disk(self, path, color_converter=ColorConverter.Raw):
        """Writes a PNG as CARLA's: RGBA (Raw, CityScapesPalette) or 8-bit gray (Depth,
        LogarithmicDepth), '.png' added when the path has no extension. Returns the path."""
        cc = int(color_converter)
        path = _with_extension(_frame_path(path, self.frame), '.png')
        a = self._bgra()
        if cc == ColorConverter.Raw:
            write_png(path, np.ascontiguousarray(a[..., [2, 1, 0, 3]]))
        elif cc == ColorConverter.Depth:
            write_png(path, _to_u8(_normalized_depth(a)))
        elif cc == ColorConverter.LogarithmicDepth:
            write_png(path, _to_u8(_log_linear(_normalized_depth(a))))
        elif cc == ColorConverter.CityScapesPalette:
            rgb = _cityscapes(a)
            rgba = np.empty(a.shape, dtype=np.uint8)
            rgba[..., :3] = rgb
            rgba[..., 3] = 255
            write_png(path, rgba)
        else:
            raise ValueError('invalid color converter: %r' % (color_converter,))
        return path

    def __len__(self):
        return self.width * self.height

    def __iter__(self):
        a = self._bgra().reshape(-1, 4)
        return (Color(int(p[2]), int(p[1]), int(p[0]), int(p[3])) for p in a)

    def __getitem__(self, pos):
        p = self._bgra().reshape(-1, 4)[pos]
        return Color(int(p[2]), int(p[1]), int(p[0]), int(p[3]))

    def __setitem__(self, pos, color):
        if self._pixels is None:
            self._pixels = np.array(self._bgra(), dtype=np.uint8)
        self._pixels.reshape(-1, 4)[pos] = (color.b, color.g, color.r, color.a)

    def __str__(self):
        return 'Image(frame=%d, timestamp=%f, size=%dx%d)' % (self.frame, self.timestamp, self.width, self.height)


def write_png(path, pixels):
    """Minimal PNG writer (zlib from the standard library): pixels is (h, w) gray, (h, w, 3)
    RGB or (h, w, 4) RGBA uint8."""
    h, w = pixels.shape[:2]
    channels = 1 if pixels.ndim == 2 else pixels.shape[2]
    color_type = {1: 0, 3: 2, 4: 6}[channels]
    rows = np.ascontiguousarray(pixels, dtype=np.uint8).reshape(h, w * channels)
    raw = np.concatenate([np.zeros((h, 1), dtype=np.uint8), rows], axis=1).tobytes()

    def chunk(tag, data):
        c = struct.pack('>I', len(data)) + tag + data
        return c + struct.pack('>I', zlib.crc32(tag + data) & 0xffffffff)

    with open(path, 'wb') as f:
        f.write(b'\x89PNG\r\n\x1a\n')
        f.write(chunk(b'IHDR', struct.pack('>IIBBBBB', w, h, 8, color_type, 0, 0, 0)))
        f.write(chunk(b'IDAT', zlib.compress(raw, 3)))
        f.write(chunk(b'IEND', b''))


# --- optical flow and DVS -----------------------------------------------------------------

class OpticalFlowPixel:
    def __init__(self, x=0.0, y=0.0):
        self.x, self.y = float(x), float(y)

    def __eq__(self, o):
        return isinstance(o, OpticalFlowPixel) and (self.x, self.y) == (o.x, o.y)

    def __repr__(self):
        return 'OpticalFlowPixel(x=%f, y=%f)' % (self.x, self.y)


class _ColorCodedFlow:
    """CARLA's FakeImage: width, height, fov, raw_data (BGRA, alpha 0) and byte indexing."""

    def __init__(self, bgra, fov):
        self._bytes = bgra.reshape(-1)
        self._bytes.setflags(write=False)
        self.height, self.width = bgra.shape[:2]
        self.fov = fov

    @property
    def raw_data(self):
        return self._bytes

    def __len__(self):
        return len(self._bytes)

    def __getitem__(self, i):
        return int(self._bytes[i])

    def __iter__(self):
        return (int(b) for b in self._bytes)


def color_coded_flow(flow):
    """CARLA's ColorCodedFlow (PythonAPI SensorData.cpp), float32 as CARLA computes it:
    hue from the flow's angle + 180 deg, value from a log of its norm, saturation 1."""
    f32 = np.float32
    vx = flow[..., 0].astype(f32)
    vy = flow[..., 1].astype(f32)
    rad2ang = f32(360.0) / (f32(2.0) * f32(3.1415))
    with np.errstate(invalid='ignore'):
        angle = f32(180.0) + np.arctan2(vy, vx) * rad2ang
        angle = np.where(angle < 0, f32(360.0) + angle, angle).astype(f32)
        angle = np.fmod(angle, f32(360.0))
        norm = np.sqrt(vx * vx + vy * vy)
        a = f32(1.0) / np.log(f32(0.1) + f32(0.999))
        intensity = np.clip(a * np.log(norm + f32(0.999)), f32(0.0), f32(1.0)).astype(f32)
        h60 = angle * (f32(1.0) / f32(60.0))
        c = intensity
        x = c * (f32(1.0) - np.abs(np.fmod(h60, f32(2.0)) - f32(1.0)))
        m = intensity - c
        case = np.where(np.isfinite(h60), h60, -1).astype(np.int64)
    zero = np.zeros_like(c)
    one = np.ones_like(c)
    r = np.select([case == 0, case == 1, case == 2, case == 3, case == 4, case == 5], [c, x, zero, zero, x, c], one)
    g = np.select([case == 0, case == 1, case == 2, case == 3, case == 4, case == 5], [x, c, c, x, zero, zero], one)
    b = np.select([case == 0, case == 1, case == 2, case == 3, case == 4, case == 5], [zero, zero, x, c, c, x], one)
    out = np.zeros(flow.shape[:2] + (4,), dtype=np.uint8)
    with np.errstate(invalid='ignore'):
        out[..., 0] = ((b + m) * _F255).astype(np.uint8)
        out[..., 1] = ((g + m) * _F255).astype(np.uint8)
        out[..., 2] = ((r + m) * _F255).astype(np.uint8)
    return out


class OpticalFlowImage(SensorData):
    """sensor.camera.optical_flow: two float32 per pixel (x right, y down; [-2, 2] is the
    image size), CARLA's OpticalFlowPixel layout."""

    def __init__(self, sample, world):
        super().__init__(sample, world)
        self.width = self._fields['width']
        self.height = self._fields['height']
        self.fov = math.degrees(self._fields['fov'])

    @property
    def raw_data(self):
        return self._sample.raw()

    def to_numpy(self):
        """(height, width, 2) float32, no copy."""
        return self._sample.array()

    def get_color_coded_flow(self):
        return _ColorCodedFlow(color_coded_flow(self.to_numpy()), self.fov)

    def __len__(self):
        return self.width * self.height

    def __getitem__(self, pos):
        p = self.to_numpy().reshape(-1, 2)[pos]
        return OpticalFlowPixel(p[0], p[1])

    def __iter__(self):
        return (OpticalFlowPixel(p[0], p[1]) for p in self.to_numpy().reshape(-1, 2))

    def __str__(self):
        return 'OpticalFlowImage(frame=%d, timestamp=%f, size=%dx%d)' % (self.frame, self.timestamp, self.width,
                                                                         self.height)


# CARLA's DVSEvent, #pragma pack(1): x, y uint16, t int64 (ns), pol bool: 13 bytes.
DVS_EVENT_DTYPE = np.dtype([('x', '<u2'), ('y', '<u2'), ('t', '<i8'), ('pol', '?')])


class DVSEvent:
    def __init__(self, x=0, y=0, t=0, pol=False):
        self.x, self.y, self.t, self.pol = int(x), int(y), int(t), bool(pol)

    def __repr__(self):
        return 'Event(x=%d, y=%d, t=%d, pol=%d)' % (self.x, self.y, self.t, self.pol)


class DVSEventArray(SensorData):
    """sensor.camera.dvs: CARLA's 13-byte packed events in raw_data; width, height and fov
    of the camera."""

    def __init__(self, sample, world):
        super().__init__(sample, world)
        self.fov = math.degrees(self._fields['fov'])
        self.width, self.height = _camera_size(world, sample.sensor)
        wire = self._sample.array()  # x, y, pol, t in 16-byte records
        events = np.empty(len(wire), dtype=DVS_EVENT_DTYPE)
        for k in ('x', 'y', 't', 'pol'):
            events[k] = wire[k]
        events.setflags(write=False)
        self._events = events

    @property
    def raw_data(self):
        v = self._events.view(np.uint8).reshape(-1)
        v.setflags(write=False)
        return v

    def __len__(self):
        return len(self._events)

    def __getitem__(self, pos):
        e = self._events[pos]
        return DVSEvent(e['x'], e['y'], e['t'], e['pol'])

    def __iter__(self):
        return (DVSEvent(e['x'], e['y'], e['t'], e['pol']) for e in self._events)

    def to_image(self):
        """One carla.Color per pixel (row major): blue 255 where the last event is positive,
        red 255 where negative, the rest 0 (alpha 0), as CARLA's ToImage."""
        img = np.zeros((self.height * self.width, 4), dtype=np.uint8)  # b, g, r, a
        idx = self._events['y'].astype(np.int64) * self.width + self._events['x'].astype(np.int64)
        for i, pol in zip(idx, self._events['pol']):
            img[i, 0 if pol else 2] = 255
        return [Color(int(p[2]), int(p[1]), int(p[0]), int(p[3])) for p in img]

    def to_array(self):
        e = self._events
        return [[int(x), int(y), int(t), 2 * int(p) - 1] for x, y, t, p in zip(e['x'], e['y'], e['t'], e['pol'])]

    def to_array_x(self):
        return [int(v) for v in self._events['x']]

    def to_array_y(self):
        return [int(v) for v in self._events['y']]

    def to_array_t(self):
        return [int(v) for v in self._events['t']]

    def to_array_pol(self):
        return [2 * int(v) - 1 for v in self._events['pol']]

    def __str__(self):
        return 'EventArray(frame=%d, timestamp=%f, dimensions=%dx%d, number_of_events=%d)' % (
            self.frame, self.timestamp, self.width, self.height, len(self))


def _camera_size(world, sensor):
    """The DVS camera's image size: the wire carries the event count as its width."""
    actor = world.get_actor(sensor) if world else None
    attrs = dict(getattr(actor, 'attributes', {}) or {})
    if 'image_size_x' not in attrs or 'image_size_y' not in attrs:
        try:
            bp = world.get_blueprint_library().find(actor.type_id if actor else 'sensor.camera.dvs')
            for k in ('image_size_x', 'image_size_y'):
                attrs.setdefault(k, bp.get_attribute(k).as_int())
        except Exception:  # no blueprint library at hand: CARLA's defaults
            attrs.setdefault('image_size_x', 800)
            attrs.setdefault('image_size_y', 600)
    return int(attrs['image_size_x']), int(attrs['image_size_y'])


# --- LiDAR and radar ---------------------------------------------------------------------

class LidarDetection:
    def __init__(self, x=0.0, y=0.0, z=0.0, intensity=0.0):
        self.point = Location(x, y, z)
        self.intensity = float(intensity)

    def __repr__(self):
        return 'LidarDetection(x=%f, y=%f, z=%f, intensity=%f)' % (self.point.x, self.point.y, self.point.z, self.intensity)


class SemanticLidarDetection:
    def __init__(self, x=0.0, y=0.0, z=0.0, cos_inc_angle=0.0, object_idx=0, object_tag=0):
        self.point = Location(x, y, z)
        self.cos_inc_angle = float(cos_inc_angle)
        self.object_idx = int(object_idx)
        self.object_tag = int(object_tag)

    def __repr__(self):
        return ('SemanticLidarDetection(x=%f, y=%f, z=%f, cos_inc_angle=%f, object_idx=%d, object_tag=%d)'
                % (self.point.x, self.point.y, self.point.z, self.cos_inc_angle, self.object_idx, self.object_tag))


class LidarMeasurement(SensorData):
    """Points in CARLA's sensor frame (x forward, y right, z up; m): the wire's FLU points
    with y negated, in raw_data (x, y, z, intensity float32 per point) and iteration alike."""

    _PLY_HEADER = 'property float32 x\nproperty float32 y\nproperty float32 z\nproperty float32 I'

    def __init__(self, sample, world):
        super().__init__(sample, world)
        self.channels = len(self._fields['channels'])
        self._per_channel = list(self._fields['channels'])
        self.horizontal_angle = 0.0
        self._points = None

    def _carla_points(self):
        if self._points is None:
            a = np.array(self._sample.array())  # a copy: the wire's view is read-only
            if a.dtype.names:
                a['y'] = -a['y']
            else:
                a[:, 1] = -a[:, 1]
            a.setflags(write=False)
            self._points = a
        return self._points

    @property
    def raw_data(self):
        v = self._carla_points().view(np.uint8).reshape(-1)
        v.setflags(write=False)
        return v

    def to_numpy(self):
        """(N, 4) float32 x, y, z, intensity in CARLA's sensor frame (y right), as raw_data."""
        return self._carla_points()

    def get_point_count(self, channel):
        return self._per_channel[channel]

    def __len__(self):
        return self._fields['point_count']

    def _detection(self, row):
        return LidarDetection(float(row[0]), float(row[1]), float(row[2]), float(row[3]))

    def __getitem__(self, pos):
        return self._detection(self._carla_points()[pos])

    def __iter__(self):
        for row in self._carla_points():
            yield self._detection(row)

    def _ply_line(self, row):
        return '%.4f %.4f %.4f %.4f' % (row[0], row[1], row[2], row[3])

    def save_to_disk(self, path):
        """CARLA's PointCloudIO: an ASCII PLY, 4 decimals, '.ply' added when the path has no
        extension. Returns the path."""
        path = _with_extension(_frame_path(path, self.frame), '.ply')
        pts = self._carla_points()
        with open(path, 'w') as f:
            f.write('ply\nformat ascii 1.0\nelement vertex %d\n%s\nend_header\n' % (len(pts), self._PLY_HEADER))
            for row in pts:
                f.write(self._ply_line(row) + '\n')
        return path

    def __str__(self):
        return '%s(frame=%d, timestamp=%f, number_of_points=%d)' % (type(self).__name__, self.frame, self.timestamp,
                                                                    len(self))


class SemanticLidarMeasurement(LidarMeasurement):
    """CARLA's 24-byte points: x, y, z (y right), cos_inc_angle float32; object_idx (the
    actor id, 0 for the static scene), object_tag (CARLA's semantic tag) uint32."""

    _PLY_HEADER = ('property float32 x\nproperty float32 y\nproperty float32 z\nproperty float32 CosAngle\n'
                   'property uint32 ObjIdx\nproperty uint32 ObjTag')

    def to_numpy(self):
        """(N,) structured x, y, z, CosAngle, ObjIdx, ObjTag in CARLA's frame, as raw_data."""
        return self._carla_points()

    def _detection(self, row):
        return SemanticLidarDetection(float(row['x']), float(row['y']), float(row['z']), float(row['CosAngle']),
                                      int(row['ObjIdx']), int(row['ObjTag']))

    def _ply_line(self, row):
        return '%.4f %.4f %.4f %.4f %d %d' % (row['x'], row['y'], row['z'], row['CosAngle'], row['ObjIdx'], row['ObjTag'])


class RadarDetection:
    """velocity m/s (towards the sensor negative), azimuth rad (positive to the right, CARLA's
    FMath::GetAzimuthAndElevation), altitude rad (positive up), depth m."""

    def __init__(self, velocity=0.0, azimuth=0.0, altitude=0.0, depth=0.0):
        self.velocity, self.azimuth, self.altitude, self.depth = float(velocity), float(azimuth), float(altitude), float(depth)

    def __repr__(self):
        return 'RadarDetection(velocity=%f, azimuth=%f, altitude=%f, depth=%f)' % (self.velocity, self.azimuth,
                                                                                   self.altitude, self.depth)


class RadarMeasurement(SensorData):
    def __init__(self, sample, world):
        super().__init__(sample, world)
        d = np.array(self._fields['detections'], dtype=np.float32).reshape(-1, 4)
        d[:, 1] = -d[:, 1]  # FLU azimuth (left positive) -> CARLA's (right positive)
        d.setflags(write=False)
        self._det = d
        self._dets = [RadarDetection(*row) for row in d.tolist()]

    @property
    def raw_data(self):
        """velocity, azimuth, altitude, depth float32 per detection (CARLA's RadarDetection)."""
        v = self._det.view(np.uint8).reshape(-1)
        v.setflags(write=False)
        return v

    def get_detection_count(self):
        return len(self._dets)

    def __len__(self):
        return len(self._dets)

    def __getitem__(self, pos):
        return self._dets[pos]

    def __iter__(self):
        return iter(self._dets)

    def __str__(self):
        return 'RadarMeasurement(frame=%d, timestamp=%f, point_count=%d)' % (self.frame, self.timestamp, len(self))


# --- inertial and navigation -------------------------------------------------------------

def flu_rates_to_carla(w):
    """An angular velocity (rad/s) in an FLU or ENU frame -> CARLA's (Unreal's) frame: a
    pseudovector under the y mirror is (-x, y, -z); CARLA's yaw rate is positive turning right."""
    return (-w[0], w[1], -w[2])


class IMUMeasurement(SensorData):
    """accelerometer m/s^2 and gyroscope rad/s in CARLA's sensor frame; compass rad from north
    (-y in CARLA's world), clockwise."""

    def __init__(self, sample, world):
        super().__init__(sample, world)
        self.accelerometer = from_enu_vector(self._fields['accelerometer'])
        self.gyroscope = Vector3D(*flu_rates_to_carla(self._fields['gyroscope']))
        self.compass = self._fields['compass']

    def __str__(self):
        return 'IMUMeasurement(frame=%d, timestamp=%f, accelerometer=%r, gyroscope=%r, compass=%f)' % (
            self.frame, self.timestamp, self.accelerometer, self.gyroscope, self.compass)


class GnssMeasurement(SensorData):
    """latitude and longitude in degrees, altitude m (CARLA's GeoLocation::Transform)."""

    def __init__(self, sample, world):
        super().__init__(sample, world)
        self.latitude = self._fields['latitude']
        self.longitude = self._fields['longitude']
        self.altitude = self._fields['altitude']

    def __str__(self):
        return 'GnssMeasurement(frame=%d, timestamp=%f, lat=%f, lon=%f, alt=%f)' % (
            self.frame, self.timestamp, self.latitude, self.longitude, self.altitude)


# --- events ------------------------------------------------------------------------------

# ObjectKind on the wire (idl/lockstep/common.idl).
_OBJECT_GROUND, _OBJECT_STATIC = 1, 2
# The CARLA semantic tag of a kind when the wire gives none: ground is road or terrain,
# static geometry unlabeled.
_KIND_TAGS = {_OBJECT_GROUND: 1, _OBJECT_STATIC: 0}


def static_type_id(tag):
    """CARLA's type id of unregistered scene geometry (CarlaGetRelevantTagAsString):
    'static.' + the tag's name in lower case without a final 's'; 'static.unknown' for None
    and Other."""
    if tag in (0, 22) or not 0 <= tag < len(_TAGGER_NAMES):
        return 'static.unknown'
    name = _TAGGER_NAMES[tag].lower()
    return 'static.' + (name[:-1] if name.endswith('s') else name)


def _other_actor(world, fields):
    """The event's other actor: a registered actor, or, for the static scene, CARLA's
    unregistered actor (id 0, type_id 'static.<tag>', its semantic tag)."""
    if not world:
        return None
    other = fields.get('other_actor', 0)
    if other:
        return world.get_actor(other)
    kind = fields.get('other_kind', 0)
    tag = fields.get('other_semantic_tag', 0) or _KIND_TAGS.get(kind, 0)
    if kind not in _KIND_TAGS and not tag:
        return None
    from .actors import Actor  # actors imports this module
    a = Actor(world, {'id': 0, 'blueprint': static_type_id(tag)})
    a.semantic_tags = [tag] if tag else []
    return a


class CollisionEvent(SensorData):
    def __init__(self, sample, world):
        super().__init__(sample, world)
        self.actor = world.get_actor(self._fields['actor']) if world else None
        self.other_actor = _other_actor(world, self._fields)
        self.normal_impulse = from_enu_vector(self._fields['normal_impulse'])

    def __str__(self):
        return 'CollisionEvent(frame=%d, timestamp=%f, other_actor=%s)' % (self.frame, self.timestamp, self.other_actor)


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
        self.other_actor = _other_actor(world, self._fields)
        self.distance = self._fields['distance']

    def __str__(self):
        return 'ObstacleDetectionEvent(frame=%d, timestamp=%f, other_actor=%s)' % (self.frame, self.timestamp,
                                                                                  self.other_actor)


# ---- V2X (CARLA 0.9.16: LibCarla sensor/data/V2XEvent.h, PythonAPI libcarla/V2XData.cpp) ----
# The payload of each message is docs/sensors.md's packed layout: little-endian int32 fields,
# CARLA's ItsPduHeader first; get() builds CARLA's dict from it, key for key.

_CAM_FIELDS = ('protocol_version', 'message_id', 'station_id', 'generation_delta_time', 'station_type', 'latitude',
               'longitude', 'semi_major_confidence', 'semi_minor_confidence', 'semi_major_orientation', 'altitude_value',
               'altitude_confidence', 'high_frequency_present', 'heading_value', 'heading_confidence', 'speed_value',
               'speed_confidence', 'drive_direction', 'vehicle_length_value', 'vehicle_length_confidence', 'vehicle_width',
               'longitudinal_acceleration_value', 'longitudinal_acceleration_confidence', 'curvature_value',
               'curvature_confidence', 'curvature_calculation_mode', 'yaw_rate_value', 'yaw_rate_confidence',
               'optional_present', 'lateral_acceleration_value', 'lateral_acceleration_confidence',
               'vertical_acceleration_value', 'vertical_acceleration_confidence', 'low_frequency_present', 'vehicle_role',
               'exterior_lights', 'path_history_points')
_MESSAGE_IDS = {0: 'CUSTOM', 1: 'DENM', 2: 'CAM', 3: 'POI', 4: 'SPAT', 5: 'MAP', 6: 'IVI', 7: 'EV_RSR'}
_STATION_TYPES = {0: 'Uunknown', 1: 'Pedestrian', 2: 'Cyclist', 3: 'Moped', 4: 'Motorcycle', 5: 'Passenger Car', 6: 'Bus',
                  7: 'Light Truck', 8: 'HeavyTruck', 9: 'Trailer', 10: 'Special Vehicle', 11: 'Tram', 15: 'Road Side Unit'}
_SEMI_AXIS = {1: 'Semi Axis Length One Centimeter', 4094: 'Semi Axis Length Out Of Range'}
_ORIENTATION = {0: 'Heading wgs84 North', 900: 'Heading wgs84 East', 1800: 'Heading wgs84 South', 2700: 'Heading wgs84 West'}
_HEADING_CONF = {1: 'Equal or With in Zero Point One Degree', 10: 'Equal or With in One Degree', 126: 'Out of Range'}
_SPEED_CONF = {1: 'Equal or With in One Centimeter per Sec', 100: 'Equal or With in One Meter per Sec', 126: 'Out of Range'}
_LENGTH_CONF = {0: 'No Trailer Present', 1: 'Trailer Present With Known Length', 2: 'Trailer Present With Unknown Length',
                3: 'Trailer Presence Is Unknown'}
_ACCEL_CONF = {1: 'Point One Meter Per Sec Squared', 101: 'Out Of Range'}
_CURVATURE_CONF = {0: 'One Per Meter 0_00002', 1: 'One Per Meter 0_0001', 2: 'One Per Meter 0_0005', 3: 'One Per Meter 0_002',
                   4: 'One Per Meter 0_01', 5: 'One Per Meter 0_1', 6: 'Out Of Range'}
_YAW_CONF = {0: 'degSec 000_01', 1: 'degSec 000_05', 2: 'degSec 000_10', 3: 'degSec 001_00', 4: 'degSec 005_00',
             5: 'degSec 010_00', 6: 'degSec 100_00', 7: 'Out Of Range'}
_ROLES = {0: 'Default', 1: 'Public Transport', 2: 'Special Transport', 3: 'Dangerous Goods', 4: 'Road Work', 5: 'Rescue',
          6: 'Emergency', 7: 'Safety Car', 8: 'Agriculture', 9: 'Commercial', 10: 'Military', 11: 'Road Operator',
          12: 'Taxi', 13: 'Reserved 1', 14: 'Reserved 2', 15: 'Reserved 3'}


def _int32s(payload, count):
    n = min(count, len(payload) // 4)
    values = list(struct.unpack_from('<%di' % n, payload)) if n else []
    return values + [0] * (count - n)


def _header(protocol_version, message_id, station_id):
    return {'Protocol Version': protocol_version, 'Message ID': _MESSAGE_IDS.get(message_id, 'Not Found'),
            'Station ID': station_id}


def _cam_dict(c):
    ref = {'Latitude': c['latitude'], 'Longitude': c['longitude'],
           'Position Confidence Eliipse': {  # sic, CARLA's key
               'Semi Major Confidence': _SEMI_AXIS.get(c['semi_major_confidence'], 'Semi Axis Length Unavailable'),
               'Semi Minor Confidence': _SEMI_AXIS.get(c['semi_minor_confidence'], 'Semi Axis Length Unavailable'),
               'Semi Major Orientation': _ORIENTATION.get(c['semi_major_orientation'], 'Heading Unavailable')}}
    basic = {'Station Type': _STATION_TYPES.get(c['station_type'], 'Unknown'), 'Reference Position': ref}
    present = c['high_frequency_present']
    if present == 1:
        opt = c['optional_present']
        vc = lambda value, table, conf: {'Value': value, 'Confidence': table.get(conf, 'Unavailable')}  # noqa: E731
        bvc = {'Heading': vc(c['heading_value'], _HEADING_CONF, c['heading_confidence']),
               'Speed': vc(c['speed_value'], _SPEED_CONF, c['speed_confidence']),
               'Drive Direction': c['drive_direction'],
               'Vehicle Length': vc(c['vehicle_length_value'], _LENGTH_CONF, c['vehicle_length_confidence']),
               'Vehicle Width': c['vehicle_width'],
               'Longitudinal Acceleration': vc(c['longitudinal_acceleration_value'], _ACCEL_CONF,
                                               c['longitudinal_acceleration_confidence']),
               'Curvature': vc(c['curvature_value'], _CURVATURE_CONF, c['curvature_confidence']),
               'Curvature Calculation Mode': c['curvature_calculation_mode'],
               'Yaw Rate': vc(c['yaw_rate_value'], _YAW_CONF, c['yaw_rate_confidence']),
               'Acceleration Control': None, 'Lane Position': None, 'Steering Wheel Angle': None,
               'Lateral Acceleration': vc(c['lateral_acceleration_value'], _ACCEL_CONF,
                                          c['lateral_acceleration_confidence']) if opt & 8 else None,
               'Vertical Acceleration': vc(c['vertical_acceleration_value'], _ACCEL_CONF,
                                           c['vertical_acceleration_confidence']) if opt & 16 else None,
               'Performance class': None, 'Cen DSRC Tolling Zone': None}
        hfc = {'High Frequency Container Present': 'Basic Vehicle Container High Frequency',
               'Basic Vehicle Container High Frequency': bvc}
    elif present == 2:
        hfc = {'High Frequency Container Present': 'RSU Container High Frequency',
               'RSU Container High Frequency': {'Protected Communication Zone': []}}
    else:
        hfc = {'High Frequency Container Present': 'No container present'}
    if c['low_frequency_present'] == 1:
        lfc = {'Low Frequency Container Present': 'Basic Vehicle Container Low Frequency',
               'Basic Vehicle Low Frequency': {'Vehicle Role': _ROLES.get(c['vehicle_role'], 'Default'),
                                               'Exterior Light': c['exterior_lights'], 'Path History': None}}
    else:
        lfc = {'Low Frequency Container Present': 'No Container Present'}
    return {'Header': _header(c['protocol_version'], c['message_id'], c['station_id']),
            'Message': {'Generation Delta Time': c['generation_delta_time'],
                        'CAM Parameters': {'Basic Container': basic, 'High Frequency Container': hfc,
                                           'Low Frequency Container': lfc}}}


class CAMMessage:
    """carla.CAMMessage: one cooperative awareness message as a sensor.other.v2x received it."""

    def __init__(self, power=0.0, payload=b''):
        self.power = float(power)
        self._fields = dict(zip(_CAM_FIELDS, _int32s(payload, len(_CAM_FIELDS))))

    def get(self):
        """CARLA's dict of the message (Header, Message: Generation Delta Time, CAM Parameters)."""
        return _cam_dict(self._fields)

    def __str__(self):
        return 'CAMData(power=%f, stationId=%d, messageId=%d)' % (self.power, self._fields['station_id'],
                                                                   self._fields['message_id'])


class CustomV2XData:
    """carla.CustomV2XData: one message a sensor.other.v2x_custom received."""

    def __init__(self, power=0.0, payload=b''):
        self.power = float(power)
        self._header = _int32s(payload[:12], 3)
        self._text = bytes(payload[12:]).decode('utf-8', errors='replace')

    def get(self):
        """CARLA's dict: Header (Protocol Version, Message ID, Station ID) and the Message text."""
        return {'Header': _header(*self._header), 'Message': self._text}

    def __str__(self):
        return 'CustomV2XData(power=%f, stationId=%d, messageId=%d)' % (self.power, self._header[2], self._header[1])


class _V2XEvent(SensorData):
    _message = None

    def __init__(self, sample, world):
        super().__init__(sample, world)
        self._messages = [self._message(power, payload) for _, power, payload in self._fields['messages']]

    def get_message_count(self):
        return len(self._messages)

    def __len__(self):
        return len(self._messages)

    def __iter__(self):
        return iter(self._messages)

    def __getitem__(self, pos):
        return self._messages[pos]

    def __str__(self):
        return '%s(frame=%d, timestamp=%f, message_count=%d)' % (type(self).__name__, self.frame, self.timestamp,
                                                                 len(self._messages))


class CAMEvent(_V2XEvent):
    """carla.CAMEvent: the CAMs a sensor.other.v2x received in one step (sent only when any)."""
    _message = CAMMessage


class CustomV2XEvent(_V2XEvent):
    """carla.CustomV2XEvent: the messages a sensor.other.v2x_custom received in one step."""
    _message = CustomV2XData


def _v2x_event(sample, world):
    msgs = sample.fields()['messages']
    custom = bool(msgs) and _int32s(msgs[0][2][:8], 2)[1] == 0  # message id 0: custom
    return (CustomV2XEvent if custom else CAMEvent)(sample, world)


_CLASSES = {'v2x': _v2x_event, 'imu': IMUMeasurement, 'gnss': GnssMeasurement, 'radar': RadarMeasurement,
            'collision': CollisionEvent, 'lane_invasion': LaneInvasionEvent, 'obstacle': ObstacleDetectionEvent}
_IMAGE_CLASSES = {'flow_f32x2': OpticalFlowImage, 'dvs_events': DVSEventArray}


def make_sensor_data(sample, world):
    t = sample.type
    if t == 'point_cloud':
        return (SemanticLidarMeasurement if sample.fields()['semantic'] else LidarMeasurement)(sample, world)
    if t == 'image':
        return _IMAGE_CLASSES.get(sample.fields()['encoding'], Image)(sample, world)
    cls = _CLASSES.get(t)
    if cls is None:
        data = SensorData(sample, world)
        data.__dict__.update(data._fields)
        return data
    return cls(sample, world)
