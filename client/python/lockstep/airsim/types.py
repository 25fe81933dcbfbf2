"""airsim's message types (Vector3r, Quaternionr, Pose, YawMode, ...), same names and fields."""
import math

__all__ = ['Vector3r', 'Vector2r', 'Quaternionr', 'Pose', 'YawMode', 'DrivetrainType', 'LandedState', 'ImageType',
           'ImageRequest', 'ImageResponse', 'KinematicsState', 'CollisionInfo', 'GeoPoint', 'MultirotorState',
           'RCData', 'ImuData', 'GnssReport', 'GpsData', 'BarometerData', 'MagnetometerData', 'DistanceSensorData',
           'LidarData', 'WeatherParameter', 'to_quaternion', 'to_eularian_angles', 'EnvironmentState', 'RotorStates',
           'PIDGains', 'AngleRateControllerGains', 'AngleLevelControllerGains', 'VelocityControllerGains',
           'PositionControllerGains', 'GnssFixType', 'ProjectionMatrix', 'CameraInfo', 'Box2D', 'Box3D', 'DetectionInfo',
           'CarControls', 'CarState', 'MeshPositionVertexBuffersResponse', 'MsgpackMixin']


def _is_number(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool) or type(v).__module__ == 'numpy' and \
        getattr(v, 'ndim', 1) == 0


class MsgpackMixin:
    """AirSim's base of its message types: repr of the fields, to_msgpack / from_msgpack."""

    def __repr__(self):
        from pprint import pformat
        return '<' + type(self).__name__ + '> ' + pformat(vars(self), indent=4, width=1)

    def to_msgpack(self, *args, **kwargs):
        return self.__dict__

    @classmethod
    def from_msgpack(cls, encoded):
        obj = cls()
        obj.__dict__ = {k: (v if not isinstance(v, dict) else getattr(getattr(obj, k).__class__, 'from_msgpack')(v))
                        for k, v in encoded.items()}
        return obj


class Vector2r(MsgpackMixin):
    def __init__(self, x_val=0.0, y_val=0.0):
        self.x_val, self.y_val = x_val, y_val


class Vector3r(MsgpackMixin):
    def __init__(self, x_val=0.0, y_val=0.0, z_val=0.0):
        self.x_val, self.y_val, self.z_val = x_val, y_val, z_val

    @staticmethod
    def nanVector3r():
        return Vector3r(math.nan, math.nan, math.nan)

    def containsNan(self):
        return any(math.isnan(v) for v in (self.x_val, self.y_val, self.z_val))

    def __add__(self, o):
        return Vector3r(self.x_val + o.x_val, self.y_val + o.y_val, self.z_val + o.z_val)

    def __sub__(self, o):
        return Vector3r(self.x_val - o.x_val, self.y_val - o.y_val, self.z_val - o.z_val)

    def __truediv__(self, k):
        if not _is_number(k):
            raise TypeError('unsupported operand type(s) for /: %s and %s' % (type(self), type(k)))
        return Vector3r(self.x_val / k, self.y_val / k, self.z_val / k)

    def __mul__(self, k):
        if not _is_number(k):
            raise TypeError('unsupported operand type(s) for *: %s and %s' % (type(self), type(k)))
        return Vector3r(self.x_val * k, self.y_val * k, self.z_val * k)

    def dot(self, o):
        if type(self) is not type(o):
            raise TypeError("unsupported operand type(s) for 'dot': %s and %s" % (type(self), type(o)))
        return self.x_val * o.x_val + self.y_val * o.y_val + self.z_val * o.z_val

    def cross(self, o):
        if type(self) is not type(o):
            raise TypeError("unsupported operand type(s) for 'cross': %s and %s" % (type(self), type(o)))
        return Vector3r(self.y_val * o.z_val - self.z_val * o.y_val, self.z_val * o.x_val - self.x_val * o.z_val,
                        self.x_val * o.y_val - self.y_val * o.x_val)

    def get_length(self):
        return (self.x_val ** 2 + self.y_val ** 2 + self.z_val ** 2) ** 0.5

    def distance_to(self, o):
        return ((self.x_val - o.x_val) ** 2 + (self.y_val - o.y_val) ** 2 + (self.z_val - o.z_val) ** 2) ** 0.5

    def to_Quaternionr(self):
        return Quaternionr(self.x_val, self.y_val, self.z_val, 0)

    def to_numpy_array(self):
        import numpy as np
        return np.array([self.x_val, self.y_val, self.z_val], dtype=np.float32)

    def __iter__(self):
        return iter((self.x_val, self.y_val, self.z_val))


class Quaternionr(MsgpackMixin):
    def __init__(self, x_val=0.0, y_val=0.0, z_val=0.0, w_val=1.0):
        self.x_val, self.y_val, self.z_val, self.w_val = x_val, y_val, z_val, w_val

    @staticmethod
    def nanQuaternionr():
        return Quaternionr(math.nan, math.nan, math.nan, math.nan)

    def containsNan(self):
        return any(math.isnan(v) for v in (self.w_val, self.x_val, self.y_val, self.z_val))

    def _same(self, o, op):
        if type(self) is not type(o):
            raise TypeError("unsupported operand type(s) for %s: %s and %s" % (op, type(self), type(o)))

    def __add__(self, o):
        self._same(o, '+')
        return Quaternionr(self.x_val + o.x_val, self.y_val + o.y_val, self.z_val + o.z_val, self.w_val + o.w_val)

    def __sub__(self, o):
        self._same(o, '-')
        return Quaternionr(self.x_val - o.x_val, self.y_val - o.y_val, self.z_val - o.z_val, self.w_val - o.w_val)

    def __mul__(self, o):
        self._same(o, '*')
        t, x, y, z = self.w_val, self.x_val, self.y_val, self.z_val
        a, b, c, d = o.w_val, o.x_val, o.y_val, o.z_val
        return Quaternionr(w_val=a * t - b * x - c * y - d * z, x_val=b * t + a * x + d * y - c * z,
                           y_val=c * t + a * y + b * z - d * x, z_val=d * t + z * a + c * x - b * y)

    def __truediv__(self, o):
        if type(o) is type(self):
            return self * o.inverse()
        if _is_number(o):
            return Quaternionr(self.x_val / o, self.y_val / o, self.z_val / o, self.w_val / o)
        raise TypeError('unsupported operand type(s) for /: %s and %s' % (type(self), type(o)))

    def dot(self, o):
        self._same(o, "'dot'")
        return self.x_val * o.x_val + self.y_val * o.y_val + self.z_val * o.z_val + self.w_val * o.w_val

    def cross(self, o):
        self._same(o, "'cross'")
        return (self * o - o * self) / 2

    def outer_product(self, o):
        self._same(o, "'outer_product'")
        return (self.inverse() * o - o.inverse() * self) / 2

    def rotate(self, o):
        """AirSim's: this quaternion rotated by the unit quaternion `o` (o * self * o^-1)."""
        self._same(o, "'rotate'")
        if o.get_length() == 1:
            return o * self * o.inverse()
        raise ValueError('length of the other Quaternionr must be 1')

    def conjugate(self):
        return Quaternionr(-self.x_val, -self.y_val, -self.z_val, self.w_val)

    def star(self):
        return self.conjugate()

    def inverse(self):
        return self.star() / self.dot(self)

    def sgn(self):
        return self / self.get_length()

    def get_length(self):
        return (self.x_val ** 2 + self.y_val ** 2 + self.z_val ** 2 + self.w_val ** 2) ** 0.5

    def to_numpy_array(self):
        import numpy as np
        return np.array([self.x_val, self.y_val, self.z_val, self.w_val], dtype=np.float32)

    def __iter__(self):
        return iter((self.x_val, self.y_val, self.z_val, self.w_val))


def _rotate_vector(q, v):
    """v (Vector3r) rotated by the rotation of q (not necessarily unit)."""
    n = q.get_length()
    u = q / n if n > 0 else Quaternionr()
    r = u * Quaternionr(v.x_val, v.y_val, v.z_val, 0) * u.conjugate()
    return Vector3r(r.x_val, r.y_val, r.z_val)


class Pose(MsgpackMixin):
    def __init__(self, position_val=None, orientation_val=None):
        self.position = position_val if position_val is not None else Vector3r()
        self.orientation = orientation_val if orientation_val is not None else Quaternionr()

    @staticmethod
    def nanPose():
        return Pose(Vector3r.nanVector3r(), Quaternionr.nanQuaternionr())

    def containsNan(self):
        return self.position.containsNan() or self.orientation.containsNan()

    def __iter__(self):
        return iter((self.position, self.orientation))


class YawMode(MsgpackMixin):
    def __init__(self, is_rate=True, yaw_or_rate=0.0):
        self.is_rate, self.yaw_or_rate = is_rate, yaw_or_rate


class DrivetrainType:
    MaxDegreeOfFreedom = 0
    ForwardOnly = 1


class LandedState:
    Landed = 0
    Flying = 1


class WeatherParameter:
    Rain = 0
    Roadwetness = 1
    Snow = 2
    RoadSnow = 3
    MapleLeaf = 4
    RoadLeaf = 5
    Dust = 6
    Fog = 7
    Enabled = 8


class ImageType:
    Scene = 0
    DepthPlanar = 1
    DepthPerspective = 2
    DepthVis = 3
    DisparityNormalized = 4
    Segmentation = 5
    SurfaceNormals = 6
    Infrared = 7
    OpticalFlow = 8
    OpticalFlowVis = 9


class ImageRequest(MsgpackMixin):
    def __init__(self, camera_name, image_type, pixels_as_float=False, compress=True):
        self.camera_name = str(camera_name)
        self.image_type = image_type
        self.pixels_as_float = pixels_as_float
        self.compress = compress


class ImageResponse(MsgpackMixin):
    def __init__(self):
        self.image_data_uint8 = b''
        self.image_data_float = []
        self.camera_name = ''
        self.camera_position = Vector3r()
        self.camera_orientation = Quaternionr()
        self.time_stamp = 0
        self.message = ''
        self.pixels_as_float = False
        self.compress = True
        self.width = 0
        self.height = 0
        self.image_type = ImageType.Scene
        self.frame = 0  # Lockstep: the frame the image shows


class KinematicsState(MsgpackMixin):
    def __init__(self):
        self.position = Vector3r()
        self.orientation = Quaternionr()
        self.linear_velocity = Vector3r()
        self.angular_velocity = Vector3r()
        self.linear_acceleration = Vector3r()
        self.angular_acceleration = Vector3r()


class PIDGains:
    """One axis of a controller: proportional, integral and derivative gains."""

    def __init__(self, kp, ki, kd):
        self.kp, self.ki, self.kd = kp, ki, kd

    def to_list(self):
        return [self.kp, self.ki, self.kd]


class AngleRateControllerGains:
    def __init__(self, roll_gains=PIDGains(0.25, 0, 0), pitch_gains=PIDGains(0.25, 0, 0), yaw_gains=PIDGains(0.25, 0, 0)):
        self.roll_gains, self.pitch_gains, self.yaw_gains = roll_gains, pitch_gains, yaw_gains

    def to_lists(self):
        g = (self.roll_gains, self.pitch_gains, self.yaw_gains)
        return [x.kp for x in g], [x.ki for x in g], [x.kd for x in g]


class AngleLevelControllerGains(AngleRateControllerGains):
    def __init__(self, roll_gains=PIDGains(2.5, 0, 0), pitch_gains=PIDGains(2.5, 0, 0), yaw_gains=PIDGains(2.5, 0, 0)):
        super().__init__(roll_gains, pitch_gains, yaw_gains)


class VelocityControllerGains:
    def __init__(self, x_gains=PIDGains(0.2, 0, 0), y_gains=PIDGains(0.2, 0, 0), z_gains=PIDGains(2.0, 2.0, 0)):
        self.x_gains, self.y_gains, self.z_gains = x_gains, y_gains, z_gains

    def to_lists(self):
        g = (self.x_gains, self.y_gains, self.z_gains)
        return [x.kp for x in g], [x.ki for x in g], [x.kd for x in g]


class PositionControllerGains(VelocityControllerGains):
    def __init__(self, x_gains=PIDGains(0.25, 0, 0), y_gains=PIDGains(0.25, 0, 0), z_gains=PIDGains(0.25, 0, 0)):
        super().__init__(x_gains, y_gains, z_gains)


class EnvironmentState(MsgpackMixin):
    def __init__(self):
        self.position = Vector3r()
        self.geo_point = GeoPoint()
        self.gravity = Vector3r(0, 0, 9.80665)
        self.air_pressure = 101325.0
        self.temperature = 288.15
        self.air_density = 1.225


class CollisionInfo(MsgpackMixin):
    def __init__(self):
        self.has_collided = False
        self.normal = Vector3r()
        self.impact_point = Vector3r()
        self.position = Vector3r()
        self.penetration_depth = 0.0
        self.time_stamp = 0
        self.object_name = ''
        self.object_id = -1


class GeoPoint(MsgpackMixin):
    def __init__(self, latitude=0.0, longitude=0.0, altitude=0.0):
        self.latitude, self.longitude, self.altitude = latitude, longitude, altitude


class RCData(MsgpackMixin):
    def __init__(self, timestamp=0, pitch=0.0, roll=0.0, throttle=0.0, yaw=0.0, switch1=0, switch2=0, switch3=0,
                 switch4=0, switch5=0, switch6=0, switch7=0, switch8=0, is_initialized=False, is_valid=False):
        self.timestamp = timestamp
        self.pitch, self.roll, self.throttle, self.yaw = pitch, roll, throttle, yaw
        self.switch1, self.switch2, self.switch3, self.switch4 = switch1, switch2, switch3, switch4
        self.switch5, self.switch6, self.switch7, self.switch8 = switch5, switch6, switch7, switch8
        self.is_initialized = is_initialized
        self.is_valid = is_valid


class MultirotorState(MsgpackMixin):
    def __init__(self):
        self.collision = CollisionInfo()
        self.kinematics_estimated = KinematicsState()
        self.gps_location = GeoPoint()
        self.timestamp = 0
        self.landed_state = LandedState.Landed
        self.rc_data = RCData()
        self.ready = True
        self.ready_message = ''
        self.can_arm = True


class RotorStates(MsgpackMixin):
    def __init__(self):
        self.timestamp = 0
        self.rotors = []


class ImuData(MsgpackMixin):
    def __init__(self):
        self.time_stamp = 0
        self.orientation = Quaternionr()
        self.angular_velocity = Vector3r()
        self.linear_acceleration = Vector3r()


class GnssReport(MsgpackMixin):
    def __init__(self):
        self.geo_point = GeoPoint()
        self.eph = 0.0
        self.epv = 0.0
        self.velocity = Vector3r()
        self.fix_type = 0
        self.time_utc = 0


class GpsData(MsgpackMixin):
    def __init__(self):
        self.time_stamp = 0
        self.gnss = GnssReport()
        self.is_valid = False


class BarometerData(MsgpackMixin):
    def __init__(self):
        self.time_stamp = 0
        self.altitude = 0.0
        self.pressure = 0.0
        self.qnh = 0.0


class MagnetometerData(MsgpackMixin):
    def __init__(self):
        self.time_stamp = 0
        self.magnetic_field_body = Vector3r()
        self.magnetic_field_covariance = 0.0


class DistanceSensorData(MsgpackMixin):
    def __init__(self):
        self.time_stamp = 0
        self.distance = 0.0
        self.min_distance = 0.0
        self.max_distance = 0.0
        self.relative_pose = Pose()


class LidarData(MsgpackMixin):
    def __init__(self):
        self.point_cloud = []
        self.time_stamp = 0
        self.pose = Pose()
        self.segmentation = []


class GnssFixType(MsgpackMixin):
    GNSS_FIX_NO_FIX = 0
    GNSS_FIX_TIME_ONLY = 1
    GNSS_FIX_2D_FIX = 2
    GNSS_FIX_3D_FIX = 3


class ProjectionMatrix(MsgpackMixin):
    def __init__(self, matrix=None):
        self.matrix = matrix if matrix is not None else []


class CameraInfo(MsgpackMixin):
    def __init__(self):
        self.pose = Pose()
        self.fov = -1
        self.proj_mat = ProjectionMatrix()


class Box2D(MsgpackMixin):
    def __init__(self):
        self.min = Vector2r()
        self.max = Vector2r()


class Box3D(MsgpackMixin):
    def __init__(self):
        self.min = Vector3r()
        self.max = Vector3r()


class DetectionInfo(MsgpackMixin):
    def __init__(self):
        self.name = ''
        self.geo_point = GeoPoint()
        self.box2D = Box2D()
        self.box3D = Box3D()
        self.relative_pose = Pose()


class CarControls(MsgpackMixin):
    def __init__(self, throttle=0, steering=0, brake=0, handbrake=False, is_manual_gear=False, manual_gear=0,
                 gear_immediate=True):
        self.throttle, self.steering, self.brake = throttle, steering, brake
        self.handbrake = handbrake
        self.is_manual_gear, self.manual_gear, self.gear_immediate = is_manual_gear, manual_gear, gear_immediate

    def set_throttle(self, throttle_val, forward):
        self.is_manual_gear = False
        if forward:
            self.manual_gear = 0
            self.throttle = abs(throttle_val)
        else:
            self.manual_gear = -1
            self.throttle = -abs(throttle_val)


class CarState(MsgpackMixin):
    def __init__(self):
        self.speed = 0.0
        self.gear = 0
        self.rpm = 0.0
        self.maxrpm = 0.0
        self.handbrake = False
        self.collision = CollisionInfo()
        self.kinematics_estimated = KinematicsState()
        self.timestamp = 0


class MeshPositionVertexBuffersResponse(MsgpackMixin):
    def __init__(self):
        self.position = Vector3r()
        self.orientation = Quaternionr()
        self.vertices = 0.0
        self.indices = 0.0
        self.name = ''


def to_quaternion(pitch, roll, yaw):
    """AirSim's to_quaternion (radians, NED/FRD)."""
    t0, t1 = math.cos(yaw * 0.5), math.sin(yaw * 0.5)
    t2, t3 = math.cos(roll * 0.5), math.sin(roll * 0.5)
    t4, t5 = math.cos(pitch * 0.5), math.sin(pitch * 0.5)
    q = Quaternionr()
    q.w_val = t0 * t2 * t4 + t1 * t3 * t5
    q.x_val = t0 * t3 * t4 - t1 * t2 * t5
    q.y_val = t0 * t2 * t5 + t1 * t3 * t4
    q.z_val = t1 * t2 * t4 - t0 * t3 * t5
    return q


def to_eularian_angles(q):
    """AirSim's to_eularian_angles: (pitch, roll, yaw) in radians."""
    z, y, x, w = q.z_val, q.y_val, q.x_val, q.w_val
    ysqr = y * y
    roll = math.atan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + ysqr))
    t2 = max(-1.0, min(1.0, 2.0 * (w * y - z * x)))
    pitch = math.asin(t2)
    yaw = math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (ysqr + z * z))
    return pitch, roll, yaw
