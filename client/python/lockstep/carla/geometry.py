"""carla.Vector3D, Location, Rotation, Transform, BoundingBox... and the conversion between
CARLA's convention (left-handed: x forward/east, y right = ENU -y, z up; angles in degrees,
pitch up positive, yaw clockwise seen from above) and Lockstep's wire (right-handed ENU,
radians, quaternions)."""
import math

__all__ = ['Vector2D', 'Vector3D', 'Location', 'Rotation', 'Transform', 'BoundingBox', 'Color', 'GeoLocation',
           'to_wire_pose', 'from_wire_pose', 'from_enu_vector', 'to_enu_vector', 'rpy_from_quat']


class Vector2D:
    def __init__(self, x=0.0, y=0.0):
        self.x, self.y = float(x), float(y)

    def length(self):
        return math.hypot(self.x, self.y)

    def __eq__(self, o):
        return isinstance(o, Vector2D) and self.x == o.x and self.y == o.y

    def __repr__(self):
        return 'Vector2D(x=%g, y=%g)' % (self.x, self.y)


class Vector3D:
    __slots__ = ('x', 'y', 'z')

    def __init__(self, x=0.0, y=0.0, z=0.0):
        self.x, self.y, self.z = float(x), float(y), float(z)

    def _new(self, x, y, z):
        return type(self)(x, y, z)

    def __add__(self, o):
        return self._new(self.x + o.x, self.y + o.y, self.z + o.z)

    def __sub__(self, o):
        return self._new(self.x - o.x, self.y - o.y, self.z - o.z)

    def __mul__(self, k):
        return self._new(self.x * k, self.y * k, self.z * k)

    __rmul__ = __mul__

    def __truediv__(self, k):
        return self._new(self.x / k, self.y / k, self.z / k)

    def __neg__(self):
        return self._new(-self.x, -self.y, -self.z)

    def __eq__(self, o):
        return isinstance(o, Vector3D) and self.x == o.x and self.y == o.y and self.z == o.z

    def __ne__(self, o):
        return not self == o

    def __hash__(self):
        return hash((self.x, self.y, self.z))

    def __iter__(self):
        return iter((self.x, self.y, self.z))

    def length(self):
        return math.sqrt(self.x * self.x + self.y * self.y + self.z * self.z)

    def squared_length(self):
        return self.x * self.x + self.y * self.y + self.z * self.z

    def distance(self, o):
        return (self - o).length()

    def distance_squared(self, o):
        return (self - o).squared_length()

    def distance_2d(self, o):
        return math.hypot(self.x - o.x, self.y - o.y)

    def dot(self, o):
        return self.x * o.x + self.y * o.y + self.z * o.z

    def dot_2d(self, o):
        return self.x * o.x + self.y * o.y

    def cross(self, o):
        return Vector3D(self.y * o.z - self.z * o.y, self.z * o.x - self.x * o.z, self.x * o.y - self.y * o.x)

    def make_unit_vector(self):
        n = self.length()
        return self._new(self.x / n, self.y / n, self.z / n) if n > 0 else self._new(0, 0, 0)

    def get_vector_angle(self, o):
        n = self.length() * o.length()
        return math.acos(max(-1.0, min(1.0, self.dot(o) / n))) if n > 0 else 0.0

    def __repr__(self):
        return '%s(x=%.6f, y=%.6f, z=%.6f)' % (type(self).__name__, self.x, self.y, self.z)


class Location(Vector3D):
    __slots__ = ()


class Rotation:
    """Degrees: pitch (nose up positive), yaw (clockwise from +x seen from above), roll."""
    __slots__ = ('pitch', 'yaw', 'roll')

    def __init__(self, pitch=0.0, yaw=0.0, roll=0.0):
        self.pitch, self.yaw, self.roll = float(pitch), float(yaw), float(roll)

    def _matrix(self):
        cp, sp = math.cos(math.radians(self.pitch)), math.sin(math.radians(self.pitch))
        cy, sy = math.cos(math.radians(self.yaw)), math.sin(math.radians(self.yaw))
        cr, sr = math.cos(math.radians(self.roll)), math.sin(math.radians(self.roll))
        # Unreal's rotation matrix (as CARLA's Transform::GetMatrix).
        return [[cp * cy, cy * sp * sr - sy * cr, -cy * sp * cr - sy * sr],
                [cp * sy, sy * sp * sr + cy * cr, -sy * sp * cr + cy * sr],
                [sp, -cp * sr, cp * cr]]

    def get_forward_vector(self):
        m = self._matrix()
        return Vector3D(m[0][0], m[1][0], m[2][0])

    def get_right_vector(self):
        m = self._matrix()
        return Vector3D(m[0][1], m[1][1], m[2][1])

    def get_up_vector(self):
        m = self._matrix()
        return Vector3D(m[0][2], m[1][2], m[2][2])

    def __eq__(self, o):
        return isinstance(o, Rotation) and (self.pitch, self.yaw, self.roll) == (o.pitch, o.yaw, o.roll)

    def __repr__(self):
        return 'Rotation(pitch=%.6f, yaw=%.6f, roll=%.6f)' % (self.pitch, self.yaw, self.roll)


class Transform:
    __slots__ = ('location', 'rotation')

    def __init__(self, location=None, rotation=None):
        self.location = Location(*location) if location is not None else Location()
        self.rotation = Rotation(rotation.pitch, rotation.yaw, rotation.roll) if rotation is not None else Rotation()

    def transform(self, point):
        """A point in this transform's frame -> world (in place for Location, like CARLA; also returned)."""
        m = self.rotation._matrix()
        x = m[0][0] * point.x + m[0][1] * point.y + m[0][2] * point.z + self.location.x
        y = m[1][0] * point.x + m[1][1] * point.y + m[1][2] * point.z + self.location.y
        z = m[2][0] * point.x + m[2][1] * point.y + m[2][2] * point.z + self.location.z
        point.x, point.y, point.z = x, y, z
        return point

    def transform_vector(self, v):
        m = self.rotation._matrix()
        return Vector3D(m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z, m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
                        m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z)

    def inverse_transform(self, point):
        m = self.rotation._matrix()
        d = point - self.location
        out = Vector3D(m[0][0] * d.x + m[1][0] * d.y + m[2][0] * d.z, m[0][1] * d.x + m[1][1] * d.y + m[2][1] * d.z,
                       m[0][2] * d.x + m[1][2] * d.y + m[2][2] * d.z)
        point.x, point.y, point.z = out.x, out.y, out.z
        return point

    def get_matrix(self):
        m = self.rotation._matrix()
        t = self.location
        return [m[0] + [t.x], m[1] + [t.y], m[2] + [t.z], [0.0, 0.0, 0.0, 1.0]]

    def get_inverse_matrix(self):
        m = self.rotation._matrix()
        t = self.location
        rt = [[m[j][i] for j in range(3)] for i in range(3)]
        tt = [-(rt[i][0] * t.x + rt[i][1] * t.y + rt[i][2] * t.z) for i in range(3)]
        return [rt[0] + [tt[0]], rt[1] + [tt[1]], rt[2] + [tt[2]], [0.0, 0.0, 0.0, 1.0]]

    def get_forward_vector(self):
        return self.rotation.get_forward_vector()

    def get_right_vector(self):
        return self.rotation.get_right_vector()

    def get_up_vector(self):
        return self.rotation.get_up_vector()

    def __eq__(self, o):
        return isinstance(o, Transform) and self.location == o.location and self.rotation == o.rotation

    def __repr__(self):
        return 'Transform(%r, %r)' % (self.location, self.rotation)


class BoundingBox:
    def __init__(self, location=None, extent=None):
        self.location = location if location is not None else Location()
        self.extent = extent if extent is not None else Vector3D()
        self.rotation = Rotation()

    def contains(self, point, transform):
        p = transform.inverse_transform(Location(point.x, point.y, point.z)) - self.location
        return abs(p.x) <= self.extent.x and abs(p.y) <= self.extent.y and abs(p.z) <= self.extent.z

    def get_local_vertices(self):
        e, c = self.extent, self.location
        return [Location(c.x + sx * e.x, c.y + sy * e.y, c.z + sz * e.z)
                for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]

    def get_world_vertices(self, transform):
        return [transform.transform(v) for v in self.get_local_vertices()]

    def __repr__(self):
        return 'BoundingBox(%r, Extent(x=%g, y=%g, z=%g))' % (self.location, self.extent.x, self.extent.y, self.extent.z)


class Color:
    def __init__(self, r=0, g=0, b=0, a=255):
        self.r, self.g, self.b, self.a = int(r), int(g), int(b), int(a)

    def __repr__(self):
        return 'Color(%d,%d,%d,%d)' % (self.r, self.g, self.b, self.a)


class GeoLocation:
    def __init__(self, latitude=0.0, longitude=0.0, altitude=0.0):
        self.latitude, self.longitude, self.altitude = latitude, longitude, altitude

    def __repr__(self):
        return 'GeoLocation(latitude=%f, longitude=%f, altitude=%f)' % (self.latitude, self.longitude, self.altitude)


# --- CARLA <-> wire (ENU) ----------------------------------------------------------------

def _quat_from_rpy(roll, pitch, yaw):
    """ENU roll, pitch, yaw (rad, ZYX) -> (w, x, y, z)."""
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return (cr * cp * cy + sr * sp * sy, sr * cp * cy - cr * sp * sy, cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy)


def rpy_from_quat(w, x, y, z):
    """(w, x, y, z) -> ENU roll, pitch, yaw (rad, ZYX)."""
    roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    pitch = math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x))))
    yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    return roll, pitch, yaw


def to_wire_pose(transform):
    """carla.Transform -> (x, y, z, qw, qx, qy, qz), world ENU."""
    loc, rot = transform.location, transform.rotation
    q = _quat_from_rpy(math.radians(rot.roll), -math.radians(rot.pitch), -math.radians(rot.yaw))
    return (loc.x, -loc.y, loc.z) + q


def from_wire_pose(pose):
    """(x, y, z, qw, qx, qy, qz) ENU -> carla.Transform."""
    x, y, z, qw, qx, qy, qz = pose
    roll, pitch, yaw = rpy_from_quat(qw, qx, qy, qz)
    return Transform(Location(x, -y, z), Rotation(-math.degrees(pitch), -math.degrees(yaw), math.degrees(roll)))


def from_enu_vector(v, cls=Vector3D):
    return cls(v[0], -v[1], v[2])


def to_enu_vector(v):
    return (v.x, -v.y, v.z)
