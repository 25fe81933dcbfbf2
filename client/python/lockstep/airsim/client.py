"""airsim.MultirotorClient over Lockstep: NED metres from each drone's spawn point, as
AirSim reports a vehicle relative to its start. *Async calls return a future whose join()
waits until air_sim reports the command finished (in synchronous mode it ticks the world)."""
import math
import os
import threading
import time
import weakref
import zlib
import struct

import numpy as np

import lockstep

from .types import (AngleLevelControllerGains, AngleRateControllerGains, BarometerData, CollisionInfo,
                    DistanceSensorData, DrivetrainType, GeoPoint, GpsData, ImageResponse, ImageType, ImuData,
                    KinematicsState, LandedState, LidarData, MagnetometerData, MultirotorState, Pose,
                    PositionControllerGains, Quaternionr, RotorStates, Vector3r, VelocityControllerGains,
                    WeatherParameter, YawMode)

__all__ = ['MultirotorClient', 'VehicleClient', 'LockstepUnsupported']


class LockstepUnsupported(RuntimeError):
    """An airsim call Lockstep cannot do (yet); the message names the call and why."""


def _unsupported(call, why):
    raise LockstepUnsupported('%s is not supported by Lockstep: %s (docs/compatibility.md)' % (call, why))


def _v(t):
    return Vector3r(*t)


def _q(t):
    w, x, y, z = t
    return Quaternionr(x, y, z, w)


class _Future:
    """What AirSim's *Async calls return: join() blocks until the command finished."""

    def __init__(self, native):
        self._f = native

    def join(self):
        return self._f.join()

    def status(self):
        return self._f.status()


# AirSim's camera names -> mount pose on the drone (FLU body, m / deg pitch), as its default multirotor.
_CAMERAS = {'0': ((0.25, 0, 0), 0), 'front_center': ((0.25, 0, 0), 0), '1': ((0.25, -0.05, 0), 0),
            'front_right': ((0.25, -0.05, 0), 0), '2': ((0.25, 0.05, 0), 0), 'front_left': ((0.25, 0.05, 0), 0),
            '3': ((0, 0, -0.1), -90), 'bottom_center': ((0, 0, -0.1), -90), '4': ((-0.25, 0, 0), 180),
            'back_center': ((-0.25, 0, 0), 180)}
_IMAGE_BLUEPRINTS = {ImageType.Scene: 'sensor.camera.rgb', ImageType.DepthPlanar: 'sensor.camera.depth',
                     ImageType.DepthPerspective: 'sensor.camera.depth', ImageType.DepthVis: 'sensor.camera.depth',
                     ImageType.Segmentation: 'sensor.camera.semantic_segmentation',
                     ImageType.SurfaceNormals: 'sensor.camera.normals'}


def _png(rgb):
    h, w = rgb.shape[:2]
    raw = np.concatenate([np.zeros((h, 1), dtype=np.uint8), rgb.reshape(h, w * 3)], axis=1).tobytes()

    def chunk(tag, data):
        c = struct.pack('>I', len(data)) + tag + data
        return c + struct.pack('>I', zlib.crc32(tag + data) & 0xffffffff)

    return (b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', w, h, 8, 2, 0, 0, 0)) +
            chunk(b'IDAT', zlib.compress(raw, 3)) + chunk(b'IEND', b''))


def _quat_yaw_pitch(yaw, pitch):
    """ENU quaternion (w, x, y, z) from heading and pitch (rad, FLU: pitch > 0 nose down)."""
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    return (cy * cp, -sy * sp, cy * sp, sy * cp)


class _AttachedSensors:
    """Sensors AirSim declares in settings.json are spawned here on first use, attached to
    the drone, and listened to; each get*Data returns the newest sample. One set per DDS
    session (every MultirotorClient of a process shares it): a drone's IMU is spawned once,
    lives as long as the drone, and goes with it (or with the run)."""

    def __init__(self, client):
        self._client_ref = weakref.ref(client)   # the session holds the listeners, not the other way
        self._sensors = {}  # (vehicle actor, blueprint, name) -> [actor id, latest sample]
        self._lock = threading.Lock()
        self._cv = threading.Condition(self._lock)

    def latest(self, call, actor, blueprint, name, attributes=None, pose=(0, 0, 0, 1, 0, 0, 0)):
        key = (actor, blueprint, name)
        c = self._client_ref()
        if key not in self._sensors:
            declared = {d['id'] for d in c.blueprints(1.0)}
            if blueprint not in declared:
                _unsupported(call, "no running service declares '%s' (start the sensors/render services)" % blueprint)
            attrs = dict(attributes or {})
            attrs.setdefault('role_name', name or blueprint.split('.')[-1])
            sensor = c.spawn(blueprint, pose, attrs, actor)
            slot = [sensor, None]
            self._sensors[key] = slot

            def on_data(sample, slot=slot):
                with self._cv:
                    slot[1] = sample
                    self._cv.notify_all()

            c.listen(sensor, on_data)
        slot = self._sensors[key]
        deadline = time.monotonic() + 10.0
        while True:
            with self._cv:
                if slot[1] is not None:
                    return slot[1]
            if c.world_info()['settings']['synchronous_mode']:
                c.tick()
            else:
                with self._cv:
                    self._cv.wait(0.1)
            if time.monotonic() > deadline:
                raise lockstep.ClientError('%s: sensor %s (%s) delivered no data within 10 s' % (call, slot[0], blueprint))


_attached = weakref.WeakKeyDictionary()   # session (lockstep.Client) -> its (run, _AttachedSensors)
_attached_lock = threading.Lock()


# AirSim 1.8's ImuSimpleParams: gyro bias stability 4.6 deg/h, accel 36 ug (SI units).
_AIRSIM_IMU_ATTRIBUTES = {'noise_gyro_bias_stability': repr(4.6 / 3600 * math.pi / 180),
                          'noise_accel_bias_stability': repr(36e-6 * 9.80665)}


def _attached_sensors(client):
    """The session's attached sensors of its current run (a reset starts a new set)."""
    run = client.world_info()['run']
    with _attached_lock:
        entry = _attached.get(client)
        if entry is None or entry[0] != run:
            entry = (run, _AttachedSensors(client))
            _attached[client] = entry
        return entry[1]


class MultirotorClient:
    def __init__(self, ip='', port=41451, timeout_value=3600):
        self._ip, self._port = ip, port
        self._client = lockstep.session(timeout=float(os.environ.get('LOCKSTEP_CONNECT_TIMEOUT', '10')))
        self._mc = lockstep.Multirotor(self._client)
        self._paused_from = None   # settings before simPause(True)
        self._weather = {}

    # --- connection and vehicles ---
    def confirmConnection(self):
        info = self._client.world_info()
        print('Connected to Lockstep (DDS domain %d, map %s, run %d)' % (self._client.domain, info['map_name'], info['run']))

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

    def _drone(self, vehicle_name):
        try:
            return self._mc.resolve(vehicle_name)
        except lockstep.ClientError:
            if self._client.actors() and any(a['kind'] == 'drone' for a in self._client.actors()):
                raise
        # AirSim always starts with a drone ("SimpleFlight"): spawn one at the map's first spawn point.
        name = vehicle_name or 'SimpleFlight'
        x, y, z, yaw = self._default_spawn()
        self._mc.add_vehicle(name, 'drone.generic_quad', (x, y, z) + _quat_yaw_pitch(yaw, 0))
        self._settle()
        return self._mc.resolve(vehicle_name)

    def _default_spawn(self):
        env = os.environ.get('LOCKSTEP_DRONE_SPAWN')  # "x,y,z[,yaw_deg]" in world ENU
        if env:
            v = [float(p) for p in env.split(',')]
            return v[0], v[1], v[2], math.radians(v[3]) if len(v) > 3 else 0.0
        try:
            p = self._client.map().spawn_points(25.0)[0]
            return p[0], p[1], 0.0, p[3]
        except lockstep.ClientError:
            return 0.0, 0.0, 0.0, 0.0

    def _settle(self):
        """Wait until the drone appears in the air state (one tick in synchronous mode)."""
        if self._client.world_info()['settings']['synchronous_mode']:
            self._client.tick()
        else:
            self._client.wait_for_tick(10.0)
            self._client.wait_for_tick(10.0)

    def listVehicles(self):
        return self._mc.list_vehicles()

    def simAddVehicle(self, vehicle_name, vehicle_type, pose, pawn_path=''):
        """Spawns a drone; pose is NED from the first drone's home (AirSim's world NED)."""
        if vehicle_type.lower() not in ('simpleflight', 'px4multirotor', 'arducopter', ''):
            _unsupported('simAddVehicle(%r)' % vehicle_type, 'Lockstep simulates multirotors only on the AirSim side')
        try:
            home = self._mc.home('')
        except lockstep.ClientError:
            x, y, z, _ = self._default_spawn()
            home = (x, y, z)
        p = pose.position
        x, y, z = home[0] + p.y_val, home[1] + p.x_val, home[2] - p.z_val
        yaw = math.radians(90) - self._yaw_of(pose.orientation)
        self._mc.add_vehicle(vehicle_name, 'drone.generic_quad', (x, y, z) + _quat_yaw_pitch(yaw, 0))
        self._settle()
        return True

    @staticmethod
    def _yaw_of(q):
        from .types import to_eularian_angles
        return to_eularian_angles(q)[2]

    def reset(self):
        self._client.reset(0)

    def enableApiControl(self, is_enabled, vehicle_name=''):
        self._drone(vehicle_name)
        self._mc.enable_api_control(is_enabled, vehicle_name)

    def isApiControlEnabled(self, vehicle_name=''):
        return self._mc.is_api_control_enabled(vehicle_name)

    def armDisarm(self, arm, vehicle_name=''):
        self._drone(vehicle_name)
        return self._mc.arm_disarm(arm, vehicle_name)

    # --- the clock ---
    def simPause(self, is_paused):
        """Paused = synchronous mode: the clock stops until simContinueFor* ticks it."""
        s = self._client.world_info()['settings']
        if is_paused and not s['synchronous_mode']:
            self._paused_from = s
            self._client.apply_settings({'synchronous_mode': True})
        elif not is_paused and s['synchronous_mode']:
            self._client.apply_settings({'synchronous_mode': False})

    def simIsPause(self):
        return self._client.world_info()['settings']['synchronous_mode']

    def simContinueForTime(self, seconds):
        dt = self._client.world_info()['settings']['fixed_delta_seconds']
        self.simContinueForFrames(max(1, int(round(seconds / dt))))

    def simContinueForFrames(self, frames):
        was_paused = self.simIsPause()
        if not was_paused:
            self.simPause(True)
        for _ in range(int(frames)):
            self._client.tick()
        if not was_paused:
            self.simPause(False)

    def simGetTime(self):
        return self._client.frame() * self._client.world_info()['settings']['fixed_delta_seconds']

    # --- commands ---
    def takeoffAsync(self, timeout_sec=20, vehicle_name=''):
        self._drone(vehicle_name)
        return _Future(self._mc.takeoff(timeout_sec, vehicle_name))

    def landAsync(self, timeout_sec=60, vehicle_name=''):
        return _Future(self._mc.land(timeout_sec, vehicle_name))

    def goHomeAsync(self, timeout_sec=3e+38, vehicle_name=''):
        return _Future(self._mc.go_home(timeout_sec, vehicle_name))

    def hoverAsync(self, vehicle_name=''):
        return _Future(self._mc.hover(vehicle_name))

    def cancelLastTask(self, vehicle_name=''):
        self._mc.cancel(vehicle_name)

    def moveToPositionAsync(self, x, y, z, velocity, timeout_sec=3e+38, drivetrain=DrivetrainType.MaxDegreeOfFreedom,
                            yaw_mode=YawMode(), lookahead=-1, adaptive_lookahead=1, vehicle_name=''):
        return _Future(self._mc.move_to_position(x, y, z, velocity, timeout_sec, drivetrain, yaw_mode.is_rate,
                                                 yaw_mode.yaw_or_rate, lookahead, vehicle_name))

    def moveToZAsync(self, z, velocity, timeout_sec=3e+38, yaw_mode=YawMode(), lookahead=-1, adaptive_lookahead=1,
                     vehicle_name=''):
        return _Future(self._mc.move_to_z(z, velocity, timeout_sec, yaw_mode.is_rate, yaw_mode.yaw_or_rate, lookahead,
                                          vehicle_name))

    def moveOnPathAsync(self, path, velocity, timeout_sec=3e+38, drivetrain=DrivetrainType.MaxDegreeOfFreedom,
                        yaw_mode=YawMode(), lookahead=-1, adaptive_lookahead=1, vehicle_name=''):
        pts = [(p.x_val, p.y_val, p.z_val) for p in path]
        return _Future(self._mc.move_on_path(pts, velocity, timeout_sec, drivetrain, yaw_mode.is_rate,
                                             yaw_mode.yaw_or_rate, lookahead, vehicle_name))

    def moveByVelocityAsync(self, vx, vy, vz, duration, drivetrain=DrivetrainType.MaxDegreeOfFreedom, yaw_mode=YawMode(),
                            vehicle_name=''):
        return _Future(self._mc.move_by_velocity(vx, vy, vz, duration, drivetrain, yaw_mode.is_rate,
                                                 yaw_mode.yaw_or_rate, False, vehicle_name))

    def moveByVelocityBodyFrameAsync(self, vx, vy, vz, duration, drivetrain=DrivetrainType.MaxDegreeOfFreedom,
                                     yaw_mode=YawMode(), vehicle_name=''):
        return _Future(self._mc.move_by_velocity(vx, vy, vz, duration, drivetrain, yaw_mode.is_rate,
                                                 yaw_mode.yaw_or_rate, True, vehicle_name))

    def moveByVelocityZAsync(self, vx, vy, z, duration, drivetrain=DrivetrainType.MaxDegreeOfFreedom, yaw_mode=YawMode(),
                             vehicle_name=''):
        return _Future(self._mc.move_by_velocity_z(vx, vy, z, duration, drivetrain, yaw_mode.is_rate,
                                                   yaw_mode.yaw_or_rate, vehicle_name))

    def rotateToYawAsync(self, yaw, timeout_sec=3e+38, margin=5, vehicle_name=''):
        return _Future(self._mc.rotate_to_yaw(yaw, timeout_sec, margin, vehicle_name))

    def rotateByYawRateAsync(self, yaw_rate, duration, vehicle_name=''):
        return _Future(self._mc.rotate_by_yaw_rate(yaw_rate, duration, vehicle_name))

    def moveByRollPitchYawThrottleAsync(self, roll, pitch, yaw, throttle, duration, vehicle_name=''):
        return _Future(self._mc.move_by_rpy_throttle(roll, pitch, yaw, throttle, duration, vehicle_name))

    def moveByRollPitchYawZAsync(self, roll, pitch, yaw, z, duration, vehicle_name=''):
        return _Future(self._mc.move_by_rpy_z(roll, pitch, yaw, z, duration, vehicle_name))

    def moveByAngleRatesThrottleAsync(self, roll_rate, pitch_rate, yaw_rate, throttle, duration, vehicle_name=''):
        return _Future(self._mc.move_by_angle_rates_throttle(roll_rate, pitch_rate, yaw_rate, throttle, duration,
                                                             vehicle_name))

    def moveByMotorPWMsAsync(self, front_right_pwm, rear_left_pwm, front_left_pwm, rear_right_pwm, duration,
                             vehicle_name=''):
        return _Future(self._mc.move_by_motor_pwms([front_right_pwm, rear_left_pwm, front_left_pwm, rear_right_pwm],
                                                   duration, vehicle_name))

    def trackTargetAsync(self, position, velocity, max_speed=0.0, duration=1.0, vehicle_name=''):
        """Lockstep extension: follow a moving target (NED position m, velocity m/s, from this drone's home)."""
        return _Future(self._mc.track_target(tuple(position), tuple(velocity), max_speed, duration, vehicle_name))

    def moveByManualAsync(self, *args, **kwargs):
        _unsupported('moveByManualAsync', 'there is no RC input on the wire')

    def moveByRC(self, *args, **kwargs):
        _unsupported('moveByRC', 'there is no RC input on the wire')

    def moveByRollPitchYawrateThrottleAsync(self, roll, pitch, yaw_rate, throttle, duration, vehicle_name=''):
        return _Future(self._mc.move_by_rp_yawrate_throttle(roll, pitch, yaw_rate, throttle, duration, vehicle_name))

    def moveByRollPitchYawrateZAsync(self, roll, pitch, yaw_rate, z, duration, vehicle_name=''):
        return _Future(self._mc.move_by_rp_yawrate_z(roll, pitch, yaw_rate, z, duration, vehicle_name))

    def moveByAngleRatesZAsync(self, roll_rate, pitch_rate, yaw_rate, z, duration, vehicle_name=''):
        return _Future(self._mc.move_by_angle_rates_z(roll_rate, pitch_rate, yaw_rate, z, duration, vehicle_name))

    def moveToGPSAsync(self, latitude, longitude, altitude, velocity, timeout_sec=3e+38,
                       drivetrain=DrivetrainType.MaxDegreeOfFreedom, yaw_mode=YawMode(), lookahead=-1, adaptive_lookahead=1,
                       vehicle_name=''):
        return _Future(self._mc.move_to_gps(latitude, longitude, altitude, velocity, timeout_sec, drivetrain,
                                            yaw_mode.is_rate, yaw_mode.yaw_or_rate, lookahead, adaptive_lookahead,
                                            vehicle_name))

    # The terms air_sim's loops have (docs/compatibility.md): the others must be 0.
    _GAIN_TERMS = {'angle_rate': 'pid', 'angle_level': 'p', 'velocity': 'pi', 'position': 'p'}

    def _set_gains(self, call, loop, gains, vehicle_name):
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

    def simSetWind(self, wind):
        """One wind (m/s, world NED) for every drone, added to the weather's wind."""
        self._mc.set_wind((wind.x_val, wind.y_val, wind.z_val))

    def simSetKinematics(self, state, ignore_collision, vehicle_name=''):
        """Pose, linear velocity (world NED) and angular velocity (body FRD) at once; accelerations are ignored
        (air_sim derives them from the next step)."""
        self._drone(vehicle_name)
        o = state.orientation

        def t(v):
            return (v.x_val, v.y_val, v.z_val)
        self._mc.set_kinematics(t(state.position), (o.w_val, o.x_val, o.y_val, o.z_val), t(state.linear_velocity),
                                t(state.angular_velocity), vehicle_name)

    # --- state ---
    def getMultirotorState(self, vehicle_name=''):
        self._drone(vehicle_name)
        s = self._mc.state(vehicle_name)
        out = MultirotorState()
        k = out.kinematics_estimated
        k.position = _v(s['position'])
        k.orientation = _q(s['orientation'])
        k.linear_velocity = _v(s['linear_velocity'])
        k.angular_velocity = _v(s['angular_velocity'])
        k.linear_acceleration = _v(s['linear_acceleration'])
        k.angular_acceleration = _v(s['angular_acceleration'])
        out.collision = self._collision(s['collision'])
        out.timestamp = s['timestamp']
        out.landed_state = LandedState.Landed if s['landed'] else LandedState.Flying
        out.can_arm = True
        return out

    def getRotorStates(self, vehicle_name=''):
        s = self._mc.state(vehicle_name)
        out = RotorStates()
        out.timestamp = s['timestamp']
        out.rotors = [{'speed': sp, 'thrust': th, 'torque_scaler': 0.0}
                      for sp, th in zip(s['rotor_speeds'], s['rotor_thrusts'])]
        return out

    def simGetGroundTruthKinematics(self, vehicle_name=''):
        return self.getMultirotorState(vehicle_name).kinematics_estimated

    def _collision(self, c):
        has, normal, impact, pos, depth, obj_id, obj_name, frame = c
        out = CollisionInfo()
        out.has_collided = has
        out.normal, out.impact_point, out.position = _v(normal), _v(impact), _v(pos)
        out.penetration_depth = depth
        out.object_id = obj_id if obj_name else -1
        out.object_name = obj_name
        out.time_stamp = frame
        return out

    def simGetCollisionInfo(self, vehicle_name=''):
        self._drone(vehicle_name)
        return self._collision(self._mc.state(vehicle_name)['collision'])

    def simGetVehiclePose(self, vehicle_name=''):
        self._drone(vehicle_name)
        p, q = self._mc.pose(vehicle_name)
        return Pose(_v(p), _q(q))

    def simSetVehiclePose(self, pose, ignore_collision, vehicle_name=''):
        o = pose.orientation
        self._mc.set_pose((pose.position.x_val, pose.position.y_val, pose.position.z_val),
                          (o.w_val, o.x_val, o.y_val, o.z_val), vehicle_name)

    def getHomeGeoPoint(self, vehicle_name=''):
        return self.getGpsData('', vehicle_name).gnss.geo_point

    # --- sensors (spawned on first use, attached to the drone) ---
    def getImuData(self, imu_name='', vehicle_name=''):
        # AirSim's IMU bias instability (a random walk; sensor.other.imu has it off, as CARLA).
        s = _attached_sensors(self._client).latest('getImuData', self._drone(vehicle_name), 'sensor.other.imu', imu_name,
                                                   _AIRSIM_IMU_ATTRIBUTES)
        f = s.fields()
        out = ImuData()
        out.time_stamp = int(s.sim_time * 1e9)
        from lockstep._lockstep import Multirotor  # noqa: F401 (same process)
        a, g = f['accelerometer'], f['gyroscope']
        out.linear_acceleration = Vector3r(a[0], -a[1], -a[2])   # FLU -> FRD
        out.angular_velocity = Vector3r(g[0], -g[1], -g[2])
        w, x, y, z = f['orientation']
        out.orientation = self._ned_quat((w, x, y, z))
        return out

    @staticmethod
    def _ned_quat(q):
        # ENU/FLU -> NED/FRD: q_ned = qA * q * qB (see lockstep/client/multirotor.h).
        def mul(a, b):
            aw, ax, ay, az = a
            bw, bx, by, bz = b
            return (aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
                    aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw)
        r = mul(mul((0, math.sqrt(0.5), math.sqrt(0.5), 0), q), (0, 1, 0, 0))
        if r[0] < 0:
            r = tuple(-v for v in r)
        return Quaternionr(r[1], r[2], r[3], r[0])

    def getGpsData(self, gps_name='', vehicle_name=''):
        s = _attached_sensors(self._client).latest('getGpsData', self._drone(vehicle_name), 'sensor.other.gnss', gps_name)
        f = s.fields()
        out = GpsData()
        out.time_stamp = int(s.sim_time * 1e9)
        out.gnss.geo_point = GeoPoint(f['latitude'], f['longitude'], f['altitude'])
        out.gnss.eph, out.gnss.epv = f['eph'], f['epv']
        out.gnss.fix_type = 3 if f['fix'] else 0
        out.is_valid = True
        return out

    def getBarometerData(self, barometer_name='', vehicle_name=''):
        s = _attached_sensors(self._client).latest('getBarometerData', self._drone(vehicle_name), 'sensor.other.barometer', barometer_name)
        f = s.fields()
        out = BarometerData()
        out.time_stamp = int(s.sim_time * 1e9)
        out.altitude, out.pressure, out.qnh = f['altitude'], f['pressure'], f['qnh']
        return out

    def getMagnetometerData(self, magnetometer_name='', vehicle_name=''):
        s = _attached_sensors(self._client).latest('getMagnetometerData', self._drone(vehicle_name), 'sensor.other.magnetometer',
                                 magnetometer_name)
        m = s.fields()['magnetic_field']
        out = MagnetometerData()
        out.time_stamp = int(s.sim_time * 1e9)
        out.magnetic_field_body = Vector3r(m[0], -m[1], -m[2])
        return out

    def getDistanceSensorData(self, distance_sensor_name='', vehicle_name=''):
        s = _attached_sensors(self._client).latest('getDistanceSensorData', self._drone(vehicle_name), 'sensor.other.distance',
                                 distance_sensor_name)
        f = s.fields()
        out = DistanceSensorData()
        out.time_stamp = int(s.sim_time * 1e9)
        out.distance, out.min_distance, out.max_distance = f['distance'], f['min_distance'], f['max_distance']
        return out

    def getLidarData(self, lidar_name='', vehicle_name=''):
        s = _attached_sensors(self._client).latest('getLidarData', self._drone(vehicle_name), 'sensor.lidar.ray_cast', lidar_name)
        pts = np.array(s.array(), dtype=np.float32)[:, :3]
        pts[:, 1] *= -1   # FLU -> FRD
        pts[:, 2] *= -1
        out = LidarData()
        out.time_stamp = int(s.sim_time * 1e9)
        out.point_cloud = pts.reshape(-1).tolist()
        return out

    def simGetImages(self, requests, vehicle_name='', external=False):
        if external:
            _unsupported('simGetImages(external=True)', 'external cameras are spawned with the CARLA API')
        actor = self._drone(vehicle_name)
        out = []
        for r in requests:
            bp = _IMAGE_BLUEPRINTS.get(r.image_type)
            if bp is None:
                _unsupported('simGetImages(image_type=%d)' % r.image_type, 'no camera renders that image type')
            mount = _CAMERAS.get(str(r.camera_name))
            if mount is None:
                _unsupported("simGetImages(camera_name=%r)" % r.camera_name, 'cameras are named %s' % sorted(_CAMERAS))
            (x, y, z), pitch = mount
            pose = (x, y, z) + _quat_yaw_pitch(math.radians(180) if pitch == 180 else 0.0,
                                               -math.radians(pitch) if pitch != 180 else 0.0)
            s = _attached_sensors(self._client).latest('simGetImages', actor, bp, 'camera_%s_%d' % (r.camera_name, r.image_type),
                                     {'image_size_x': '256', 'image_size_y': '144', 'fov': '90'}, pose)
            out.append(self._image_response(s, r))
        return out

    def simGetImage(self, camera_name, image_type, vehicle_name='', external=False):
        from .types import ImageRequest
        return self.simGetImages([ImageRequest(camera_name, image_type, False, True)], vehicle_name)[0].image_data_uint8

    @staticmethod
    def _image_response(s, r):
        f = s.fields()
        resp = ImageResponse()
        resp.camera_name = r.camera_name
        resp.image_type = r.image_type
        resp.width, resp.height = f['width'], f['height']
        resp.time_stamp = int(s.sim_time * 1e9)
        resp.frame = s.frame
        resp.pixels_as_float = r.pixels_as_float
        resp.compress = r.compress
        a = s.array()
        if r.pixels_as_float:
            if a.ndim == 2:
                resp.image_data_float = a.astype(np.float32).reshape(-1).tolist()
            else:
                b, g, rr = a[..., 0].astype(np.float64), a[..., 1].astype(np.float64), a[..., 2].astype(np.float64)
                resp.image_data_float = (1000.0 * (rr + g * 256 + b * 65536) / (256 ** 3 - 1)).reshape(-1).tolist()
            return resp
        if a.ndim == 2:
            a = np.repeat(np.clip(a / max(float(a.max()), 1e-6) * 255, 0, 255).astype(np.uint8)[..., None], 4, axis=2)
        bgr = np.ascontiguousarray(a[..., :3])
        resp.image_data_uint8 = _png(np.ascontiguousarray(bgr[..., ::-1])) if r.compress else bgr.tobytes()
        return resp

    # --- weather ---
    def simEnableWeather(self, enable):
        self._weather_enabled = bool(enable)

    def simSetWeatherParameter(self, param, val):
        """AirSim's weather (0..1) mapped onto CARLA's WeatherParameters (0..100)."""
        fields = {WeatherParameter.Rain: 'precipitation', WeatherParameter.Roadwetness: 'wetness',
                  WeatherParameter.Fog: 'fog_density', WeatherParameter.Dust: 'dust_storm'}
        if param not in fields:
            _unsupported('simSetWeatherParameter(%d)' % param, 'snow and leaves are not rendered')
        self._client.set_weather({fields[param]: float(val) * 100.0})

    # --- not supported ---
    def simGetObjectPose(self, object_name):
        _unsupported('simGetObjectPose', 'scene objects are not exposed over the wire')

    def simSetObjectPose(self, *args, **kwargs):
        _unsupported('simSetObjectPose', 'scene objects are not exposed over the wire')

    def simListSceneObjects(self, *args, **kwargs):
        _unsupported('simListSceneObjects', 'scene objects are not exposed over the wire')

    def simSetSegmentationObjectID(self, *args, **kwargs):
        _unsupported('simSetSegmentationObjectID', "segmentation ids are CARLA's semantic tags")

    def simPrintLogMessage(self, message, message_param='', severity=0):
        print('%s %s' % (message, message_param))

    def simFlushPersistentMarkers(self):
        _unsupported('simFlushPersistentMarkers', 'there is no viewport to draw in')

    def simPlotPoints(self, *args, **kwargs):
        _unsupported('simPlotPoints', 'there is no viewport to draw in')

    def simPlotLineStrip(self, *args, **kwargs):
        _unsupported('simPlotLineStrip', 'there is no viewport to draw in')

    def simSetTimeOfDay(self, *args, **kwargs):
        _unsupported('simSetTimeOfDay', "set the sun angles with the CARLA API's WeatherParameters")

    def simSetCameraPose(self, *args, **kwargs):
        _unsupported('simSetCameraPose', 'cameras are fixed mounts; spawn others with the CARLA API')

    def simSetCameraFov(self, *args, **kwargs):
        _unsupported('simSetCameraFov', "a camera's fov is a spawn attribute; spawn another with the CARLA API")

    def simGetSegmentationObjectID(self, *args, **kwargs):
        _unsupported('simGetSegmentationObjectID', "segmentation ids are CARLA's semantic tags")



VehicleClient = MultirotorClient
