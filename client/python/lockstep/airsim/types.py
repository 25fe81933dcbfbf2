"""airsim's message types (Vector3r, Quaternionr, Pose, YawMode, ...), same names and fields."""
import math

__all__ = ['Vector3r', 'Vector2r', 'Quaternionr', 'Pose', 'YawMode', 'DrivetrainType', 'LandedState', 'ImageType',
           'ImageRequest', 'ImageResponse', 'KinematicsState', 'CollisionInfo', 'GeoPoint', 'MultirotorState',
           'RCData', 'ImuData', 'GnssReport', 'GpsData', 'BarometerData', 'MagnetometerData', 'DistanceSensorData',
           'LidarData', 'WeatherParameter', 'to_quaternion', 'to_eularian_angles', 'EnvironmentState', 'RotorStates',
           'PIDGains', 'AngleRateControllerGains', 'AngleLevelControllerGains', 'VelocityControllerGains',
           'PositionControllerGains']


class MsgpackMixin:
    def __repr__(self):
        return '<%s> %s' % (type(self).__name__, {k: v for k, v in self.__dict__.items()})

    def to_msgpack(self, *args, **kwargs):
        return self.__dict__


class Vector2r(MsgpackMixin):
    def __init__(self, x_val=0.0, y_val=0.0):
        self.x_val, self.y_val = x_val, y_val


class Vector3r(MsgpackMixin):
    def __init__(self, x_val=0.0, y_val=0.0, z_val=0.0):
        self.x_val, self.y_val, self.z_val = float(x_val), float(y_val), float(z_val)

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
        return Vector3r(self.x_val / k, self.y_val / k, self.z_val / k)

    def __mul__(self, k):
        return Vector3r(self.x_val * k, self.y_val * k, self.z_val * k)

    __rmul__ = __mul__

    def dot(self, o):
        return self.x_val * o.x_val + self.y_val * o.y_val + self.z_val * o.z_val

    def cross(self, o):
        return Vector3r(self.y_val * o.z_val - self.z_val * o.y_val, self.z_val * o.x_val - self.x_val * o.z_val,
                        self.x_val * o.y_val - self.y_val * o.x_val)

    def get_length(self):
        return math.sqrt(self.dot(self))

    def distance_to(self, o):
        return (self - o).get_length()

    def to_Quaternionr(self):
        return Quaternionr(self.x_val, self.y_val, self.z_val, 0)

    def to_numpy_array(self):
        import numpy as np
        return np.array([self.x_val, self.y_val, self.z_val], dtype=np.float32)

    def __iter__(self):
        return iter((self.x_val, self.y_val, self.z_val))


class Quaternionr(MsgpackMixin):
    def __init__(self, x_val=0.0, y_val=0.0, z_val=0.0, w_val=1.0):
        self.x_val, self.y_val, self.z_val, self.w_val = float(x_val), float(y_val), float(z_val), float(w_val)

    @staticmethod
    def nanQuaternionr():
        return Quaternionr(math.nan, math.nan, math.nan, math.nan)

    def __mul__(self, o):
        t, x, y, z = self.w_val, self.x_val, self.y_val, self.z_val
        a, b, c, d = o.w_val, o.x_val, o.y_val, o.z_val
        return Quaternionr(w_val=a * t - b * x - c * y - d * z, x_val=b * t + a * x + d * y - c * z,
                           y_val=c * t + a * y + b * z - d * x, z_val=d * t + z * a + c * x - b * y)

    def conjugate(self):
        return Quaternionr(-self.x_val, -self.y_val, -self.z_val, self.w_val)

    def inverse(self):
        n = self.get_length() ** 2
        c = self.conjugate()
        return Quaternionr(c.x_val / n, c.y_val / n, c.z_val / n, c.w_val / n)

    def get_length(self):
        return math.sqrt(self.x_val ** 2 + self.y_val ** 2 + self.z_val ** 2 + self.w_val ** 2)

    def rotate(self, v):
        q = self * Quaternionr(v.x_val, v.y_val, v.z_val, 0) * self.inverse()
        return Vector3r(q.x_val, q.y_val, q.z_val)

    def to_numpy_array(self):
        import numpy as np
        return np.array([self.x_val, self.y_val, self.z_val, self.w_val], dtype=np.float32)


class Pose(MsgpackMixin):
    def __init__(self, position_val=None, orientation_val=None):
        self.position = position_val if position_val is not None else Vector3r()
        self.orientation = orientation_val if orientation_val is not None else Quaternionr()

    @staticmethod
    def nanPose():
        return Pose(Vector3r.nanVector3r(), Quaternionr.nanQuaternionr())

    def containsNan(self):
        return self.position.containsNan()


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
    def __init__(self):
        self.timestamp = 0
        self.pitch = self.roll = self.throttle = self.yaw = 0.0
        self.switch1 = self.switch2 = self.switch3 = self.switch4 = 0
        self.switch5 = self.switch6 = self.switch7 = self.switch8 = 0
        self.is_initialized = False
        self.is_valid = False


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
