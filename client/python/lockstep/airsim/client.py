"""airsim.VehicleClient / MultirotorClient / CarClient over Lockstep.

Coordinates are AirSim's: each vehicle's NED metres from its own start (its home), body
FRD; the world NED of simAddVehicle, settings.json and the plotting calls is the player
start's (docs/compatibility.md). *Async calls return a future whose join() waits until
air_sim reports the command finished (in synchronous mode it ticks the world).

API control is the vehicle's (air_sim's drone state), whichever client or process takes it,
as AirSim's server holds it. One state per process (per DDS session): camera poses, the
settings.json vehicles and the sensors attached to them belong to the vehicle, whichever
client of the process asks."""
import logging
import math
import os
import re
import struct
import threading
import time
import weakref
import zlib

import numpy as np

import lockstep

from . import geometry as geo
from . import segmentation as seg
from . import settings as settings_mod
from .types import (AngleLevelControllerGains, AngleRateControllerGains, BarometerData, Box2D, Box3D, CameraInfo,
                    CarState, CollisionInfo, DetectionInfo, DistanceSensorData, DrivetrainType, EnvironmentState,
                    GeoPoint, GpsData, ImageRequest, ImageResponse, ImageType, ImuData, KinematicsState, LandedState,
                    LidarData, MagnetometerData, MultirotorState, Pose, PositionControllerGains, ProjectionMatrix,
                    Quaternionr, RCData, RotorStates, Vector2r, Vector3r, VelocityControllerGains, WeatherParameter,
                    YawMode, _rotate_vector, to_eularian_angles)

__all__ = ['VehicleClient', 'MultirotorClient', 'CarClient', 'LockstepUnsupported']

log = logging.getLogger('lockstep.airsim')


class LockstepUnsupported(RuntimeError):
    """An airsim call Lockstep cannot do; the message names the call and why."""


def _unsupported(call, why):
    raise LockstepUnsupported('%s is not supported by Lockstep: %s (docs/compatibility.md)' % (call, why))


def _v(t):
    return Vector3r(*t)


def _q(t):
    w, x, y, z = t
    return Quaternionr(x, y, z, w)


# --------------------------------------------------------------------------- futures
class _Future:
    """What AirSim's *Async calls return. join() blocks until air_sim reports the command
    finished: True when it completed, False when it timed out or was cancelled (AirSim's
    bool); a rejected command raises CommandRejected with air_sim's reason. While it
    waits, it looks at the vehicle every 10 s of wall time and logs where it is when it has not
    moved 0.5 m since the last look, so a command that cannot complete (a target the drone
    cannot reach) is visible."""

    _REPORT_S = 10.0

    def __init__(self, shared, native, name, call):
        self._shared, self._f, self._name, self._call = shared, native, name, call
        self._result = None

    def join(self):
        if self._result is not None:
            return self._result
        client = self._shared.client
        start = last = time.monotonic()
        while True:
            try:
                client.wait_drone(self._f.actor, self._f.command_id, 1.0)
                break
            except lockstep.ClientError as e:
                if 'not finished within' not in str(e):
                    raise
            now = time.monotonic()
            if now - last >= self._REPORT_S:
                last = now
                self._report(now - start)
        self._result = bool(self._f.join())
        return self._result

    def _report(self, waited):
        """A log line when the vehicle moved less than 0.5 m since the last look: it is stuck."""
        try:
            s = self._shared.mc.state(self._name)
            p, v = s['position'], s['linear_velocity']
            last, self._last_seen = getattr(self, '_last_seen', None), p
            if last is None or sum((a - b) ** 2 for a, b in zip(p, last)) >= 0.25:
                return
            c = s['collision']
            what = 'at (%.1f, %.1f, %.1f) m NED, %.2f m/s' % (p[0], p[1], p[2], math.sqrt(sum(x * x for x in v)))
            if c[0] or c[6]:
                what += ', last contact with %s' % (c[6] or 'something')
            log.warning("airsim: %s on vehicle '%s' still running after %.0f s and not getting anywhere (%s); "
                        "AirSim's timeout_sec bounds it", self._call, self._name or 'default', waited, what)
        except Exception:  # noqa: BLE001 - a report must never break the wait
            pass

    def get(self):
        return self.join()

    @property
    def result(self):
        return self.join()

    def status(self):
        return self._f.status()


class _DoneFuture:
    """A command AirSim completes at once (duration <= 0): join() returns `value`."""

    def __init__(self, value=True):
        self._value = value

    def join(self):
        return self._value

    get = join

    @property
    def result(self):
        return self._value

    def status(self):
        return 'COMPLETED'


class _TimedFuture:
    """moveByManualAsync: completes after `duration` s of simulation time."""

    def __init__(self, shared, end_time):
        self._shared, self._end = shared, end_time

    def join(self):
        c = self._shared.client
        while self._shared.sim_time() < self._end:
            if self._shared.synchronous():
                c.tick()
            else:
                c.wait_for_tick(10.0)
        return True

    get = join

    def status(self):
        return 'COMPLETED' if self._shared.sim_time() >= self._end else 'RUNNING'


# --------------------------------------------------------------------------- cameras
# AirSim's multirotor cameras (BP_FlyingPawn): name -> mount (x, y, z m FRD; roll, pitch, yaw deg).
_DEFAULT_CAMERAS = {
    'front_center': (0.25, 0.0, 0.0, 0.0, 0.0, 0.0),
    'front_right': (0.25, 0.05, 0.0, 0.0, 0.0, 0.0),
    'front_left': (0.25, -0.05, 0.0, 0.0, 0.0, 0.0),
    'bottom_center': (0.0, 0.0, 0.1, 0.0, -90.0, 0.0),
    'back_center': (-0.25, 0.0, 0.0, 0.0, 0.0, 180.0),
    'fpv': (0.25, 0.0, 0.0, 0.0, 0.0, 0.0),
}
_CAMERA_ALIASES = {'0': 'front_center', '1': 'front_right', '2': 'front_left', '3': 'bottom_center',
                   '4': 'back_center', '': 'front_center'}
_IMAGE_TYPE_NAMES = {ImageType.Scene: 'Scene', ImageType.DepthPlanar: 'DepthPlanar',
                     ImageType.DepthPerspective: 'DepthPerspective', ImageType.DepthVis: 'DepthVis',
                     ImageType.DisparityNormalized: 'DisparityNormalized', ImageType.Segmentation: 'Segmentation',
                     ImageType.SurfaceNormals: 'SurfaceNormals', ImageType.Infrared: 'Infrared'}


def _png(img):
    """PNG bytes of an (h, w, 4) RGBA or (h, w) grey uint8 image (AirSim's compressed images are RGBA)."""
    img = np.ascontiguousarray(img, dtype=np.uint8)
    h, w = img.shape[:2]
    channels = 1 if img.ndim == 2 else img.shape[2]
    color_type = {1: 0, 3: 2, 4: 6}[channels]
    raw = np.concatenate([np.zeros((h, 1), dtype=np.uint8), img.reshape(h, w * channels)], axis=1).tobytes()

    def chunk(tag, data):
        c = struct.pack('>I', len(data)) + tag + data
        return c + struct.pack('>I', zlib.crc32(tag + data) & 0xffffffff)

    return (b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', w, h, 8, color_type, 0, 0, 0)) +
            chunk(b'IDAT', zlib.compress(raw, 3)) + chunk(b'IEND', b''))


def _airsim_flow(flow):
    """CARLA's optical flow (render's: x right, y down, image-plane motion since the previous
    image, [-2, 2] spans the image) as AirSim's OpticalFlow material computes it: (current -
    previous) clip position / 2, i.e. the motion as a fraction of the image, x right, y UP."""
    f = np.asarray(flow, np.float32)
    return f[..., 0] * np.float32(0.5), f[..., 1] * np.float32(-0.5)


def _flow_vis(vx, vy):
    """AirSim's OpticalFlowVis material (OpticalFlowRGBMaterial: hue 180 deg + the flow's angle,
    as its HLSL with 180 / 3.1415; saturation 1; value log(|flow| + 0.999) / log(1.099), clamped
    to 0..1), r, g, b floats 0..1 (no flow: black)."""
    vx = np.asarray(vx, np.float32)
    vy = np.asarray(vy, np.float32)
    angle = np.float32(180.0) + np.arctan2(vy, vx) * np.float32(180.0 / 3.1415)
    angle = np.where(angle < 0, angle + np.float32(360.0), angle)
    angle = np.fmod(angle, np.float32(360.0))
    norm = np.sqrt(vx * vx + vy * vy)
    with np.errstate(divide='ignore'):
        v = np.clip(np.log(norm + np.float32(0.999)) / np.float32(math.log(0.1 + 0.999)), 0.0, 1.0).astype(np.float32)
    h60 = angle / np.float32(60.0)
    c = v
    x = c * (np.float32(1.0) - np.abs(np.fmod(h60, np.float32(2.0)) - np.float32(1.0)))
    case = h60.astype(np.int64)
    z = np.zeros_like(c)
    one = np.ones_like(c)
    r = np.select([case == 0, case == 1, case == 2, case == 3, case == 4, case == 5], [c, x, z, z, x, c], one)
    g = np.select([case == 0, case == 1, case == 2, case == 3, case == 4, case == 5], [x, c, c, x, z, z], one)
    b = np.select([case == 0, case == 1, case == 2, case == 3, case == 4, case == 5], [z, z, x, c, c, x], one)
    return r, g, b


def _unorm8(v):
    """Unreal's float -> 8-bit read-back (FLinearColor::ToFColor without gamma): clamp to 0..1, x 255.999, truncate."""
    return np.floor(np.clip(np.asarray(v, np.float32), 0.0, 1.0) * np.float32(255.999)).astype(np.uint8)


def _airsim_normals(bgra, cam_q_ned):
    """The render's camera-frame normals (x right, y up, z towards the camera; BGRA bytes,
    (n + 1) / 2) as AirSim's NormalsMaterial writes them: Unreal's world-space normal (X north,
    Y east, Z up) as (n + 1) / 2 in R, G, B, read back as Unreal does (x 255.999, truncated:
    0 is 127, AirSim issue 2813's (127, 127, 255) for an upward face); `cam_q_ned` is the
    camera's orientation (body FRD to world NED). Where nothing was drawn (the sky: alpha 0)
    stays black."""
    a = np.asarray(bgra)
    n_view = a[..., 2::-1].astype(np.float32) / np.float32(255.0) * 2 - 1   # x, y, z
    n_view[np.abs(n_view) <= np.float32(1.5 / 255)] = 0   # 127 and 128: the render's 0
    n_frd = np.stack([-n_view[..., 2], n_view[..., 0], -n_view[..., 1]], axis=-1)
    q = cam_q_ned
    w, x, y, z = q.w_val, q.x_val, q.y_val, q.z_val
    n = math.sqrt(w * w + x * x + y * y + z * z) or 1.0
    w, x, y, z = w / n, x / n, y / n, z / n
    rot = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                    [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                    [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]], np.float32)
    n_ned = n_frd @ rot.T
    n_ue = np.stack([n_ned[..., 0], n_ned[..., 1], -n_ned[..., 2]], axis=-1)   # X north, Y east, Z up
    out = np.ascontiguousarray(_unorm8(n_ue * 0.5 + 0.5)[..., ::-1])   # B, G, R as Unreal reads them back (0 -> 127)
    if a.shape[-1] == 4:
        out[a[..., 3] == 0] = 0
    return out


# --------------------------------------------------------------------------- shared state
class _Sensors:
    """Sensors spawned on the vehicles on first use (from settings.json or AirSim's
    defaults), listened to; latest() returns the newest sample. One set per session and run."""

    def __init__(self, shared):
        self._shared = weakref.proxy(shared)
        self._slots = {}   # key -> [actor id, latest sample, spec]
        self._cv = threading.Condition()

    def latest(self, call, key, blueprint, attributes, pose, parent, newer_than=None):
        """The newest sample of the sensor `key` (spawned with blueprint/attributes/pose on
        `parent` the first time; respawned when they change)."""
        c = self._shared.client
        spec = (blueprint, tuple(sorted(attributes.items())), tuple(round(v, 9) for v in pose), parent)
        slot = self._slots.get(key)
        if slot is not None and slot[2] != spec:
            try:
                c.destroy(slot[0])
            except lockstep.ClientError:
                pass
            slot = None
        if slot is None:
            declared = {d['id'] for d in c.blueprints(1.0)}
            if blueprint not in declared:
                _unsupported(call, "no running service declares '%s' (start the sensors/render services)" % blueprint)
            sensor = c.spawn(blueprint, pose, dict(attributes), parent)
            slot = [sensor, None, spec]
            self._slots[key] = slot

            def on_data(sample, slot=slot):
                with self._cv:
                    slot[1] = sample
                    self._cv.notify_all()

            c.listen(sensor, on_data)
        deadline = time.monotonic() + 60.0
        while True:
            with self._cv:
                s = slot[1]
                if s is not None and (newer_than is None or s.frame > newer_than):
                    return s
            if self._shared.synchronous():
                c.tick()
            else:
                with self._cv:
                    self._cv.wait(0.1)
            if time.monotonic() > deadline:
                raise lockstep.ClientError('%s: sensor %s (%s) delivered no data within 60 s' % (call, slot[0], blueprint))

    def drop(self, predicate):
        for key in [k for k in self._slots if predicate(k)]:
            slot = self._slots.pop(key)
            try:
                self._shared.client.destroy(slot[0])
            except lockstep.ClientError:
                pass


class _Shared:
    """A process's AirSim-side state over its DDS session (see the module docstring)."""

    def __init__(self, client):
        self.client = client
        self.mc = lockstep.Multirotor(client)
        self.lock = threading.RLock()
        self.settings = None
        self.run = None
        self.sensors = None
        self.player_start = None
        self.cameras = {}       # (actor, camera) -> {'pose': (x y z roll pitch yaw), 'fov': deg}
        self.manual = {}        # actor -> (vx_max, vy_max, z_min, end_time, drivetrain, yaw_mode)
        self.rc = {}            # actor -> RCData
        self.trace = {}         # actor -> (rgba, thickness)
        self.seg_ids = {}       # object name -> id (simSetSegmentationObjectID)
        self.statics = None     # the town's static objects: name -> (mesh instance id, tag, centre ENU)
        self.static_names = {}  # mesh instance id -> name
        self.detection = {}     # (actor, camera, image_type) -> {'filters': [...], 'radius_cm': ...}
        self.recording = None      # {'folder', 'log'} while startRecording runs
        self.weather_enabled = False
        self.time_of_day = None
        self.spawned_objects = {}  # name -> actor id (simSpawnObject)
        self.car_api = {}          # (run, car actor id) -> API control, where it cannot be the car's (no marker blueprint)
        self.car_controls = {}     # (run, car actor id) -> (CarControls last set under API control, frame set)
        self.car_watch = {}        # (run, car actor id) -> [collision sensor, last event, frame of the last reset]

    # --- settings and the run ---
    def load_settings(self):
        if self.settings is None:
            self.settings = settings_mod.load()
        return self.settings

    def synchronous(self):
        return self.client.world_info()['settings']['synchronous_mode']

    def sim_time(self):
        return self.client.frame() * self.client.world_info()['settings']['fixed_delta_seconds']

    def wait_frames(self, n=1):
        for _ in range(n):
            if self.synchronous():
                self.client.tick()
            else:
                self.client.wait_for_tick(10.0)

    def begin_run(self):
        """Per run: settings read, clock speed and wind applied, sensors reset."""
        run = self.client.world_info()['run']
        if run == self.run:
            return
        s = self.load_settings()
        self.run = run
        self.sensors = _Sensors(self)
        self.player_start = None
        self.cameras.clear()
        self.manual.clear()
        self.spawned_objects.clear()
        self.statics = None
        self.static_names = {}
        if s.path:
            info = self.client.world_info()['settings']
            if abs(info.get('real_time_factor', 1.0) - s.clock_speed) > 1e-9 and s.clock_speed != 1.0:
                self.client.apply_settings({'real_time_factor': s.clock_speed})
            if any(s.wind) and self.drones():
                self.mc.set_wind(s.wind)
        if s.recording.enabled and self.recording is None:
            self.start_recording()  # settings.json Recording.Enabled: AirSim records from the start

    def drones(self):
        return [a for a in self.client.actors() if a['kind'] == 'drone']

    # --- recording (AirSim's startRecording / settings.json Recording) ---
    def start_recording(self):
        with self.lock:
            if self.recording is not None:
                self.stop_recording()  # AirSim's startRecording stops a recording in course first
            rec = self.load_settings().recording
            base = os.path.expanduser(rec.folder) if rec.folder else os.path.join(os.path.expanduser('~'), 'Documents',
                                                                                     'AirSim')
            # AirSim's folder name: the wall-clock time the recording starts (FileSystem::getLogFolderPath).
            folder = os.path.join(os.path.abspath(base), time.strftime('%Y-%m-%d-%H-%M-%S'))
            os.makedirs(folder, exist_ok=True)
            path = self.client.start_recorder(os.path.join(folder, 'airsim_rec.log'))
            self.recording = {'folder': folder, 'log': path}
            log.info('airsim: recording to %s', folder)

    def stop_recording(self):
        with self.lock:
            rec, self.recording = self.recording, None
            if rec is None:
                return  # AirSim: stopping with no recording is logged and ignored
            self.client.stop_recorder()
            if not self.synchronous():
                # The recorder closes the log (its writer thread drained) with the tick that
                # carries the stop: the tick in flight may not, the one after does.
                for _ in range(2):
                    self.client.wait_for_tick(10.0)
            settings = self.load_settings().recording
            try:
                from lockstep import _lockstep
                _lockstep.write_airsim_record(rec['log'], os.path.join(rec['folder'], 'airsim_rec.txt'),
                                              settings.record_interval, settings.record_on_move)
            except (lockstep.ClientError, RuntimeError) as e:  # a log the recorder could not write
                log.warning('airsim: airsim_rec.txt not written: %s', e)

    # --- the player start: where AirSim's vehicles start ---
    def start(self):
        """The player start (world ENU, on the ground): the sidewalk point nearest the map's
        first vehicle spawn point that is 6 m or more from every vehicle spawn point and 3 m
        from every actor, so no car spawned there hits the drone ($LOCKSTEP_DRONE_SPAWN=x,y,z
        sets it). In SimMode "Car" the map's first vehicle spawn point, on the road."""
        if self.player_start is not None:
            return self.player_start
        env = os.environ.get('LOCKSTEP_DRONE_SPAWN')
        if env:
            v = [float(p) for p in env.split(',')]
            self.player_start = (v[0], v[1], v[2])
            return self.player_start
        if self.load_settings().sim_mode == 'Car':
            cs = self.car_start()   # SimMode "Car": AirSim's car starts on the road
            if cs is not None:
                self.player_start = cs[:3]
                return self.player_start
        try:
            m = self.client.map()
            spawns = [tuple(p[:3]) for p in m.spawn_points(2.0)]
            walks = [tuple(p[:3]) for p in m.pedestrian_spawn_points(5.0)]
        except lockstep.ClientError:
            spawns, walks = [], []
        others = [t[:3] for t in self.actor_positions()]

        def d2(a, b):
            return (a[0] - b[0]) ** 2 + (a[1] - b[1]) ** 2

        ref = spawns[0] if spawns else (0.0, 0.0, 0.0)
        best = None
        for p in sorted(walks, key=lambda p: (d2(p, ref), p)):
            if all(d2(p, s) >= 36.0 for s in spawns) and all(d2(p, o) >= 9.0 for o in others):
                best = p
                break
        # Map spawn points stand above the surface: sidewalk ones 1 m (a walker's centre), road ones 0.5 m.
        self.player_start = (best[0], best[1], best[2] - 1.0) if best else (ref[0], ref[1], ref[2] - (0.5 if spawns else 0))
        return self.player_start

    def actor_positions(self):
        """World ENU positions of the run's actors (not sensors)."""
        out = []
        for a in self.client.actors():
            if a['kind'] == 'sensor':
                continue
            st = self.client.state(a['id'])
            t = st.get('transform') if st else None
            if t:
                out.append(tuple(t[:3]))
        return out

    def free_at(self, enu, clearance=1.5):
        """No actor of the run within `clearance` m (horizontally, 3 m vertically) of `enu`."""
        for t in self.actor_positions():
            if (t[0] - enu[0]) ** 2 + (t[1] - enu[1]) ** 2 < clearance ** 2 and abs(t[2] - enu[2]) < 3:
                return False
        return True

    # --- vehicles ---
    def ensure_vehicles(self):
        """AirSim's vehicles exist from the start: the settings' AutoCreate vehicles (or the
        default SimpleFlight when no drone is there) are spawned at their poses the first time
        a client needs one."""
        with self.lock:
            self.begin_run()
            s = self.load_settings()
            have = set(self.mc.list_vehicles())
            drones_present = bool(self.drones())
            created = []
            for v in s.all_vehicles():
                if v.mode != 'Multirotor' or not v.auto_create or v.name in have:
                    continue
                if not s.vehicles and drones_present:
                    continue  # a drone is there already: AirSim's single default vehicle
                created.append(self.spawn_vehicle(v.name, (v.x, v.y, v.z), (v.roll, v.pitch, v.yaw)))
            if created:
                self.wait_at_rest(created)
                if any(s.wind):
                    self.mc.set_wind(s.wind)

    def spawn_vehicle(self, name, ned, rpy_deg):
        sx, sy, sz = self.start()
        x, y, z = geo.ned_to_enu_pos(ned, (sx, sy, sz + 0.2))
        if not self.free_at((x, y, z)):
            # As Unreal's AdjustIfPossibleButAlwaysSpawn (AirSim's pawns): the nearest free place nearby.
            for r in (2.0, 4.0, 6.0, 8.0):
                spots = [(x + r * math.cos(k * math.pi / 4), y + r * math.sin(k * math.pi / 4), z) for k in range(8)]
                free = [p for p in spots if self.free_at(p)]
                if free:
                    log.warning("airsim: vehicle '%s': its start overlaps an actor; placed %.0f m away", name, r)
                    x, y, z = free[0]
                    break
            else:
                raise lockstep.ClientError("vehicle '%s': its start (%.1f, %.1f, %.1f) and 8 m around it are taken"
                                           % (name, x, y, z))
        q = geo.ned_to_enu_quat(geo.frd_euler_deg_to_quat(*rpy_deg))
        return self.mc.add_vehicle(name, 'drone.generic_quad', (x, y, z) + tuple(q))

    def wait_at_rest(self, actors, limit_s=10.0):
        """AirSim's vehicles are at rest when a script starts: wait (at most limit_s of
        simulation time) until the new drones have settled on the ground (|v| < 0.05 m/s)."""
        dt = self.client.world_info()['settings']['fixed_delta_seconds'] or 0.05
        still = {}
        for _ in range(int(limit_s / dt) + 2):
            self.wait_frames(1)
            done = True
            for a in actors:
                d = self.client.drone_state(a)
                if d is None:
                    done = False
                    continue
                speed = math.sqrt(sum(x * x for x in d['velocity']))
                still[a] = still.get(a, 0) + 1 if speed < 0.05 else 0
                done = done and still[a] >= 3
            if done:
                return

    def actor(self, name):
        self.ensure_vehicles()
        return self.mc.resolve(name)

    def vehicle_setting(self, name):
        s = self.load_settings()
        if name in s.vehicles:
            return s.vehicles[name]
        if not name:
            vs = s.all_vehicles()
            try:
                first = self.mc.list_vehicles()[0]
            except IndexError:
                first = None
            for v in vs:
                if v.name == first:
                    return v
            return vs[0] if not s.vehicles else None
        return None

    # --- AirSim's cars (CarClient, SimMode "Car") on ground_sim ---
    def airsim_car_names(self):
        """The names of AirSim's cars: the settings' cars in SimMode "Car" (AirSim's PhysXCar
        when it names none), else the PhysXCar a CarClient creates."""
        s = self.load_settings()
        if s.sim_mode == 'Car':
            return [v.name for v in s.all_vehicles() if v.mode == 'Car']
        return ['PhysXCar']

    def car_setting(self, name):
        s = self.load_settings()
        if name in s.vehicles:
            return s.vehicles[name]
        if not s.vehicles and s.sim_mode == 'Car' and name == 'PhysXCar':
            return s.default_vehicle()
        return None

    def car_start(self):
        """The map's first vehicle spawn point (x, y, z on the road, yaw rad ENU); None without one."""
        try:
            sp = self.client.map().spawn_points(2.0)[0]
        except (lockstep.ClientError, IndexError):
            return None
        return (sp[0], sp[1], sp[2] - 0.5, sp[3])   # road spawn points stand 0.5 m above the road

    def spawn_car(self, name, pose):
        bps = sorted(d['id'] for d in self.client.blueprints(1.0) if d['id'].startswith('vehicle.'))
        if not bps:
            _unsupported('CarClient', 'no ground_sim service is running')
        return self.client.spawn(bps[0], pose, {'role_name': name})

    def ensure_cars(self):
        """SimMode "Car": AirSim's cars exist from the start: the settings' AutoCreate cars (or
        AirSim's PhysXCar) are spawned at their poses (NED from the player start; without a
        Yaw the player start's heading) the first time a client needs one."""
        with self.lock:
            self.begin_run()
            s = self.load_settings()
            if s.sim_mode != 'Car':
                return
            want = [v for v in s.all_vehicles() if v.mode == 'Car' and v.auto_create]
            have = {a['attributes'].get('role_name', '') for a in self.client.actors() if a['kind'] == 'vehicle'}
            missing = [v for v in want if v.name not in have]
            if not missing:
                return
            sx, sy, sz = self.start()
            cs = self.car_start()
            yaw_enu = cs[3] if cs else 0.0
            for v in missing:
                x, y, z = geo.ned_to_enu_pos((v.x, v.y, v.z), (sx, sy, sz + _CAR_HEIGHT))
                yaw = v.yaw if v.yaw_given else 90.0 - math.degrees(yaw_enu)
                q = geo.ned_to_enu_quat(geo.frd_euler_deg_to_quat(v.roll, v.pitch, yaw))
                self.spawn_car(v.name, (x, y, z) + tuple(q))
            self.wait_frames(2)

    def airsim_cars(self):
        """The run's AirSim cars (by name), not the other cars of the world."""
        names = set(self.airsim_car_names())
        return [a for a in self.client.actors() if a['kind'] == 'vehicle' and a['attributes'].get('role_name', '') in names]

    def reset_car(self, a):
        """CarPawnSimApi::reset: the car back at its start, at rest, CarControls() applied and
        kept (CarPawnApi::resetImplementation), its collision info cleared; API control stays."""
        from .types import CarControls
        c = self.client
        c.submit({'type': 'set_transform', 'actor': a['id'], 'transform': tuple(a['spawn_transform'])})
        for kind in ('set_target_velocity', 'set_target_angular_velocity'):
            c.submit({'type': 'actor_physics', 'actor': a['id'], 'kind': kind, 'value': (0.0, 0.0, 0.0)})
        c.submit(dict(_car_wire_controls(CarControls()), type='vehicle_control', actor=a['id']))
        key = (self.client.world_info()['run'], a['id'])
        if key in self.car_controls:
            self.car_controls[key] = (CarControls(), math.inf)
        w = self.car_watch.get(key)
        if w is not None:
            with self.lock:
                w[1] = None
                w[2] = c.frame()   # events of frames before the reset are not this start's

    def watch_car(self, a):
        """Listens to the car's collision sensor (role_name airsim_collision; spawned on it the
        first time, when the sensors service declares sensor.other.collision); returns `a`."""
        key = (self.client.world_info()['run'], a['id'])
        if key in self.car_watch:
            return a
        with self.lock:
            if key in self.car_watch:
                return a
            slot = [None, None, -1]   # sensor id, last event sample, ignore events up to this frame
            self.car_watch[key] = slot
            found = [x for x in self.client.actors()
                     if x['parent'] == a['id'] and x['attributes'].get('role_name') == _COLLISION_SENSOR]
            if found:
                slot[0] = found[0]['id']
            elif 'sensor.other.collision' in {d['id'] for d in self.client.blueprints(1.0)}:
                slot[0] = self.client.spawn('sensor.other.collision', (0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0),
                                            {'role_name': _COLLISION_SENSOR}, a['id'])
            if slot[0] is not None:
                def on_event(sample, slot=slot):
                    if sample.frame > slot[2]:
                        slot[1] = sample
                self.client.listen(slot[0], on_event)
        return a

    def car_collision(self, a, st, call):
        """AirSim's CollisionInfo of the car's last collision since its start or reset."""
        key = (self.client.world_info()['run'], a['id'])
        slot = self.car_watch.get(key)
        if slot is None or slot[0] is None:
            _unsupported((call or 'CarState.collision') + ' on a car', 'it needs the sensors service (sensor.other.collision on the car)')
        out = CollisionInfo()
        ev = slot[1]
        if ev is None:
            return out
        f = ev.fields()
        n = f['normal_impulse']
        norm = math.sqrt(sum(x * x for x in n))
        out.has_collided = True
        out.normal = _v(geo.enu_to_ned_pos(tuple(x / norm for x in n), (0, 0, 0))) if norm > 0 else Vector3r()
        pos = _v(geo.enu_to_ned_pos(st['transform'][:3], a['spawn_transform'][:3]))
        out.position = out.impact_point = pos
        other = int(f['other_actor'])
        out.object_id = other if other else -1
        if other:
            oa = self.client.actor(other)
            role = oa['attributes'].get('role_name', '') if oa else ''
            out.object_name = role or ('%s_%d' % (oa['kind'], other) if oa else '')
        dt = self.client.world_info()['settings']['fixed_delta_seconds']
        out.time_stamp = int(round(ev.frame * dt * 1e9))
        return out

    def car_api_enabled(self, a):
        """A car's API control: an actor on it named airsim_api_control (any process sees it:
        AirSim's server holds the flag); per process where no service declares its blueprint."""
        key = (self.client.world_info()['run'], a['id'])
        if key in self.car_api:
            return self.car_api[key]
        return any(x['parent'] == a['id'] and x['attributes'].get('role_name') == _API_MARKER for x in self.client.actors())

    def set_car_api(self, a, enabled):
        key = (self.client.world_info()['run'], a['id'])
        marker_bp = 'sensor.other.collision'
        if key not in self.car_api and marker_bp not in {d['id'] for d in self.client.blueprints(1.0)}:
            log.warning('airsim: no service declares %s: the API control of car %d is this process\'s', marker_bp, a['id'])
            self.car_api[key] = False
        if key in self.car_api:
            self.car_api[key] = enabled
            return
        markers = [x['id'] for x in self.client.actors()
                   if x['parent'] == a['id'] and x['attributes'].get('role_name') == _API_MARKER]
        if enabled and not markers:
            self.client.spawn(marker_bp, (0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0), {'role_name': _API_MARKER}, a['id'])
        elif not enabled:
            for m in markers:
                try:
                    self.client.destroy(m)
                except lockstep.ClientError:
                    pass

    # --- geodesy (the map's geo-reference; settings' OriginGeopoint at the player start) ---
    def _geo_ref(self):
        lat = lon = 0.0
        try:
            for token in self.client.map().geo_reference.split():
                key, _, value = token.partition('=')
                if key == '+lat_0':
                    lat = float(value)
                elif key == '+lon_0':
                    lon = float(value)
        except (lockstep.ClientError, ValueError):
            pass
        return lat, lon

    def enu_to_geo(self, x, y, z):
        """CARLA's projection (the GNSS sensor's), shifted so that the player start is the
        settings' OriginGeopoint when it is given."""
        lat0, lon0 = self._geo_ref()
        r = 6378137.0
        scale = math.cos(math.radians(lat0))
        mx = scale * math.radians(lon0) * r + x
        my = scale * r * math.log(math.tan(math.radians(90.0 + lat0) / 2.0)) + y
        lon = mx * 180.0 / (math.pi * r * scale)
        lat = 360.0 * math.atan(math.exp(my / (r * scale))) / math.pi - 90.0
        return self.geo_shift((lat, lon, z))

    def geo_shift(self, g, inverse=False):
        s = self.load_settings()
        if s.origin_geopoint is None:
            return g
        sx, sy, sz = self.start()
        o = s.origin_geopoint
        saved, s.origin_geopoint = s.origin_geopoint, None
        try:
            base = self.enu_to_geo(sx, sy, sz)
        finally:
            s.origin_geopoint = saved
        k = -1 if inverse else 1
        return (g[0] + k * (o[0] - base[0]), g[1] + k * (o[1] - base[1]), g[2] + k * (o[2] - base[2]))

    def geo_to_enu(self, lat, lon, alt):
        lat, lon, alt = self.geo_shift((lat, lon, alt), inverse=True)
        lat0, lon0 = self._geo_ref()
        r = 6378137.0
        scale = math.cos(math.radians(lat0))
        mx0 = scale * math.radians(lon0) * r
        my0 = scale * r * math.log(math.tan(math.radians(90.0 + lat0) / 2.0))
        mx = scale * math.radians(lon) * r
        my = scale * r * math.log(math.tan(math.radians(90.0 + lat) / 2.0))
        return mx - mx0, my - my0, alt


_shared_by_session = weakref.WeakKeyDictionary()
_shared_lock = threading.Lock()


def _shared(client):
    with _shared_lock:
        s = _shared_by_session.get(client)
        if s is None:
            s = _Shared(client)
            _shared_by_session[client] = s
        return s


def _dur(d):
    return d is not None and d > 0


def _plot_life(duration, is_persistent, dt):
    """A plotted shape's life_time (s) as Unreal's DrawDebug* gives it (GetDebugLineLifeTime):
    persistent: until flushed (0), whatever the duration; else the duration when > 0; else one
    frame (Unreal's non-persistent line batcher): shown in the frame of the tick that carries
    it and gone from the next (a life of one step would end before its frame is drawn)."""
    if is_persistent:
        return 0.0
    if duration is not None and duration > 0:
        return float(duration)
    return 1.5 * dt


# --------------------------------------------------------------------------- VehicleClient
class VehicleClient:
    """AirSim's VehicleClient: the calls every vehicle has."""

    def __new__(cls, *args, **kwargs):
        # SimMode "Car": AirSim's vehicles are cars, and a VehicleClient's calls address them
        # (a CarClient, whose VehicleClient calls are the car's).
        if cls is VehicleClient and settings_mod.load().sim_mode == 'Car':
            cls = CarClient
        return super().__new__(cls)

    def __init__(self, ip='', port=41451, timeout_value=3600):
        self._ip, self._port, self._timeout = ip, port, timeout_value
        self._client = lockstep.session(timeout=float(os.environ.get('LOCKSTEP_CONNECT_TIMEOUT', '10')))
        self._s = _shared(self._client)
        self._mc = self._s.mc
        self._s.load_settings()   # a bad settings.json fails here, naming the key, as AirSim fails to start

    # --- the vehicle a call addresses: a drone here, a car in a CarClient ---
    def _vehicle(self, vehicle_name):
        """The actor id of the vehicle named `vehicle_name` ('' AirSim's default vehicle)."""
        return self._s.actor(vehicle_name)

    def _vehicle_pose(self, vehicle_name):
        """((x, y, z), (w, x, y, z)): the vehicle's pose, NED from its start (its home)."""
        self._s.actor(vehicle_name)
        return self._mc.pose(vehicle_name)

    def _set_vehicle_pose(self, pos, q, vehicle_name):
        self._mc.set_pose(pos, q, vehicle_name)

    def _vehicle_home(self, actor):
        """The vehicle's start (world ENU x, y, z); None before it has a state."""
        d = self._client.drone_state(actor)
        return tuple(d['home'][:3]) if d else None

    def _vehicle_setting(self, vehicle_name):
        return self._s.vehicle_setting(vehicle_name)

    def _default_cameras(self, actor):
        """AirSim's cameras of the vehicle's pawn: name -> mount (x, y, z m FRD; roll, pitch, yaw deg)."""
        return _DEFAULT_CAMERAS

    # --- connection ---
    def reset(self):
        """AirSim's reset: every vehicle back to its start (its settings pose), at rest: a
        drone disarmed and without API control, its command cancelled; an AirSim car with
        CarControls() applied, its API control kept (CarPawnApi); the rest of the world
        (other cars, walkers, lights) goes on."""
        s = self._s
        with s.lock:
            s.ensure_vehicles()
            actors = []
            for a in s.drones():
                name = a['attributes'].get('role_name') or 'Drone%d' % a['id']
                try:
                    self._mc.enable_api_control(True, name)
                    self._mc.cancel(name)
                    k = (0.0, 0.0, 0.0)
                    home = self._client.drone_state(a['id'])['home']
                    q = geo.enu_to_ned_quat(home[3:7])
                    self._mc.set_kinematics(k, (q.w_val, q.x_val, q.y_val, q.z_val), k, k, name)
                    self._mc.arm_disarm(False, name)
                finally:
                    self._mc.enable_api_control(False, name)
                actors.append(a['id'])
            for a in s.airsim_cars():
                s.reset_car(a)
            s.manual.clear()
            s.rc.clear()
            s.cameras.clear()
            s.wait_frames(2)
            s.wait_at_rest(actors, 5.0)

    def ping(self):
        return True

    def getClientVersion(self):
        return 1

    def getServerVersion(self):
        return 1

    def getMinRequiredServerVersion(self):
        return 1

    def getMinRequiredClientVersion(self):
        return 1

    def confirmConnection(self):
        print('Connected!' if self.ping() else 'Ping returned false!')
        print('Client Ver:%d (Min Req: %d), Server Ver:%d (Min Req: %d)' % (
            self.getClientVersion(), self.getMinRequiredClientVersion(), self.getServerVersion(),
            self.getMinRequiredServerVersion()))
        info = self._client.world_info()
        print('(Lockstep: DDS domain %d, map %s, run %d)' % (self._client.domain, info['map_name'], info['run']))
        print('')

    # --- API control and arming: the vehicle's, whichever client asks ---
    def enableApiControl(self, is_enabled, vehicle_name=''):
        self._s.actor(vehicle_name)
        self._mc.enable_api_control(bool(is_enabled), vehicle_name)

    def isApiControlEnabled(self, vehicle_name=''):
        self._s.actor(vehicle_name)
        return self._mc.is_api_control_enabled(vehicle_name)

    def armDisarm(self, arm, vehicle_name=''):
        """As AirSim's simple_flight: without API control the vehicle is not armed (nor
        disarmed) and the call returns False; nor is a vehicle that is not landed disarmed."""
        self._s.actor(vehicle_name)
        if not self._mc.is_api_control_enabled(vehicle_name):
            log.warning("airsim: vehicle '%s' cannot be %s via API because API has not been given control",
                        vehicle_name or 'default', 'armed' if arm else 'disarmed')
            return False
        if not arm and not self._mc.state(vehicle_name)['landed']:
            log.warning("airsim: vehicle '%s' cannot be disarmed because it is not landed", vehicle_name or 'default')
            return False
        return self._mc.arm_disarm(bool(arm), vehicle_name)

    # --- the clock ---
    def simPause(self, is_paused):
        """Paused = synchronous mode: the clock stops until simContinueFor* ticks it."""
        sync = self._s.synchronous()
        if is_paused and not sync:
            self._client.apply_settings({'synchronous_mode': True})
        elif not is_paused and sync:
            self._client.apply_settings({'synchronous_mode': False})

    def simIsPause(self):
        return self._s.synchronous()

    def simContinueForTime(self, seconds):
        dt = self._client.world_info()['settings']['fixed_delta_seconds']
        self.simContinueForFrames(max(1, int(round(seconds / dt))))

    def simContinueForFrames(self, frames):
        """Runs `frames` ticks and leaves the simulation paused, as AirSim."""
        if not self._s.synchronous():
            self.simPause(True)
        for _ in range(int(frames)):
            self._client.tick()

    def simGetTime(self):
        return self._s.sim_time()

    def getHomeGeoPoint(self, vehicle_name=''):
        """The vehicle's home (its start) through the map's geo-reference."""
        a = self._vehicle(vehicle_name)
        h = self._vehicle_home(a)
        if h is None:
            _unsupported('getHomeGeoPoint(%r)' % vehicle_name, 'the vehicle has no state yet')
        return GeoPoint(*self._s.enu_to_geo(*h))

    # --- environment ---
    def simSetLightIntensity(self, light_name, intensity):
        _unsupported('simSetLightIntensity', 'the towns have no named lights (the sun is the weather)')

    def simSwapTextures(self, tags, tex_id=0, component_id=0, material_id=0):
        _unsupported('simSwapTextures', 'the render service has no texture sets to swap')

    def simSetObjectMaterial(self, object_name, material_name, component_id=0):
        _unsupported('simSetObjectMaterial', 'the render service has no Unreal materials')

    def simSetObjectMaterialFromTexture(self, object_name, texture_path, component_id=0):
        _unsupported('simSetObjectMaterialFromTexture', 'the render service has no Unreal materials')

    def simSetTimeOfDay(self, is_enabled, start_datetime='', is_start_datetime_dst=False, celestial_clock_speed=1,
                        update_interval_secs=60, move_sun=True):
        """The sun's position for a date and time at the origin geo point (CARLA's sun angles)."""
        self._s.time_of_day = bool(is_enabled)
        if not is_enabled or not move_sun:
            return
        import datetime
        when = datetime.datetime.strptime(start_datetime, '%Y-%m-%d %H:%M:%S') if start_datetime else \
            datetime.datetime(2020, 6, 21, 12, 0, 0)
        if is_start_datetime_dst:
            when -= datetime.timedelta(hours=1)
        sx, sy, sz = self._s.start()
        lat, lon, _ = self._s.enu_to_geo(sx, sy, sz)
        alt, azi = _sun_position(when, lat, lon)
        self._client.set_weather({'sun_altitude_angle': alt, 'sun_azimuth_angle': azi})

    def simEnableWeather(self, enable):
        self._s.weather_enabled = bool(enable)

    def simSetWeatherParameter(self, param, val):
        """AirSim's weather (0..1) on CARLA's WeatherParameters (0..100)."""
        fields = {WeatherParameter.Rain: 'precipitation', WeatherParameter.Roadwetness: 'wetness',
                  WeatherParameter.Fog: 'fog_density', WeatherParameter.Dust: 'dust_storm'}
        if param == WeatherParameter.Enabled:
            self._s.weather_enabled = bool(val)
            return
        if param not in fields:
            _unsupported('simSetWeatherParameter(%d)' % param, 'snow and leaves are not rendered')
        self._client.set_weather({fields[param]: float(min(max(val, 0.0), 1.0)) * 100.0})

    # --- images ---
    def _camera(self, vehicle_name, camera_name, call):
        """(actor, canonical camera name, mount (x y z roll pitch yaw, FRD), fov or None, capture settings)."""
        a = self._vehicle(vehicle_name)
        v = self._vehicle_setting(vehicle_name)
        name = str(camera_name)
        cams = dict(self._default_cameras(a))
        name = _CAMERA_ALIASES.get(name, name)
        cs = v.cameras.get(name) if v else None
        if name not in cams and cs is None:
            known = sorted(set(cams) | set(v.cameras if v else ()) | set(_CAMERA_ALIASES) - {''})
            raise lockstep.ClientError("%s: vehicle '%s' has no camera '%s' (cameras: %s)" % (
                call, vehicle_name or 'default', camera_name, ', '.join(known)))
        mount = list(cams.get(name, (0.0,) * 6))
        if cs is not None:
            for i, k in enumerate(('x', 'y', 'z', 'roll', 'pitch', 'yaw')):
                if getattr(cs, k) is not None:
                    mount[i] = getattr(cs, k)
        over = self._s.cameras.get((a, name), {})
        if 'pose' in over:
            mount = list(over['pose'])
        return a, name, tuple(mount), over.get('fov'), cs

    def _capture(self, cs, image_type, fov_override):
        defaults = self._s.load_settings().camera_defaults
        if cs is not None:
            c = cs.capture_for(image_type, defaults)
        else:
            c = defaults.capture_for(image_type)
        fov = fov_override if fov_override is not None else c.fov_degrees
        return c.width, c.height, fov

    def _camera_world(self, actor, vehicle_name, mount):
        """The camera's pose in the vehicle's NED frame (from its home)."""
        p, q = self._vehicle_pose(vehicle_name)
        mq = geo.frd_euler_deg_to_quat(mount[3], mount[4], mount[5])
        return geo.compose(_v(p), _q(q), Vector3r(*mount[:3]), mq)

    def simGetImages(self, requests, vehicle_name='', external=False):
        if external:
            _unsupported('simGetImages(external=True)', 'external cameras are spawned with the CARLA API')
        return [self._image(r, vehicle_name, 'simGetImages') for r in requests]

    def simGetImage(self, camera_name, image_type, vehicle_name='', external=False):
        if external:
            _unsupported('simGetImage(external=True)', 'external cameras are spawned with the CARLA API')
        r = self._image(ImageRequest(camera_name, image_type, False, True), vehicle_name, 'simGetImage')
        return r.image_data_uint8

    def _image(self, r, vehicle_name, call):
        it = int(r.image_type)
        if it not in _IMAGE_TYPE_NAMES and it not in (ImageType.OpticalFlow, ImageType.OpticalFlowVis):
            raise lockstep.ClientError('%s: image_type %r is not one of AirSim\'s (0..9)' % (call, r.image_type))
        a, cam, mount, fov_over, cs = self._camera(vehicle_name, r.camera_name, call)
        w, h, fov = self._capture(cs, it, fov_over)
        if w * h > 7680 * 4320:
            _unsupported('%s(camera %r, %dx%d)' % (call, cam, w, h), 'cameras are at most 7680x4320 (8K) pixels')
        attrs = {'image_size_x': str(w), 'image_size_y': str(h), 'fov': repr(float(fov)),
                 'role_name': 'airsim_%s_%d' % (cam, it)}
        if it in _IMAGE_TYPE_NAMES:
            bp = 'sensor.camera.airsim'
            attrs['image_type'] = _IMAGE_TYPE_NAMES[it]
        else:
            bp = 'sensor.camera.optical_flow'
        pose = geo.frd_mount_to_flu(*mount)
        s = self._s.sensors.latest(call, ('camera', a, cam, it), bp, attrs, pose, a)
        resp = ImageResponse()
        resp.camera_name = str(r.camera_name)
        resp.image_type = it
        resp.time_stamp = int(round(s.sim_time * 1e9))
        resp.frame = s.frame
        resp.pixels_as_float = bool(r.pixels_as_float)
        resp.compress = bool(r.compress)
        try:
            cp, cq = self._camera_world(a, vehicle_name, mount)
            resp.camera_position, resp.camera_orientation = cp, cq
        except lockstep.ClientError:
            pass
        arr = np.asarray(s.array())
        resp.height, resp.width = int(arr.shape[0]), int(arr.shape[1])
        if it in (ImageType.Segmentation, ImageType.Infrared):
            # AirSim's: the object id's palette colour (Segmentation) or the id as grey (Infrared);
            # a hidden object (-1) is black.
            ids = self._object_ids(arr)
            if it == ImageType.Segmentation:
                lut = np.asarray([c[::-1] for c in seg.PALETTE] + [(0, 0, 0)], np.uint8)   # BGR; -1 -> black
                arr = lut[np.where(ids < 0, 256, ids)]
            else:
                arr = np.repeat(np.clip(ids, 0, 255).astype(np.uint8)[..., None], 3, axis=2)
        if it == ImageType.SurfaceNormals and arr.ndim == 3:
            arr = _airsim_normals(arr, resp.camera_orientation)
        _encode(resp, it, arr)
        return resp

    def simGetPresetLensSettings(self, camera_name, vehicle_name='', external=False):
        _unsupported('simGetPresetLensSettings', "the cameras are pinhole cameras (no CinemAirSim lens)")

    def simGetLensSettings(self, camera_name, vehicle_name='', external=False):
        _unsupported('simGetLensSettings', "the cameras are pinhole cameras (no CinemAirSim lens)")

    def simSetPresetLensSettings(self, preset_lens_settings, camera_name, vehicle_name='', external=False):
        _unsupported('simSetPresetLensSettings', "the cameras are pinhole cameras (no CinemAirSim lens)")

    def simGetPresetFilmbackSettings(self, camera_name, vehicle_name='', external=False):
        _unsupported('simGetPresetFilmbackSettings', "the cameras are pinhole cameras (no CinemAirSim filmback)")

    def simSetPresetFilmbackSettings(self, preset_filmback_settings, camera_name, vehicle_name='', external=False):
        _unsupported('simSetPresetFilmbackSettings', "the cameras are pinhole cameras (no CinemAirSim filmback)")

    def simGetFilmbackSettings(self, camera_name, vehicle_name='', external=False):
        _unsupported('simGetFilmbackSettings', "the cameras are pinhole cameras (no CinemAirSim filmback)")

    def simSetFilmbackSettings(self, sensor_width, sensor_height, camera_name, vehicle_name='', external=False):
        _unsupported('simSetFilmbackSettings', "the cameras are pinhole cameras (no CinemAirSim filmback)")

    def simGetFocalLength(self, camera_name, vehicle_name='', external=False):
        _unsupported('simGetFocalLength', "the cameras are pinhole cameras (field of view only; simGetCameraInfo)")

    def simSetFocalLength(self, focal_length, camera_name, vehicle_name='', external=False):
        _unsupported('simSetFocalLength', "the cameras are pinhole cameras (set the field of view: simSetCameraFov)")

    def simEnableManualFocus(self, enable, camera_name, vehicle_name='', external=False):
        _unsupported('simEnableManualFocus', "the cameras are pinhole cameras (everything is in focus)")

    def simGetFocusDistance(self, camera_name, vehicle_name='', external=False):
        _unsupported('simGetFocusDistance', "the cameras are pinhole cameras (everything is in focus)")

    def simSetFocusDistance(self, focus_distance, camera_name, vehicle_name='', external=False):
        _unsupported('simSetFocusDistance', "the cameras are pinhole cameras (everything is in focus)")

    def simGetFocusAperture(self, camera_name, vehicle_name='', external=False):
        _unsupported('simGetFocusAperture', "the cameras are pinhole cameras (everything is in focus)")

    def simSetFocusAperture(self, focus_aperture, camera_name, vehicle_name='', external=False):
        _unsupported('simSetFocusAperture', "the cameras are pinhole cameras (everything is in focus)")

    def simEnableFocusPlane(self, enable, camera_name, vehicle_name='', external=False):
        _unsupported('simEnableFocusPlane', "the cameras are pinhole cameras (everything is in focus)")

    def simGetCurrentFieldOfView(self, camera_name, vehicle_name='', external=False):
        return '%.2f' % self.simGetCameraInfo(camera_name, vehicle_name, external).fov

    def simGetCameraInfo(self, camera_name, vehicle_name='', external=False):
        """Pose (the vehicle's NED frame), horizontal FOV (deg) and AirSim's projection matrix."""
        if external:
            _unsupported('simGetCameraInfo(external=True)', 'external cameras are spawned with the CARLA API')
        a, cam, mount, fov_over, cs = self._camera(vehicle_name, camera_name, 'simGetCameraInfo')
        w, h, fov = self._capture(cs, ImageType.Scene, fov_over)
        info = CameraInfo()
        try:
            p, q = self._camera_world(a, vehicle_name, mount)
            info.pose = Pose(p, q)
        except lockstep.ClientError:
            pass
        info.fov = float(fov)
        info.proj_mat = ProjectionMatrix(_projection_matrix(fov, w, h))
        return info

    def simGetDistortionParams(self, camera_name, vehicle_name='', external=False):
        self._camera(vehicle_name, camera_name, 'simGetDistortionParams')
        return [0.0, 0.0, 0.0, 0.0, 0.0]   # K1 K2 K3 P1 P2: the cameras have no lens distortion

    def simSetDistortionParams(self, camera_name, distortion_params, vehicle_name='', external=False):
        for k, v in distortion_params.items():
            self.simSetDistortionParam(camera_name, k, v, vehicle_name, external)

    def simSetDistortionParam(self, camera_name, param_name, value, vehicle_name='', external=False):
        if value != 0:
            _unsupported('simSetDistortionParam(%s=%r)' % (param_name, value), 'the cameras have no lens distortion')

    def simSetCameraPose(self, camera_name, pose, vehicle_name='', external=False):
        """The camera's mount on the vehicle (NED/FRD, m); the next image comes from there."""
        if external:
            _unsupported('simSetCameraPose(external=True)', 'external cameras are spawned with the CARLA API')
        a, cam, mount, _, _ = self._camera(vehicle_name, camera_name, 'simSetCameraPose')
        p, o = pose.position, pose.orientation
        new = list(mount)
        if not p.containsNan():
            new[0:3] = [p.x_val, p.y_val, p.z_val]
        if not o.containsNan():
            pitch, roll, yaw = to_eularian_angles(o)
            new[3:6] = [math.degrees(roll), math.degrees(pitch), math.degrees(yaw)]
        self._s.cameras.setdefault((a, cam), {})['pose'] = tuple(new)

    def simSetCameraOrientation(self, camera_name, orientation, vehicle_name='', external=False):
        log.warning('`simSetCameraOrientation` API has been upgraded to `simSetCameraPose`. Please update your code.')
        self.simSetCameraPose(camera_name, Pose(Vector3r.nanVector3r(), orientation), vehicle_name, external)

    def simSetCameraFov(self, camera_name, fov_degrees, vehicle_name='', external=False):
        if external:
            _unsupported('simSetCameraFov(external=True)', 'external cameras are spawned with the CARLA API')
        if not 0 < float(fov_degrees) < 180:
            raise lockstep.ClientError('simSetCameraFov: fov_degrees must be in (0, 180), got %r' % (fov_degrees,))
        a, cam, _, _, _ = self._camera(vehicle_name, camera_name, 'simSetCameraFov')
        self._s.cameras.setdefault((a, cam), {})['fov'] = float(fov_degrees)

    # --- line of sight and the world ---
    def _ray_clear(self, call, p1, p2):
        """Whether the segment p1 -> p2 (world ENU) is free of the town: a distance sensor's
        ray from p1 towards p2 (needs sensors)."""
        d = [b - a for a, b in zip(p1, p2)]
        length = math.sqrt(sum(x * x for x in d))
        if length < 1e-6:
            return True
        yaw = math.atan2(d[1], d[0])
        pitch = -math.asin(max(-1.0, min(1.0, d[2] / length)))
        cy, sy, cp, sp = math.cos(yaw / 2), math.sin(yaw / 2), math.cos(pitch / 2), math.sin(pitch / 2)
        q = (cy * cp, -sy * sp, cy * sp, sy * cp)
        reach = min(length, 9999.0)
        attrs = {'min_distance': '0', 'max_distance': repr(reach), 'noise_stddev': '0', 'role_name': 'airsim_los'}
        key = ('los', tuple(round(v, 6) for v in p1 + p2))
        frame = self._client.frame()
        s = self._s.sensors.latest(call, key, 'sensor.other.distance', attrs, tuple(p1) + q, 0, newer_than=frame)
        dist = s.fields()['distance']
        self._s.sensors.drop(lambda k: k == key)
        return not (0 <= dist < reach - 1e-3)

    def simTestLineOfSightToPoint(self, point, vehicle_name=''):
        a = self._vehicle(vehicle_name)
        t = self._client.state(a)['transform']
        return self._ray_clear('simTestLineOfSightToPoint', tuple(t[:3]),
                               self._s.geo_to_enu(point.latitude, point.longitude, point.altitude))

    def simTestLineOfSightBetweenPoints(self, point1, point2):
        return self._ray_clear('simTestLineOfSightBetweenPoints',
                               self._s.geo_to_enu(point1.latitude, point1.longitude, point1.altitude),
                               self._s.geo_to_enu(point2.latitude, point2.longitude, point2.altitude))

    def simGetWorldExtents(self):
        """[min, max] GeoPoints of the map's bounds (ground to 200 m)."""
        x0, y0, x1, y1 = self._client.map().bounds()
        return [GeoPoint(*self._s.enu_to_geo(x0, y0, 0.0)), GeoPoint(*self._s.enu_to_geo(x1, y1, 200.0))]

    def simRunConsoleCommand(self, command):
        _unsupported('simRunConsoleCommand', 'there is no Unreal console')

    def simGetMeshPositionVertexBuffers(self):
        _unsupported('simGetMeshPositionVertexBuffers', "the town meshes are the services' (lockstep map meshes)")

    # --- vehicle pose and collisions ---
    def simGetCollisionInfo(self, vehicle_name=''):
        self._s.actor(vehicle_name)
        return self._collision(self._mc.state(vehicle_name))

    def _collision(self, s):
        has, normal, impact, pos, depth, obj_id, obj_name, frame = s['collision']
        out = CollisionInfo()
        out.has_collided = bool(has)
        out.normal, out.impact_point, out.position = _v(normal), _v(impact), _v(pos)
        out.penetration_depth = depth
        out.object_id = int(obj_id) if obj_name else -1
        out.object_name = obj_name
        dt = self._client.world_info()['settings']['fixed_delta_seconds']
        out.time_stamp = int(round(frame * dt * 1e9)) if frame else 0   # ns of simulation time, as AirSim
        return out

    def simSetVehiclePose(self, pose, ignore_collision, vehicle_name=''):
        """Teleports; NaN components keep the current value, as AirSim; the quaternion is normalised."""
        cur_p, cur_q = self._vehicle_pose(vehicle_name)
        p, o = pose.position, pose.orientation
        pos = tuple(c if math.isnan(n) else n for n, c in zip((p.x_val, p.y_val, p.z_val), cur_p))
        if o.containsNan():
            q = cur_q
        else:
            n = o.get_length()
            if n < 1e-9:
                raise lockstep.ClientError('simSetVehiclePose: the orientation is a zero quaternion')
            q = (o.w_val / n, o.x_val / n, o.y_val / n, o.z_val / n)
        self._set_vehicle_pose(pos, q, vehicle_name)

    def simGetVehiclePose(self, vehicle_name=''):
        p, q = self._vehicle_pose(vehicle_name)
        return Pose(_v(p), _q(q))

    def simSetTraceLine(self, color_rgba, thickness=1.0, vehicle_name=''):
        """The trace's colour and thickness (kept; the trace is drawn by no viewport)."""
        if len(color_rgba) != 4 or any(not 0 <= float(c) <= 1 for c in color_rgba):
            raise lockstep.ClientError('simSetTraceLine: color_rgba is 4 values in [0, 1], got %r' % (color_rgba,))
        a = self._vehicle(vehicle_name)
        self._s.trace[a] = (tuple(float(c) for c in color_rgba), float(thickness))

    # --- scene objects: the run's actors by name ---
    def _objects(self):
        """name -> actor id: drones by vehicle name, other actors by role_name or '<kind>_<id>'."""
        out = {}
        for a in self._client.actors():
            role = a['attributes'].get('role_name', '')
            if a['kind'] == 'drone':
                out[role or 'Drone%d' % a['id']] = a['id']
            elif a['kind'] != 'sensor':
                out[role or '%s_%d' % (a['kind'], a['id'])] = a['id']
                out.setdefault('%s_%d' % (a['kind'], a['id']), a['id'])
        for name, actor in self._s.spawned_objects.items():
            out[name] = actor
        return out

    def _statics(self):
        """The town's static objects (its meshes as the services build them: ground, road_<id>,
        sidewalk_<id>, building_<i>_<design>, tree_<i>, <prop>_<i>_pole, ...): name -> (mesh
        instance id, semantic tag, centre world ENU)."""
        s = self._s
        with s.lock:
            s.begin_run()
            if s.statics is None:
                try:
                    objs = self._client.scene_objects()
                except lockstep.ClientError:
                    objs = []
                s.statics = {n: (inst, tag, tuple((a + b) / 2.0 for a, b in zip(lo, hi))) for n, inst, tag, lo, hi in objs}
                s.static_names = {inst: n for n, (inst, _, _) in s.statics.items()}
            return s.statics

    def simListSceneObjects(self, name_regex='.*'):
        """The run's actors and the town's static objects whose names match (AirSim: the level's actors)."""
        rx = re.compile(name_regex)
        names = set(self._objects()) | set(self._statics())
        return sorted(n for n in names if rx.fullmatch(n))

    def _object_home(self):
        sx, sy, sz = self._s.start()
        return (sx, sy, sz)

    def simGetObjectPose(self, object_name):
        """World NED pose (from the player start) of an actor; a nan Pose when there is none, as AirSim."""
        actor = self._objects().get(object_name)
        st = self._client.state(actor) if actor is not None else None
        if st is None:
            town = self._statics().get(object_name)
            if town is not None:   # a static object: the centre of its bounds, unrotated
                return Pose(_v(geo.enu_to_ned_pos(town[2], self._object_home())), Quaternionr())
            return Pose.nanPose()
        t = st['transform']
        return Pose(_v(geo.enu_to_ned_pos(t[:3], self._object_home())), geo.enu_to_ned_quat(t[3:7]))

    def simSetObjectPose(self, object_name, pose, teleport=True):
        actor = self._objects().get(object_name)
        if actor is None:
            return False
        p, o = pose.position, pose.orientation
        enu = geo.ned_to_enu_pos((p.x_val, p.y_val, p.z_val), self._object_home())
        q = geo.ned_to_enu_quat(o)
        reply = self._client.submit({'type': 'set_transform', 'actor': actor, 'transform': tuple(enu) + tuple(q)}, False)
        return bool(reply[0])

    def simGetObjectScale(self, object_name):
        if object_name not in self._objects():
            return Vector3r.nanVector3r()
        return Vector3r(1.0, 1.0, 1.0)

    def simSetObjectScale(self, object_name, scale_vector):
        _unsupported('simSetObjectScale', "an actor's size is its blueprint's")

    def simLoadLevel(self, level_name):
        """Loads the town named `level_name` (a new run), as carla's load_world."""
        import carla
        carla.Client().load_world(level_name)
        return True

    def simListAssets(self):
        """The blueprints simSpawnObject can spawn ('static.prop.*' of the running services)."""
        return sorted(d['id'] for d in self._client.blueprints(1.0) if d['id'].startswith('static.'))

    def simSpawnObject(self, object_name, asset_name, pose, scale, physics_enabled=False, is_blueprint=False):
        if asset_name not in self.simListAssets():
            raise lockstep.ClientError("simSpawnObject: no asset '%s' (simListAssets: the static.prop.* blueprints)"
                                       % asset_name)
        if scale is not None and any(abs(v - 1.0) > 1e-9 for v in (scale.x_val, scale.y_val, scale.z_val)):
            _unsupported('simSpawnObject(scale != 1)', "a prop's size is its blueprint's")
        p = pose.position
        enu = geo.ned_to_enu_pos((p.x_val, p.y_val, p.z_val), self._object_home())
        name = object_name
        objs = self._objects()
        i = 1
        while name in objs:
            name = '%s_%d' % (object_name, i)
            i += 1
        actor = self._client.spawn(asset_name, tuple(enu) + tuple(geo.ned_to_enu_quat(pose.orientation)),
                                   {'role_name': name})
        self._s.spawned_objects[name] = actor
        return name

    def simDestroyObject(self, object_name):
        actor = self._objects().get(object_name)
        if actor is None:
            return False
        self._client.destroy(actor)
        self._s.spawned_objects.pop(object_name, None)
        return True

    # --- segmentation and detections ---
    def simSetSegmentationObjectID(self, mesh_name, object_id, is_name_regex=False):
        """AirSim's: the object id (0..255; -1 hides the object) of every object named
        `mesh_name` (a regular expression matched case-insensitively when is_name_regex);
        True when one matched. The Segmentation and Infrared images show it from the next image."""
        if not -1 <= int(object_id) <= 255:
            raise lockstep.ClientError('simSetSegmentationObjectID: object_id must be in -1..255, got %r' % (object_id,))
        names = set(self._objects()) | set(self._statics())
        if is_name_regex:
            rx = re.compile(mesh_name, re.IGNORECASE)
            hit = [n for n in names if rx.fullmatch(n)]
        else:
            hit = [n for n in names if n == mesh_name]
        for n in hit:
            self._s.seg_ids[n] = int(object_id)
        return bool(hit)

    def simGetSegmentationObjectID(self, mesh_name):
        """The object's id (AirSim's default from its name until set); -1 when there is no such object."""
        if mesh_name in self._s.seg_ids:
            return self._s.seg_ids[mesh_name]
        if mesh_name in self._objects() or mesh_name in self._statics():
            return seg.default_object_id(mesh_name)
        return -1

    def _object_ids(self, arr):
        """AirSim object ids (-1 hidden) of an instance image (B instance high, G low, R tag):
        a static mesh is instance 0x8000 + its mesh id, an actor its actor id."""
        inst = arr[..., 1].astype(np.int32) | (arr[..., 0].astype(np.int32) << 8)
        key = np.where(inst > 0, inst * 256, arr[..., 2].astype(np.int32))
        uniq, inverse = np.unique(key, return_inverse=True)
        self._statics()   # fills static_names
        actors = {}
        for name, actor in self._objects().items():
            actors.setdefault(actor, name)   # a drone's vehicle name, else role_name, else <kind>_<id>
        ids = []
        for k in uniq.tolist():
            i = k // 256
            if i >= 0x8000:
                name = self._s.static_names.get(i - 0x8000, '')
            elif i > 0:
                name = actors.get(i, '')
            else:
                name = 'Sky' if k == 11 else ''   # no mesh: the sky, or nothing
            if name in self._s.seg_ids:
                ids.append(self._s.seg_ids[name])
            else:
                ids.append(seg.default_object_id(name) if name else 0)
        return np.asarray(ids, np.int32)[inverse].reshape(inst.shape)

    def _detection(self, camera_name, image_type, vehicle_name):
        a, cam, _, _, _ = self._camera(vehicle_name, camera_name, 'simGetDetections')
        return self._s.detection.setdefault((a, cam, int(image_type)), {'filters': [], 'radius_cm': 20000.0})

    def simAddDetectionFilterMeshName(self, camera_name, image_type, mesh_name, vehicle_name='', external=False):
        self._detection(camera_name, image_type, vehicle_name)['filters'].append(mesh_name)

    def simSetDetectionFilterRadius(self, camera_name, image_type, radius_cm, vehicle_name='', external=False):
        self._detection(camera_name, image_type, vehicle_name)['radius_cm'] = float(radius_cm)

    def simClearDetectionMeshNames(self, camera_name, image_type, vehicle_name='', external=False):
        self._detection(camera_name, image_type, vehicle_name)['filters'] = []

    def simGetDetections(self, camera_name, image_type, vehicle_name='', external=False):
        """The actors matching the camera's filters (AirSim's wildcards) within its radius
        and its view: box2D from their 3D boxes projected with the camera's pinhole."""
        import fnmatch
        d = self._detection(camera_name, image_type, vehicle_name)
        if not d['filters']:
            return []
        a, cam, mount, fov_over, cs = self._camera(vehicle_name, camera_name, 'simGetDetections')
        w, h, fov = self._capture(cs, int(image_type), fov_over)
        cp, cq = self._camera_world(a, vehicle_name, mount)
        home = self._vehicle_home(a)
        f = w / 2.0 / math.tan(math.radians(fov) / 2)
        out = []
        for name, actor in sorted(self._objects().items()):
            if actor == a or not any(fnmatch.fnmatch(name, flt) for flt in d['filters']):
                continue
            st = self._client.state(actor)
            if st is None:
                continue
            t, ext = st['transform'], st['half_extents']
            rel = geo.enu_to_ned_pos(t[:3], home)
            dist = Vector3r(*rel) - cp
            if dist.get_length() * 100 > d['radius_cm']:
                continue
            corners = []
            for sx in (-1, 1):
                for sy in (-1, 1):
                    for sz in (-1, 1):
                        corners.append(_v(geo.enu_to_ned_pos((t[0] + sx * ext[0], t[1] + sy * ext[1],
                                                              t[2] + sz * ext[2]), home)))
            px = []
            inv = cq.inverse()
            for c in corners:
                v = _rotate_vector(inv, c - cp)
                if v.x_val > 0.05:
                    px.append((w / 2 + f * v.y_val / v.x_val, h / 2 + f * v.z_val / v.x_val))
            if not px:
                continue
            xs = [min(max(p[0], 0), w - 1) for p in px]
            ys = [min(max(p[1], 0), h - 1) for p in px]
            if max(xs) <= min(xs) or max(ys) <= min(ys):
                continue
            info = DetectionInfo()
            info.name = name
            info.geo_point = GeoPoint(*self._s.enu_to_geo(*t[:3]))
            info.box2D = Box2D()
            info.box2D.min, info.box2D.max = Vector2r(min(xs), min(ys)), Vector2r(max(xs), max(ys))
            info.box3D = Box3D()
            rel_c = _rotate_vector(inv, _v(rel) - cp)
            info.box3D.min = rel_c - Vector3r(*ext)
            info.box3D.max = rel_c + Vector3r(*ext)
            info.relative_pose = Pose(rel_c, inv * geo.enu_to_ned_quat(t[3:7]))
            out.append(info)
        return out

    def simPrintLogMessage(self, message, message_param='', severity=0):
        print('%s %s' % (message, message_param))

    # --- kinematics and environment ---
    def simGetGroundTruthKinematics(self, vehicle_name=''):
        self._s.actor(vehicle_name)
        return _kinematics(self._mc.state(vehicle_name))

    def simSetKinematics(self, state, ignore_collision, vehicle_name=''):
        """Pose, linear velocity (world NED) and angular velocity (body FRD) at once;
        accelerations are ignored (air_sim derives them from the next step)."""
        self._s.actor(vehicle_name)
        o = state.orientation

        def t(v):
            return (v.x_val, v.y_val, v.z_val)
        self._mc.set_kinematics(t(state.position), (o.w_val, o.x_val, o.y_val, o.z_val), t(state.linear_velocity),
                                t(state.angular_velocity), vehicle_name)

    def simGetGroundTruthEnvironment(self, vehicle_name=''):
        """The standard atmosphere at the vehicle's altitude (AirSim's EnvironmentState)."""
        a = self._vehicle(vehicle_name)
        p, _ = self._vehicle_pose(vehicle_name)
        t = self._client.state(a)['transform']
        e = EnvironmentState()
        e.position = _v(p)
        e.geo_point = GeoPoint(*self._s.enu_to_geo(*t[:3]))
        alt = e.geo_point.altitude
        temp = 288.15 - 0.0065 * alt
        e.temperature = temp
        e.air_pressure = 101325.0 * (temp / 288.15) ** 5.2558797
        e.air_density = e.air_pressure / (287.05287 * temp)
        e.gravity = Vector3r(0.0, 0.0, 9.80665)
        return e

    def simCreateVoxelGrid(self, position, x, y, z, res, of):
        _unsupported('simCreateVoxelGrid', 'no occupancy query of the town over the wire')

    # --- sensors: settings.json's, else AirSim's defaults, spawned on first use ---
    def _sensor_setting(self, vehicle_name, kind, name, call):
        v = self._vehicle_setting(vehicle_name)
        declared = [s for s in (v.sensors.values() if v else []) if s.kind == kind and s.enabled]
        if name:
            for s in declared:
                if s.name == name:
                    return s
            if declared or (v and v.sensors):
                raise lockstep.ClientError("%s: vehicle '%s' has no %s named '%s' (settings.json: %s)" % (
                    call, vehicle_name or 'default', kind, name, ', '.join(s.name for s in declared) or 'none'))
        return declared[0] if declared else None

    def _sensor(self, call, vehicle_name, kind, name, blueprint, attrs=None, newer=False):
        a = self._vehicle(vehicle_name)
        st = self._sensor_setting(vehicle_name, kind, name, call)
        mount = (0.0,) * 6
        if st is not None:
            mount = tuple(getattr(st, k) or 0.0 for k in ('x', 'y', 'z', 'roll', 'pitch', 'yaw'))
        elif kind == 'Lidar':
            mount = (0.0, 0.0, -1.0, 0.0, 0.0, 0.0)   # AirSim's default LiDAR: 1 m above the body
        a_attrs = dict(attrs or {})
        a_attrs.setdefault('role_name', name or kind.lower())
        frame = self._client.frame() if newer else None
        s = self._s.sensors.latest(call, (kind, a, st.name if st else ''), blueprint, a_attrs,
                                   geo.frd_mount_to_flu(*mount), a, newer_than=frame)
        return s, st, mount, a

    def getImuData(self, imu_name='', vehicle_name=''):
        s, _, _, _ = self._sensor('getImuData', vehicle_name, 'Imu', imu_name, 'sensor.other.imu')
        f = s.fields()
        out = ImuData()
        out.time_stamp = int(round(s.sim_time * 1e9))
        a, g = f['accelerometer'], f['gyroscope']
        out.linear_acceleration = Vector3r(a[0], -a[1], -a[2])   # FLU -> FRD
        out.angular_velocity = Vector3r(g[0], -g[1], -g[2])
        out.orientation = geo.enu_to_ned_quat(tuple(f['orientation']))
        return out

    def getGpsData(self, gps_name='', vehicle_name=''):
        s, _, _, a = self._sensor('getGpsData', vehicle_name, 'Gps', gps_name, 'sensor.other.gnss')
        f = s.fields()
        out = GpsData()
        out.time_stamp = int(round(s.sim_time * 1e9))
        out.gnss.geo_point = GeoPoint(*self._s.geo_shift((f['latitude'], f['longitude'], f['altitude'])))
        out.gnss.eph, out.gnss.epv = f['eph'], f['epv']
        out.gnss.fix_type = 3 if f['fix'] else 0
        st = self._client.state(a)
        if st:
            out.gnss.velocity = _v(geo.enu_to_ned_pos(st['velocity'], (0, 0, 0)))
        out.gnss.time_utc = int(round(s.sim_time * 1e6))
        out.is_valid = True
        return out

    def getBarometerData(self, barometer_name='', vehicle_name=''):
        s, _, _, _ = self._sensor('getBarometerData', vehicle_name, 'Barometer', barometer_name,
                                  'sensor.other.barometer')
        f = s.fields()
        out = BarometerData()
        out.time_stamp = int(round(s.sim_time * 1e9))
        out.altitude, out.pressure, out.qnh = f['altitude'], f['pressure'], f['qnh']
        return out

    def getMagnetometerData(self, magnetometer_name='', vehicle_name=''):
        s, _, _, _ = self._sensor('getMagnetometerData', vehicle_name, 'Magnetometer', magnetometer_name,
                                  'sensor.other.magnetometer')
        m = s.fields()['magnetic_field']
        out = MagnetometerData()
        out.time_stamp = int(round(s.sim_time * 1e9))
        out.magnetic_field_body = Vector3r(m[0], -m[1], -m[2])
        return out

    def getDistanceSensorData(self, distance_sensor_name='', vehicle_name=''):
        st = self._sensor_setting(vehicle_name, 'Distance', distance_sensor_name, 'getDistanceSensorData')
        attrs = {}
        if st is not None:
            attrs = {'min_distance': repr(st.params['min_distance']), 'max_distance': repr(st.params['max_distance'])}
        s, st, mount, _ = self._sensor('getDistanceSensorData', vehicle_name, 'Distance', distance_sensor_name,
                                       'sensor.other.distance', attrs)
        f = s.fields()
        out = DistanceSensorData()
        out.time_stamp = int(round(s.sim_time * 1e9))
        out.distance, out.min_distance, out.max_distance = f['distance'], f['min_distance'], f['max_distance']
        out.relative_pose = Pose(Vector3r(*mount[:3]), geo.frd_euler_deg_to_quat(*mount[3:]))
        return out

    def getLidarData(self, lidar_name='', vehicle_name=''):
        """AirSim's LidarData: the points of the last scan in the settings' DataFrame
        (VehicleInertialFrame: the vehicle's NED frame from its home, AirSim's default;
        SensorLocalFrame: the sensor's FRD frame) and the LiDAR's pose in the vehicle's NED frame."""
        st = self._sensor_setting(vehicle_name, 'Lidar', lidar_name, 'getLidarData')
        p = dict(st.params) if st is not None else {
            'channels': 16, 'range': 100.0, 'rotations_per_second': 10.0, 'points_per_second': 100000,
            'upper': -15.0, 'lower': -45.0, 'h_start': 0.0, 'h_end': 359.0, 'data_frame': 'VehicleInertialFrame'}
        width = (p['h_end'] - p['h_start']) % 360.0
        if width == 0:
            width = 360.0   # AirSim: start == end is the whole circle
        center = p['h_start'] + width / 2.0 if width < 360.0 else 0.0
        attrs = {'channels': str(p['channels']), 'range': repr(p['range']),
                 'points_per_second': str(p['points_per_second']), 'rotation_frequency': repr(p['rotations_per_second']),
                 'upper_fov': repr(p['upper']), 'lower_fov': repr(p['lower']), 'horizontal_fov': repr(width),
                 'dropoff_general_rate': '0', 'noise_stddev': '0', 'atmosphere_attenuation_rate': '0'}
        a = self._vehicle(vehicle_name)
        mount = (0.0, 0.0, -1.0, 0.0, 0.0, 0.0)
        if st is not None:
            mount = tuple(getattr(st, k) or 0.0 for k in ('x', 'y', 'z', 'roll', 'pitch', 'yaw'))
        # The scan's centre is the sensor's forward axis: turn the mount by it, turn the points back.
        spawn_mount = mount[:5] + (mount[5] + center,)
        s = self._s.sensors.latest('getLidarData', ('Lidar', a, st.name if st else ''), 'sensor.lidar.ray_cast',
                                   dict(attrs, role_name=lidar_name or 'lidar'), geo.frd_mount_to_flu(*spawn_mount), a)
        pts = np.array(s.array(), dtype=np.float64)[:, :3]
        pts[:, 1] *= -1   # FLU -> FRD
        pts[:, 2] *= -1
        if center:
            c, sn = math.cos(math.radians(center)), math.sin(math.radians(center))
            x, y = pts[:, 0].copy(), pts[:, 1].copy()
            pts[:, 0], pts[:, 1] = c * x - sn * y, sn * x + c * y
        vp, vq = self._vehicle_pose(vehicle_name)
        lp, lq = geo.compose(_v(vp), _q(vq), Vector3r(*mount[:3]), geo.frd_euler_deg_to_quat(*mount[3:]))
        out = LidarData()
        out.time_stamp = int(round(s.sim_time * 1e9))
        out.pose = Pose(lp, lq)
        if p['data_frame'] == 'VehicleInertialFrame' and len(pts):
            n = lq.get_length()
            w, x, y, z = lq.w_val / n, lq.x_val / n, lq.y_val / n, lq.z_val / n
            r = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                          [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                          [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
            pts = pts @ r.T + np.array([lp.x_val, lp.y_val, lp.z_val])
        out.point_cloud = pts.astype(np.float32).reshape(-1).tolist()
        out.segmentation = [0] * len(pts)
        return out

    def simGetLidarSegmentation(self, lidar_name='', vehicle_name=''):
        log.warning('simGetLidarSegmentation API is deprecated, use getLidarData() API instead')
        return self.getLidarData(lidar_name, vehicle_name).segmentation

    # --- plotting: debug shapes the render service draws into its colour cameras ---
    def _draw(self, call, shapes, color_rgba, duration, is_persistent):
        """World NED (from the player start) shapes as debug_draw commands (needs render to be
        seen). AirSim's sizes are Unreal's (cm, points in px): points of `size` px are CARLA's
        size / 100, thicknesses cm -> m."""
        if color_rgba is not None and (len(color_rgba) != 4 or any(not 0 <= float(c) <= 1 for c in color_rgba)):
            raise lockstep.ClientError('%s: color_rgba is 4 values in [0, 1], got %r' % (call, color_rgba))
        st = self._client.run_status()
        if st is None or not any(k == 'render' and alive for _, k, alive, _ in st['members']):
            return
        life = _plot_life(duration, is_persistent, self._client.world_info()['settings']['fixed_delta_seconds'] or 0.05)
        col = tuple(int(round(float(c) * 255)) for c in (color_rgba or (1.0, 0.0, 0.0, 1.0)))
        start = self._s.start()
        out = []
        for sh in shapes:
            d = dict(sh)
            for k in ('begin', 'end'):
                if k in d:
                    v = d[k]
                    d[k] = geo.ned_to_enu_pos((v.x_val, v.y_val, v.z_val), start)
            d.setdefault('color', col)
            d['life_time'] = life
            d['persistent_lines'] = bool(is_persistent)
            out.append(d)
        for k in range(0, len(out), 4096):
            self._client.submit({'type': 'debug_draw', 'shapes': out[k:k + 4096]})

    @staticmethod
    def _points(call, points):
        for p in points:
            if not isinstance(p, Vector3r):
                raise TypeError('%s: points are airsim.Vector3r, got %s' % (call, type(p).__name__))
        return list(points)

    def simFlushPersistentMarkers(self):
        """AirSim's: Unreal's FlushPersistentDebugLines, which erases every plotted shape still
        shown, the persistent ones and those with a duration alike (both are in Unreal's
        persistent line batcher), and CARLA's world.debug shapes too; a debug_draw that
        flushes, from the next tick on."""
        st = self._client.run_status()
        if st is None or not any(k == 'render' and alive for _, k, alive, _ in st['members']):
            return   # nothing is drawn without a render service
        self._client.submit({'type': 'debug_draw', 'shapes': [], 'flush_persistent': True})

    def simPlotPoints(self, points, color_rgba=[1.0, 0.0, 0.0, 1.0], size=10.0, duration=-1.0, is_persistent=False):
        pts = self._points('simPlotPoints', points)
        self._draw('simPlotPoints', [{'kind': 'point', 'begin': p, 'size': float(size) / 100.0} for p in pts],
                   color_rgba, duration, is_persistent)

    def simPlotLineStrip(self, points, color_rgba=[1.0, 0.0, 0.0, 1.0], thickness=5.0, duration=-1.0,
                         is_persistent=False):
        pts = self._points('simPlotLineStrip', points)
        self._draw('simPlotLineStrip', [{'kind': 'line', 'begin': a, 'end': b, 'size': float(thickness) / 100.0}
                                        for a, b in zip(pts, pts[1:])], color_rgba, duration, is_persistent)

    def simPlotLineList(self, points, color_rgba=[1.0, 0.0, 0.0, 1.0], thickness=5.0, duration=-1.0,
                        is_persistent=False):
        pts = self._points('simPlotLineList', points)
        if len(pts) % 2:
            raise lockstep.ClientError('simPlotLineList: an even number of points, got %d' % len(pts))
        self._draw('simPlotLineList', [{'kind': 'line', 'begin': a, 'end': b, 'size': float(thickness) / 100.0}
                                       for a, b in zip(pts[0::2], pts[1::2])], color_rgba, duration, is_persistent)

    def simPlotArrows(self, points_start, points_end, color_rgba=[1.0, 0.0, 0.0, 1.0], thickness=5.0, arrow_size=2.0,
                      duration=-1.0, is_persistent=False):
        a, b = self._points('simPlotArrows', points_start), self._points('simPlotArrows', points_end)
        if len(a) != len(b):
            raise lockstep.ClientError('simPlotArrows: points_start and points_end differ in length')
        self._draw('simPlotArrows', [{'kind': 'arrow', 'begin': p, 'end': q, 'size': float(thickness) / 100.0,
                                      'arrow_size': float(arrow_size) / 100.0} for p, q in zip(a, b)],
                   color_rgba, duration, is_persistent)

    def simPlotStrings(self, strings, positions, scale=5, color_rgba=[1.0, 0.0, 0.0, 1.0], duration=-1.0):
        pos = self._points('simPlotStrings', positions)
        if len(strings) != len(pos):
            raise lockstep.ClientError('simPlotStrings: strings and positions differ in length')
        self._draw('simPlotStrings', [{'kind': 'string', 'begin': p, 'text': str(t)[:256]} for t, p in zip(strings, pos)],
                   color_rgba, duration, False)

    def _axes(self, call, poses, scale, thickness):
        shapes = []
        for pose in poses:
            if not isinstance(pose, Pose):
                raise TypeError('%s: poses are airsim.Pose, got %s' % (call, type(pose).__name__))
            for axis, col in (((1, 0, 0), (255, 0, 0, 255)), ((0, 1, 0), (0, 255, 0, 255)), ((0, 0, 1), (0, 0, 255, 255))):
                tip = pose.position + _rotate_vector(pose.orientation, Vector3r(*axis) * (float(scale) / 100.0))
                shapes.append({'kind': 'line', 'begin': pose.position, 'end': tip, 'size': float(thickness) / 100.0,
                               'color': col})
        return shapes

    def simPlotTransforms(self, poses, scale=5.0, thickness=5.0, duration=-1.0, is_persistent=False):
        self._draw('simPlotTransforms', self._axes('simPlotTransforms', poses, scale, thickness), None, duration,
                   is_persistent)

    def simPlotTransformsWithNames(self, poses, names, tf_scale=5.0, tf_thickness=5.0, text_scale=10.0,
                                   text_color_rgba=[1.0, 0.0, 0.0, 1.0], duration=-1.0):
        if len(poses) != len(names):
            raise lockstep.ClientError('simPlotTransformsWithNames: poses and names differ in length')
        shapes = self._axes('simPlotTransformsWithNames', poses, tf_scale, tf_thickness)
        col = tuple(int(round(float(c) * 255)) for c in text_color_rgba)
        shapes += [{'kind': 'string', 'begin': p.position, 'text': str(n)[:256], 'color': col} for p, n in zip(poses, names)]
        self._draw('simPlotTransformsWithNames', shapes, None, duration, False)

    # --- tasks, recording, wind, vehicles, settings ---
    def cancelLastTask(self, vehicle_name=''):
        self._s.actor(vehicle_name)
        self._mc.cancel(vehicle_name)

    def startRecording(self):
        """AirSim's: records into <Recording.Folder, else ~/Documents/AirSim>/<YYYY-MM-DD-HH-MM-SS>/.
        Lockstep's recorder writes the run's log there (airsim_rec.log: every frame's world
        state); stopRecording writes AirSim's airsim_rec.txt beside it from the log (docs/
        compatibility.md: no image files)."""
        self._s.start_recording()

    def stopRecording(self):
        self._s.stop_recording()

    def isRecording(self):
        """AirSim's: True between startRecording and stopRecording (of this process's clients)."""
        return self._s.recording is not None

    def simSetWind(self, wind):
        """One wind (m/s, world NED) for every drone, from the next tick."""
        self._s.ensure_vehicles()
        self._mc.set_wind((wind.x_val, wind.y_val, wind.z_val))

    def simAddVehicle(self, vehicle_name, vehicle_type, pose, pawn_path=''):
        """A multirotor at `pose` (world NED from the player start)."""
        if vehicle_type.lower() not in ('simpleflight', 'px4multirotor', 'arducopter', ''):
            _unsupported('simAddVehicle(%r)' % vehicle_type, 'vehicles added at run time are multirotors')
        s = self._s
        with s.lock:
            s.ensure_vehicles()
            if vehicle_name in self._mc.list_vehicles():
                log.warning("airsim: vehicle '%s' exists already", vehicle_name)
                return False
            p = pose.position
            pitch, roll, yaw = to_eularian_angles(pose.orientation)
            a = s.spawn_vehicle(vehicle_name, (p.x_val, p.y_val, p.z_val),
                                (math.degrees(roll), math.degrees(pitch), math.degrees(yaw)))
            s.wait_at_rest([a])
        return True

    def listVehicles(self):
        self._s.ensure_vehicles()
        return self._mc.list_vehicles()

    def getSettingsString(self):
        return self._s.load_settings().text


# --------------------------------------------------------------------------- MultirotorClient
class MultirotorClient(VehicleClient):
    """AirSim's MultirotorClient over air_sim."""

    def _cmd(self, call, vehicle_name, fn, *args):
        a = self._s.actor(vehicle_name)
        self._motors_on(a, vehicle_name)
        return _Future(self._s, fn(*args), vehicle_name, call)

    def _motors_on(self, actor, vehicle_name):
        """simple_flight drives its motors whatever the arm state (arming only changes its
        state machine): a command to a disarmed vehicle under API control arms it, where
        air_sim would refuse it."""
        d = self._client.drone_state(actor)
        if d is not None and not d['armed'] and self._mc.is_api_control_enabled(vehicle_name):
            self._mc.arm_disarm(True, vehicle_name)

    @staticmethod
    def _drive(drivetrain, yaw_mode):
        """AirSim's adjustYaw: ForwardOnly with a yaw rate is no adjustment at all (MaxDegreeOfFreedom)."""
        if drivetrain == DrivetrainType.ForwardOnly and yaw_mode.is_rate:
            return DrivetrainType.MaxDegreeOfFreedom
        return drivetrain

    def takeoffAsync(self, timeout_sec=20, vehicle_name=''):
        """AirSim refuses a takeoff while the vehicle moves (> 0.05 m/s). A flying vehicle still
        braking from its last command (air_sim holds where a timed move ends) is given up to 3 s
        of simulation time to come to rest first; a falling one (vertical speed over 0.3 m/s) is refused."""
        self._s.actor(vehicle_name)
        st = self._mc.state(vehicle_name)
        if not st['landed'] and abs(st['linear_velocity'][2]) < 0.3 and self._mc.is_api_control_enabled(vehicle_name):
            dt = self._client.world_info()['settings']['fixed_delta_seconds'] or 0.05
            for _ in range(int(3.0 / dt)):
                st = self._mc.state(vehicle_name)
                if math.sqrt(sum(v * v for v in st['linear_velocity'])) <= 0.04 or st['landed']:
                    break
                self._s.wait_frames(1)
        return self._cmd('takeoffAsync', vehicle_name, self._mc.takeoff, timeout_sec, vehicle_name)

    def landAsync(self, timeout_sec=60, vehicle_name=''):
        return self._cmd('landAsync', vehicle_name, self._mc.land, timeout_sec, vehicle_name)

    def goHomeAsync(self, timeout_sec=3e+38, vehicle_name=''):
        """AirSim's goHome: moveToPosition(0, 0, 0) at 0.5 m/s."""
        return self._cmd('goHomeAsync', vehicle_name, self._mc.move_to_position, 0.0, 0.0, 0.0, 0.5, timeout_sec,
                         DrivetrainType.MaxDegreeOfFreedom, True, 0.0, -1, vehicle_name)

    def moveByVelocityBodyFrameAsync(self, vx, vy, vz, duration, drivetrain=DrivetrainType.MaxDegreeOfFreedom,
                                     yaw_mode=YawMode(), vehicle_name=''):
        if not _dur(duration):
            return _DoneFuture()
        return self._cmd('moveByVelocityBodyFrameAsync', vehicle_name, self._mc.move_by_velocity, vx, vy, vz, duration,
                         self._drive(drivetrain, yaw_mode), yaw_mode.is_rate, yaw_mode.yaw_or_rate, True, vehicle_name)

    def moveByVelocityZBodyFrameAsync(self, vx, vy, z, duration, drivetrain=DrivetrainType.MaxDegreeOfFreedom,
                                      yaw_mode=YawMode(), vehicle_name=''):
        """vx, vy in the body frame's heading at the call (AirSim turns them by the yaw only)."""
        if not _dur(duration):
            return _DoneFuture()
        self._s.actor(vehicle_name)
        _, q = self._mc.pose(vehicle_name)
        yaw = to_eularian_angles(_q(q))[2]
        c, s = math.cos(yaw), math.sin(yaw)
        return self.moveByVelocityZAsync(c * vx - s * vy, s * vx + c * vy, z, duration, drivetrain, yaw_mode, vehicle_name)

    def moveByAngleZAsync(self, pitch, roll, z, yaw, duration, vehicle_name=''):
        log.warning('moveByAngleZAsync API is deprecated, use moveByRollPitchYawZAsync() API instead')
        return self.moveByRollPitchYawZAsync(roll, pitch, yaw, z, duration, vehicle_name)

    def moveByAngleThrottleAsync(self, pitch, roll, throttle, yaw_rate, duration, vehicle_name=''):
        log.warning('moveByAngleThrottleAsync API is deprecated, use moveByRollPitchYawrateThrottleAsync() API instead')
        return self.moveByRollPitchYawrateThrottleAsync(roll, pitch, yaw_rate, throttle, duration, vehicle_name)

    def moveByVelocityAsync(self, vx, vy, vz, duration, drivetrain=DrivetrainType.MaxDegreeOfFreedom, yaw_mode=YawMode(),
                            vehicle_name=''):
        if not _dur(duration):
            return _DoneFuture()
        return self._cmd('moveByVelocityAsync', vehicle_name, self._mc.move_by_velocity, vx, vy, vz, duration,
                         self._drive(drivetrain, yaw_mode), yaw_mode.is_rate, yaw_mode.yaw_or_rate, False, vehicle_name)

    def moveByVelocityZAsync(self, vx, vy, z, duration, drivetrain=DrivetrainType.MaxDegreeOfFreedom, yaw_mode=YawMode(),
                             vehicle_name=''):
        if not _dur(duration):
            return _DoneFuture()
        return self._cmd('moveByVelocityZAsync', vehicle_name, self._mc.move_by_velocity_z, vx, vy, z, duration,
                         self._drive(drivetrain, yaw_mode), yaw_mode.is_rate, yaw_mode.yaw_or_rate, vehicle_name)

    def moveOnPathAsync(self, path, velocity, timeout_sec=3e+38, drivetrain=DrivetrainType.MaxDegreeOfFreedom,
                        yaw_mode=YawMode(), lookahead=-1, adaptive_lookahead=1, vehicle_name=''):
        pts = [(p.x_val, p.y_val, p.z_val) for p in path]
        return self._cmd('moveOnPathAsync', vehicle_name, self._mc.move_on_path, pts, velocity, timeout_sec,
                         self._drive(drivetrain, yaw_mode), yaw_mode.is_rate, yaw_mode.yaw_or_rate, lookahead,
                         vehicle_name)

    def moveToPositionAsync(self, x, y, z, velocity, timeout_sec=3e+38, drivetrain=DrivetrainType.MaxDegreeOfFreedom,
                            yaw_mode=YawMode(), lookahead=-1, adaptive_lookahead=1, vehicle_name=''):
        return self._cmd('moveToPositionAsync', vehicle_name, self._mc.move_to_position, x, y, z, velocity, timeout_sec,
                         self._drive(drivetrain, yaw_mode), yaw_mode.is_rate, yaw_mode.yaw_or_rate, lookahead,
                         vehicle_name)

    def moveToGPSAsync(self, latitude, longitude, altitude, velocity, timeout_sec=3e+38,
                       drivetrain=DrivetrainType.MaxDegreeOfFreedom, yaw_mode=YawMode(), lookahead=-1,
                       adaptive_lookahead=1, vehicle_name=''):
        lat, lon, alt = self._s.geo_shift((latitude, longitude, altitude), inverse=True)
        return self._cmd('moveToGPSAsync', vehicle_name, self._mc.move_to_gps, lat, lon, alt, velocity, timeout_sec,
                         self._drive(drivetrain, yaw_mode), yaw_mode.is_rate, yaw_mode.yaw_or_rate, lookahead,
                         adaptive_lookahead, vehicle_name)

    def moveToZAsync(self, z, velocity, timeout_sec=3e+38, yaw_mode=YawMode(), lookahead=-1, adaptive_lookahead=1,
                     vehicle_name=''):
        return self._cmd('moveToZAsync', vehicle_name, self._mc.move_to_z, z, velocity, timeout_sec, yaw_mode.is_rate,
                         yaw_mode.yaw_or_rate, lookahead, vehicle_name)

    def moveByManualAsync(self, vx_max, vy_max, z_min, duration, drivetrain=DrivetrainType.MaxDegreeOfFreedom,
                          yaw_mode=YawMode(), vehicle_name=''):
        """AirSim's manual mode: for `duration`, the RC input (moveByRC) drives the vehicle,
        its sticks scaled by vx_max, vy_max and z_min as AirSim's moveByManual does."""
        if not _dur(duration):
            return _DoneFuture()
        a = self._s.actor(vehicle_name)
        end = self._s.sim_time() + min(float(duration), 1e5)
        if not self._mc.is_api_control_enabled(vehicle_name):
            # simple_flight refuses the goals without API control: the call waits out its duration.
            log.warning("airsim: moveByManualAsync on vehicle '%s' without API control: it does not steer the vehicle",
                        vehicle_name or 'default')
            return _TimedFuture(self._s, end)
        self._s.manual[a] = (vx_max, vy_max, z_min, end, drivetrain, yaw_mode)
        rc = self._s.rc.get(a)
        if rc is not None:
            self._apply_rc(a, rc, vehicle_name)
        return _TimedFuture(self._s, end)

    def moveByRC(self, rcdata=RCData(), vehicle_name=''):
        """The RC input: in manual mode (moveByManualAsync) it sets the velocity and altitude
        goal as AirSim's moveByManual turns sticks into them; otherwise it is kept for it."""
        a = self._s.actor(vehicle_name)
        self._s.rc[a] = rcdata
        self._apply_rc(a, rcdata, vehicle_name)

    def _apply_rc(self, a, rc, vehicle_name):
        m = self._s.manual.get(a)
        if m is None or not rc.is_valid:
            return
        vx_max, vy_max, z_min, end, drivetrain, yaw_mode = m
        left = min(end - self._s.sim_time(), 1e5)
        if left <= 0:
            del self._s.manual[a]
            return
        self._motors_on(a, vehicle_name)
        k = 10000.0   # AirSim's kMaxRCValue
        vx, vy = rc.pitch * vy_max / k, rc.roll * vx_max / k
        _, q = self._mc.pose(vehicle_name)
        yaw = to_eularian_angles(_q(q))[2]
        c, s = math.cos(yaw), math.sin(yaw)
        z = (rc.throttle / k) * z_min + self._mc.state(vehicle_name)['position'][2]
        ym = YawMode(yaw_mode.is_rate, yaw_mode.yaw_or_rate + rc.yaw * 100.0 / k)
        speed = math.hypot(vx, vy)
        if speed > 100.0:
            vx, vy = vx * 100.0 / speed, vy * 100.0 / speed
        self._mc.move_by_velocity_z(c * vx - s * vy, s * vx + c * vy, z, left, self._drive(drivetrain, ym), ym.is_rate,
                                    ym.yaw_or_rate, vehicle_name)

    def rotateToYawAsync(self, yaw, timeout_sec=3e+38, margin=5, vehicle_name=''):
        return self._cmd('rotateToYawAsync', vehicle_name, self._mc.rotate_to_yaw, yaw, timeout_sec, margin, vehicle_name)

    def rotateByYawRateAsync(self, yaw_rate, duration, vehicle_name=''):
        if not _dur(duration):
            return _DoneFuture()
        return self._cmd('rotateByYawRateAsync', vehicle_name, self._mc.rotate_by_yaw_rate, yaw_rate, duration,
                         vehicle_name)

    def hoverAsync(self, vehicle_name=''):
        return self._cmd('hoverAsync', vehicle_name, self._mc.hover, vehicle_name)

    def moveByMotorPWMsAsync(self, front_right_pwm, rear_left_pwm, front_left_pwm, rear_right_pwm, duration,
                             vehicle_name=''):
        if not _dur(duration):
            return _DoneFuture()
        return self._cmd('moveByMotorPWMsAsync', vehicle_name, self._mc.move_by_motor_pwms,
                         [front_right_pwm, rear_left_pwm, front_left_pwm, rear_right_pwm], duration, vehicle_name)

    def moveByRollPitchYawZAsync(self, roll, pitch, yaw, z, duration, vehicle_name=''):
        if not _dur(duration):
            return _DoneFuture()
        return self._cmd('moveByRollPitchYawZAsync', vehicle_name, self._mc.move_by_rpy_z, roll, pitch, yaw, z, duration,
                         vehicle_name)

    def moveByRollPitchYawThrottleAsync(self, roll, pitch, yaw, throttle, duration, vehicle_name=''):
        if not _dur(duration):
            return _DoneFuture()
        return self._cmd('moveByRollPitchYawThrottleAsync', vehicle_name, self._mc.move_by_rpy_throttle, roll, pitch,
                         yaw, throttle, duration, vehicle_name)

    def moveByRollPitchYawrateThrottleAsync(self, roll, pitch, yaw_rate, throttle, duration, vehicle_name=''):
        if not _dur(duration):
            return _DoneFuture()
        return self._cmd('moveByRollPitchYawrateThrottleAsync', vehicle_name, self._mc.move_by_rp_yawrate_throttle, roll,
                         pitch, yaw_rate, throttle, duration, vehicle_name)

    def moveByRollPitchYawrateZAsync(self, roll, pitch, yaw_rate, z, duration, vehicle_name=''):
        if not _dur(duration):
            return _DoneFuture()
        return self._cmd('moveByRollPitchYawrateZAsync', vehicle_name, self._mc.move_by_rp_yawrate_z, roll, pitch,
                         yaw_rate, z, duration, vehicle_name)

    def moveByAngleRatesZAsync(self, roll_rate, pitch_rate, yaw_rate, z, duration, vehicle_name=''):
        if not _dur(duration):
            return _DoneFuture()
        return self._cmd('moveByAngleRatesZAsync', vehicle_name, self._mc.move_by_angle_rates_z, roll_rate, pitch_rate,
                         yaw_rate, z, duration, vehicle_name)

    def moveByAngleRatesThrottleAsync(self, roll_rate, pitch_rate, yaw_rate, throttle, duration, vehicle_name=''):
        if not _dur(duration):
            return _DoneFuture()
        return self._cmd('moveByAngleRatesThrottleAsync', vehicle_name, self._mc.move_by_angle_rates_throttle, roll_rate,
                         pitch_rate, yaw_rate, throttle, duration, vehicle_name)

    # The terms air_sim's loops have (docs/compatibility.md): the others must be 0.
    _GAIN_TERMS = {'angle_rate': 'pid', 'angle_level': 'p', 'velocity': 'pi', 'position': 'p'}

    def _set_gains(self, call, loop, gains, vehicle_name):
        self._s.actor(vehicle_name)
        kp, ki, kd = gains.to_lists()
        terms = self._GAIN_TERMS[loop]
        for name, values in (('i', ki), ('d', kd)):
            if name not in terms and any(values):
                _unsupported('%s with k%s' % (call, name), "air_sim's %s loop has no %s term" % (
                    loop.replace('_', ' '), {'i': 'integral', 'd': 'derivative'}[name]))
        self._mc.set_gains(loop, list(zip(kp, ki, kd)), vehicle_name)

    def setAngleRateControllerGains(self, angle_rate_gains=AngleRateControllerGains(), vehicle_name=''):
        self._set_gains('setAngleRateControllerGains', 'angle_rate', angle_rate_gains, vehicle_name)

    def setAngleLevelControllerGains(self, angle_level_gains=AngleLevelControllerGains(), vehicle_name=''):
        self._set_gains('setAngleLevelControllerGains', 'angle_level', angle_level_gains, vehicle_name)

    def setVelocityControllerGains(self, velocity_gains=VelocityControllerGains(), vehicle_name=''):
        self._set_gains('setVelocityControllerGains', 'velocity', velocity_gains, vehicle_name)

    def setPositionControllerGains(self, position_gains=PositionControllerGains(), vehicle_name=''):
        self._set_gains('setPositionControllerGains', 'position', position_gains, vehicle_name)

    def trackTargetAsync(self, position, velocity, max_speed=0.0, duration=1.0, vehicle_name=''):
        """Lockstep extension: follow a moving target (NED position m, velocity m/s, from this drone's home)."""
        return self._cmd('trackTargetAsync', vehicle_name, self._mc.track_target, tuple(position), tuple(velocity),
                         max_speed, duration, vehicle_name)

    def getMultirotorState(self, vehicle_name=''):
        a = self._s.actor(vehicle_name)
        s = self._mc.state(vehicle_name)
        out = MultirotorState()
        out.kinematics_estimated = _kinematics(s)
        out.collision = self._collision(s)
        out.timestamp = int(s['timestamp'])
        out.landed_state = LandedState.Landed if s['landed'] else LandedState.Flying
        st = self._client.state(a)
        if st:
            out.gps_location = GeoPoint(*self._s.enu_to_geo(*st['transform'][:3]))
        rc = self._s.rc.get(a)
        if rc is not None:
            out.rc_data = rc
        out.ready, out.ready_message, out.can_arm = True, '', True
        return out

    def getRotorStates(self, vehicle_name=''):
        self._s.actor(vehicle_name)
        s = self._mc.state(vehicle_name)
        out = RotorStates()
        out.timestamp = int(s['timestamp'])
        out.rotors = [{'speed': sp, 'thrust': th, 'torque_scaler': 0.0}
                      for sp, th in zip(s['rotor_speeds'], s['rotor_thrusts'])]
        return out


def _kinematics(s):
    k = KinematicsState()
    k.position = _v(s['position'])
    k.orientation = _q(s['orientation'])
    k.linear_velocity = _v(s['linear_velocity'])
    k.angular_velocity = _v(s['angular_velocity'])
    k.linear_acceleration = _v(s['linear_acceleration'])
    k.angular_acceleration = _v(s['angular_acceleration'])
    return k


# --------------------------------------------------------------------------- CarClient
# AirSim's car cameras (its car pawn's): name -> mount as a function of the car's half extents
# (x, y, z m FRD from the car's centre; roll, pitch, yaw deg). Lockstep's placement: the front
# ones at the top of the windscreen, fpv at the driver's eyes, back_center at the rear window.
_CAR_CAMERAS = {
    'front_center': lambda hx, hy, hz: (0.25 * hx, 0.0, -0.9 * hz, 0.0, 0.0, 0.0),
    'front_right': lambda hx, hy, hz: (0.25 * hx, 0.5 * hy, -0.9 * hz, 0.0, 0.0, 0.0),
    'front_left': lambda hx, hy, hz: (0.25 * hx, -0.5 * hy, -0.9 * hz, 0.0, 0.0, 0.0),
    'fpv': lambda hx, hy, hz: (-0.1 * hx, -0.4 * hy, -0.6 * hz, 0.0, 0.0, 0.0),
    'back_center': lambda hx, hy, hz: (-0.7 * hx, 0.0, -0.9 * hz, 0.0, 0.0, 180.0),
}
_API_MARKER = 'airsim_api_control'      # role_name of the actor that holds a car's API control
_COLLISION_SENSOR = 'airsim_collision'  # role_name of the collision sensor simGetCollisionInfo reads
_IDLE_RPM = 1000.0                      # ground_sim's engine below idle: the clutch slips (vehicle_dynamics.cpp)


def _engine_rpm(phys, gear, forward_speed, throttle):
    """The engine speed of ground_sim's powertrain (vehicle_dynamics.cpp): the driven wheels'
    speed through the gear and the final drive (0 in neutral and at rest), at least the idle
    speed while the throttle is pressed (the clutch slips there), at most max_rpm."""
    gears = phys['forward_gears']
    if gear == 0 or not gears:
        ratio = 0.0
    elif gear < 0:
        ratio = gears[0][0]
    else:
        ratio = gears[min(gear, len(gears)) - 1][0]
    rpm = abs(forward_speed) / phys['wheel_radius'] * ratio * phys['final_ratio'] * 60.0 / (2.0 * math.pi)
    if throttle > 0.0:
        rpm = max(rpm, _IDLE_RPM)
    return min(rpm, phys['max_rpm'])


class CarClient(VehicleClient):
    """AirSim's CarClient on ground_sim's vehicles: SimMode "Car" (the settings' cars at their
    poses from the player start, the map's first vehicle spawn point) or a car named by its
    role_name (or 'Car<id>'). As AirSim's PhysXCar (CarPawnApi, CarPawnSimApi): API control
    starts off and is the car's, whichever client or process takes it; without it the car gets
    AirSim's keyboard/joystick controls (none pressed: CarControls()) every frame, so
    setCarControls has no lasting effect; a change of API control starts from CarControls();
    arming is not a car's (True). The VehicleClient calls (poses, kinematics, collisions,
    sensors, cameras) address the car."""

    def _car(self, vehicle_name):
        s = self._s
        s.ensure_cars()
        cars = [a for a in self._client.actors() if a['kind'] == 'vehicle']
        if not vehicle_name:
            # AirSim's default vehicle: the settings' first car (else AirSim's PhysXCar), else any car.
            for n in s.airsim_car_names():
                for a in cars:
                    if a['attributes'].get('role_name', '') == n:
                        return s.watch_car(a)
        for a in cars:
            role = a['attributes'].get('role_name', '')
            if not vehicle_name or vehicle_name in (role, 'Car%d' % a['id']):
                return s.watch_car(a)
        if not vehicle_name and not cars:
            sp = s.car_start()
            if sp is None:
                sx, sy, sz = s.start()
                sp = (sx, sy, sz, 0.0)
            q = (math.cos(sp[3] / 2), 0.0, 0.0, math.sin(sp[3] / 2))
            s.spawn_car(s.airsim_car_names()[0], (sp[0], sp[1], sp[2] + _CAR_HEIGHT) + q)
            s.wait_frames(2)
            return self._car(vehicle_name)
        raise lockstep.ClientError("no car named '%s'" % vehicle_name)

    def _key(self, a):
        return (self._client.world_info()['run'], a['id'])

    def _apply(self, a, controls):
        self._client.submit(dict(_car_wire_controls(controls), type='vehicle_control', actor=a['id']))

    # --- the vehicle of the VehicleClient calls: the car ---
    def _vehicle(self, vehicle_name):
        return self._car(vehicle_name)['id']

    def _car_state(self, a):
        st = self._client.state(a['id'])
        if st is None:
            raise lockstep.ClientError("car %d has no state yet (is ground_sim running?)" % a['id'])
        return st

    def _vehicle_pose(self, vehicle_name):
        a = self._car(vehicle_name)
        t = self._car_state(a)['transform']
        q = geo.enu_to_ned_quat(t[3:7])
        return geo.enu_to_ned_pos(t[:3], a['spawn_transform'][:3]), (q.w_val, q.x_val, q.y_val, q.z_val)

    def _set_vehicle_pose(self, pos, q, vehicle_name):
        a = self._car(vehicle_name)
        enu = geo.ned_to_enu_pos(pos, a['spawn_transform'][:3])
        qe = geo.ned_to_enu_quat(Quaternionr(q[1], q[2], q[3], q[0]))
        self._client.submit({'type': 'set_transform', 'actor': a['id'], 'transform': tuple(enu) + tuple(qe)})

    def _vehicle_home(self, actor):
        a = self._client.actor(actor)
        return tuple(a['spawn_transform'][:3]) if a else None

    def _vehicle_setting(self, vehicle_name):
        a = self._car(vehicle_name)
        return self._s.car_setting(a['attributes'].get('role_name', ''))

    def _default_cameras(self, actor):
        st = self._client.state(actor)
        hx, hy, hz = st['half_extents'] if st else (2.0, 0.9, 0.75)
        return {name: f(hx, hy, hz) for name, f in _CAR_CAMERAS.items()}

    def _car_kinematics(self, a, st):
        """KinematicsState in NED from the car's start (angular velocity in the body FRD frame)."""
        v = st['velocity']
        q = st['transform'][3:7]
        k = KinematicsState()
        k.position = _v(geo.enu_to_ned_pos(st['transform'][:3], a['spawn_transform'][:3]))
        k.orientation = geo.enu_to_ned_quat(q)
        k.linear_velocity = _v(geo.enu_to_ned_pos(v, (0, 0, 0)))
        w = _rotate_vector(Quaternionr(-q[1], -q[2], -q[3], q[0]), Vector3r(*st['angular_velocity']))   # body FLU
        k.angular_velocity = Vector3r(w.x_val, -w.y_val, -w.z_val)   # body FRD
        k.linear_acceleration = _v(geo.enu_to_ned_pos(st['acceleration'], (0, 0, 0)))
        return k

    def simGetGroundTruthKinematics(self, vehicle_name=''):
        a = self._car(vehicle_name)
        return self._car_kinematics(a, self._car_state(a))

    def simSetKinematics(self, state, ignore_collision, vehicle_name=''):
        """Pose, linear velocity (world NED) and angular velocity (body FRD) at once."""
        a = self._car(vehicle_name)
        o = state.orientation
        p = state.position
        self._set_vehicle_pose((p.x_val, p.y_val, p.z_val), (o.w_val, o.x_val, o.y_val, o.z_val), vehicle_name)
        lv = state.linear_velocity
        w = state.angular_velocity
        w_world = _rotate_vector(o, w)   # body FRD -> world NED
        c = self._client
        c.submit({'type': 'actor_physics', 'actor': a['id'], 'kind': 'set_target_velocity',
                  'value': geo.ned_to_enu_pos((lv.x_val, lv.y_val, lv.z_val), (0.0, 0.0, 0.0))})
        c.submit({'type': 'actor_physics', 'actor': a['id'], 'kind': 'set_target_angular_velocity',
                  'value': geo.ned_to_enu_pos((w_world.x_val, w_world.y_val, w_world.z_val), (0.0, 0.0, 0.0))})

    def simGetCollisionInfo(self, vehicle_name=''):
        """The car's last collision since its start or reset (AirSim's PawnSimApi keeps it):
        from a collision sensor on the car (needs the sensors service)."""
        a = self._car(vehicle_name)
        return self._s.car_collision(a, self._car_state(a), 'simGetCollisionInfo')

    def cancelLastTask(self, vehicle_name=''):
        """AirSim's VehicleApiBase::cancelLastTask: a car runs no tasks; nothing to cancel."""
        self._car(vehicle_name)

    def listVehicles(self):
        self._s.ensure_cars()
        names = set(self._s.airsim_car_names())
        cars = [a['attributes'].get('role_name', '') for a in self._client.actors() if a['kind'] == 'vehicle']
        return self._mc.list_vehicles() + [n for n in cars if n in names]

    # --- API control: the car's, whichever client or process takes it ---
    def enableApiControl(self, is_enabled, vehicle_name=''):
        from .types import CarControls
        a = self._car(vehicle_name)
        with self._s.lock:
            if self._s.car_api_enabled(a) == bool(is_enabled):
                return
            self._s.set_car_api(a, bool(is_enabled))
            # CarPawnApi::enableApiControl: last_controls_ = CarControls(), until controls are set again.
            self._s.car_controls[self._key(a)] = (CarControls(), math.inf)
            if not is_enabled:
                self._apply(a, CarControls())   # back to the keyboard/joystick: nothing pressed

    def isApiControlEnabled(self, vehicle_name=''):
        return self._s.car_api_enabled(self._car(vehicle_name))

    def armDisarm(self, arm, vehicle_name=''):
        """AirSim's CarPawnApi::armDisarm: cars are not armed; True."""
        self._car(vehicle_name)
        return True

    def setCarControls(self, controls, vehicle_name=''):
        a = self._car(vehicle_name)
        with self._s.lock:
            if not self._s.car_api_enabled(a):
                # CarPawnSimApi::updateCarControls: without API control the keyboard/joystick
                # controls replace these in the frame they were set.
                return
            self._s.car_controls[self._key(a)] = (controls, self._client.frame())
            self._apply(a, controls)

    def getCarControls(self, vehicle_name=''):
        """The controls last set under API control (by any client: the car's applied control
        once another process set newer ones); CarControls() without API control."""
        from .types import CarControls
        a = self._car(vehicle_name)
        if not self._s.car_api_enabled(a):
            return CarControls()   # the keyboard/joystick's, nothing pressed
        mine, frame = self._s.car_controls.get(self._key(a), (None, -1))
        st = self._client.state(a['id'])
        if mine is not None and (st is None or st['frame'] <= frame or
                                 _same_controls(st['control'], _car_wire_controls(mine))):
            return mine   # this process's, set last (or not yet applied)
        if st is None:
            return CarControls()
        c = st['control']   # another client's, as the car applies them
        out = CarControls()
        out.throttle = -c['throttle'] if c['reverse'] and not c['manual_gear_shift'] else c['throttle']
        out.steering, out.brake, out.handbrake = c['steer'], c['brake'], bool(c['hand_brake'])
        out.is_manual_gear = bool(c['manual_gear_shift'])
        out.manual_gear = int(c['gear']) if out.is_manual_gear else 0
        return out

    def getCarState(self, vehicle_name=''):
        """speed: forward speed (m/s, negative backwards, as Unreal's GetForwardSpeed); gear the
        gearbox's; rpm the engine's (ground_sim's powertrain: the wheels' speed through the gear
        and the final drive, at least idle while the throttle is pressed), maxrpm the physics
        control's; handbrake the API's; kinematics in NED from the car's start (angular velocity
        in the body FRD frame); collision simGetCollisionInfo's."""
        a = self._car(vehicle_name)
        st = self._client.state(a['id'])
        out = CarState()
        if st is None:
            return out
        v = st['velocity']
        q = st['transform'][3:7]
        fwd = _rotate_vector(Quaternionr(q[1], q[2], q[3], q[0]), Vector3r(1, 0, 0))
        out.speed = v[0] * fwd.x_val + v[1] * fwd.y_val + v[2] * fwd.z_val
        out.gear = int(st.get('gear', 0))
        phys = self._client.vehicle_physics(a['id'])
        if phys:
            out.maxrpm = float(phys['max_rpm'])
            out.rpm = float(_engine_rpm(phys, out.gear, out.speed, st['control']['throttle']))
        out.handbrake = bool(self.getCarControls(vehicle_name).handbrake)
        out.kinematics_estimated = self._car_kinematics(a, st)
        try:
            out.collision = self._s.car_collision(a, st, None)
        except LockstepUnsupported:
            pass   # no sensors service: CarState's CollisionInfo() (nothing known)
        out.timestamp = int(round(self._s.sim_time() * 1e9))
        return out


_CAR_HEIGHT = 0.8   # m above the road where a car is spawned (its box centre; it settles ~3 cm lower)


def _car_wire_controls(controls):
    """AirSim's CarControls as ground_sim's vehicle_control fields (CarPawnApi::setCarControls:
    a negative throttle or gear drives backwards)."""
    reverse = controls.is_manual_gear and controls.manual_gear < 0 or controls.throttle < 0
    return {'throttle': float(min(abs(controls.throttle), 1)), 'steer': float(max(-1.0, min(1.0, controls.steering))),
            'brake': float(controls.brake), 'hand_brake': bool(controls.handbrake), 'reverse': bool(reverse),
            'manual_gear_shift': bool(controls.is_manual_gear), 'gear': int(controls.manual_gear)}


def _same_controls(wire, want):
    for k, v in want.items():
        if k == 'gear' and not want['manual_gear_shift']:
            continue
        w = wire[k]
        if isinstance(v, float):
            if abs(float(w) - v) > 1e-6:
                return False
        elif isinstance(v, bool):
            if bool(w) != v:
                return False
        elif int(w) != v:
            return False
    return True


# --------------------------------------------------------------------------- helpers
def _encode(resp, it, arr):
    """AirSim's encodings: float images as floats (pixels_as_float) or 8-bit grey; colour
    images as 3-channel BGR bytes, or RGBA PNG when compressed."""
    if it in (ImageType.OpticalFlow, ImageType.OpticalFlowVis):
        # AirSim's materials write (vx, vy, 0) or the Vis colour into a float target; its read-back
        # gives pixels_as_float the R channel only (RenderRequest: item.R) and bytes clamped to 0..1.
        vx, vy = _airsim_flow(arr)
        r, g, b = (vx, vy, np.zeros_like(vx)) if it == ImageType.OpticalFlow else _flow_vis(vx, vy)
        if resp.pixels_as_float:
            resp.image_data_float = np.asarray(r, np.float32).reshape(-1).tolist()
            return
        bgr = np.stack([_unorm8(b), _unorm8(g), _unorm8(r)], axis=-1)
    elif arr.ndim == 2 and arr.dtype != np.uint8:
        f = arr.astype(np.float32)
        if resp.pixels_as_float:
            resp.image_data_float = f.reshape(-1).tolist()
            return
        if it in (ImageType.DepthPlanar, ImageType.DepthPerspective):
            g = np.clip(f / 100.0, 0, 1) * 255   # as DepthVis
        else:
            g = np.clip(f, 0, 1) * 255
        g = np.round(g).astype(np.uint8)
        bgr = np.repeat(g[..., None], 3, axis=2)
    elif arr.ndim == 2:
        if resp.pixels_as_float:
            resp.image_data_float = (arr.astype(np.float32) / (255.0 if it == ImageType.DepthVis else 1.0)).reshape(-1).tolist()
            return
        bgr = np.repeat(arr[..., None], 3, axis=2)
    else:
        bgr = np.ascontiguousarray(arr[..., :3])
        if resp.pixels_as_float:
            resp.image_data_float = (bgr.astype(np.float32) / 255.0).reshape(-1).tolist()
            return
    if resp.compress:
        rgba = np.concatenate([bgr[..., ::-1], np.full(bgr.shape[:2] + (1,), 255, np.uint8)], axis=2)
        resp.image_data_uint8 = _png(rgba)
    else:
        resp.image_data_uint8 = np.ascontiguousarray(bgr).tobytes()


def _projection_matrix(fov_deg, width, height):
    """AirSim's CameraInfo.proj_mat: Unreal's reversed-Z perspective (near plane 10 cm)
    with the horizontal FOV, as a 4x4 list."""
    t = math.tan(math.radians(fov_deg) / 2)
    aspect = width / float(height)
    near = 10.0   # cm
    return [[1.0 / t, 0.0, 0.0, 0.0], [0.0, aspect / t, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0], [0.0, 0.0, near, 0.0]]


def _sun_position(when, lat, lon):
    """Sun altitude and azimuth (deg) at UTC `when` (NOAA's simple algorithm)."""
    doy = when.timetuple().tm_yday
    hour = when.hour + when.minute / 60.0 + when.second / 3600.0
    g = 2 * math.pi / 365 * (doy - 1 + (hour - 12) / 24)
    decl = 0.006918 - 0.399912 * math.cos(g) + 0.070257 * math.sin(g) - 0.006758 * math.cos(2 * g) + \
        0.000907 * math.sin(2 * g) - 0.002697 * math.cos(3 * g) + 0.00148 * math.sin(3 * g)
    eqt = 229.18 * (0.000075 + 0.001868 * math.cos(g) - 0.032077 * math.sin(g) - 0.014615 * math.cos(2 * g) -
                    0.040849 * math.sin(2 * g))
    tst = hour * 60 + eqt + 4 * lon
    ha = math.radians(tst / 4 - 180)
    la = math.radians(lat)
    cz = math.sin(la) * math.sin(decl) + math.cos(la) * math.cos(decl) * math.cos(ha)
    zen = math.acos(max(-1.0, min(1.0, cz)))
    az = math.degrees(math.atan2(math.sin(ha), math.cos(ha) * math.sin(la) - math.tan(decl) * math.cos(la))) + 180
    return 90 - math.degrees(zen), az % 360
