"""carla.Vector3D, Location, Rotation, Transform, BoundingBox... and the conversion between
CARLA's convention (left-handed: x forward/east, y right = ENU -y, z up; angles in degrees,
pitch up positive, yaw clockwise seen from above) and Lockstep's wire (right-handed ENU,
radians, quaternions)."""
import math

__all__ = ['Vector2D', 'Vector3D', 'Location', 'Rotation', 'Transform', 'BoundingBox', 'Color', 'GeoLocation', 'GeoEllipsoid',
           'to_wire_pose', 'from_wire_pose', 'from_enu_vector', 'to_enu_vector', 'rpy_from_quat']


def _xyz(cls, args, kwargs):
    """CARLA's constructors: (x=0, y=0, z=0) or one vector to copy (Location(vector3d),
    Vector3D(location)), as the geom bindings' `init<const Vector3D &>`."""
    if len(args) == 1 and not kwargs and hasattr(args[0], 'x') and hasattr(args[0], 'z'):
        v = args[0]
        return float(v.x), float(v.y), float(v.z)
    names = ('x', 'y', 'z')
    if len(args) > 3:
        raise TypeError('%s() takes at most 3 coordinates (%d given)' % (cls.__name__, len(args)))
    vals = dict(zip(names, args))
    for k, v in kwargs.items():
        if k not in names:
            raise TypeError("%s() got an unexpected keyword argument '%s'" % (cls.__name__, k))
        if k in vals:
            raise TypeError("%s() got multiple values for argument '%s'" % (cls.__name__, k))
        vals[k] = v
    return tuple(float(vals.get(k, 0.0)) for k in names)


class Vector2D:
    """carla.Vector2D: CARLA's operators (+, -, * and / by a number, k / v = v / k as
    LibCarla's), length, squared_length, make_unit_vector."""
    __slots__ = ('x', 'y')

    def __init__(self, x=0.0, y=0.0):
        self.x, self.y = float(x), float(y)

    def length(self):
        return math.hypot(self.x, self.y)

    def squared_length(self):
        return self.x * self.x + self.y * self.y

    def make_unit_vector(self):
        n = self.length()
        return Vector2D(self.x / n, self.y / n) if n > 0 else Vector2D(self.x, self.y)

    def __add__(self, o):
        return Vector2D(self.x + o.x, self.y + o.y)

    def __sub__(self, o):
        return Vector2D(self.x - o.x, self.y - o.y)

    def __mul__(self, k):
        return Vector2D(self.x * k, self.y * k)

    __rmul__ = __mul__

    def __truediv__(self, k):
        return Vector2D(self.x / k, self.y / k)

    __rtruediv__ = __truediv__  # LibCarla: operator/(float, Vector2D) divides the vector by the number

    def __iadd__(self, o):
        self.x += o.x
        self.y += o.y
        return self

    def __isub__(self, o):
        self.x -= o.x
        self.y -= o.y
        return self

    def __imul__(self, k):
        self.x *= k
        self.y *= k
        return self

    def __itruediv__(self, k):
        self.x /= k
        self.y /= k
        return self

    def __eq__(self, o):
        return isinstance(o, Vector2D) and self.x == o.x and self.y == o.y

    def __ne__(self, o):
        return not self == o

    def __hash__(self):
        return hash((self.x, self.y))

    def __repr__(self):
        return 'Vector2D(x=%f, y=%f)' % (self.x, self.y)


class Vector3D:
    """carla.Vector3D: CARLA's geom bindings. Arithmetic gives a Vector3D (also on
    Locations, as CARLA's); in-place operators change the vector itself."""
    __slots__ = ('x', 'y', 'z')

    def __init__(self, *args, **kwargs):
        self.x, self.y, self.z = _xyz(type(self), args, kwargs)

    def __add__(self, o):
        return Vector3D(self.x + o.x, self.y + o.y, self.z + o.z)

    def __sub__(self, o):
        return Vector3D(self.x - o.x, self.y - o.y, self.z - o.z)

    def __mul__(self, k):
        if isinstance(k, Vector3D):
            return NotImplemented
        return Vector3D(self.x * k, self.y * k, self.z * k)

    __rmul__ = __mul__

    def __truediv__(self, k):
        if isinstance(k, Vector3D):
            return NotImplemented
        return Vector3D(self.x / k, self.y / k, self.z / k)

    __rtruediv__ = __truediv__  # LibCarla: operator/(float, Vector3D) divides the vector by the number

    def __iadd__(self, o):
        self.x += o.x
        self.y += o.y
        self.z += o.z
        return self

    def __isub__(self, o):
        self.x -= o.x
        self.y -= o.y
        self.z -= o.z
        return self

    def __imul__(self, k):
        self.x *= k
        self.y *= k
        self.z *= k
        return self

    def __itruediv__(self, k):
        self.x /= k
        self.y /= k
        self.z /= k
        return self

    def __neg__(self):
        return Vector3D(-self.x, -self.y, -self.z)

    def __abs__(self):
        return type(self)(abs(self.x), abs(self.y), abs(self.z))

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

    def distance(self, vector):
        return (self - vector).length()

    def distance_squared(self, vector):
        return (self - vector).squared_length()

    def distance_2d(self, vector):
        return math.hypot(self.x - vector.x, self.y - vector.y)

    def distance_squared_2d(self, vector):
        dx, dy = self.x - vector.x, self.y - vector.y
        return dx * dx + dy * dy

    def dot(self, vector):
        return self.x * vector.x + self.y * vector.y + self.z * vector.z

    def dot_2d(self, vector):
        return self.x * vector.x + self.y * vector.y

    def cross(self, vector):
        o = vector
        return Vector3D(self.y * o.z - self.z * o.y, self.z * o.x - self.x * o.z, self.x * o.y - self.y * o.x)

    def make_unit_vector(self):
        n = self.length()
        return Vector3D(self.x / n, self.y / n, self.z / n) if n > 0 else Vector3D(self.x, self.y, self.z)

    def get_vector_angle(self, vector):
        """Radians between the two vectors (CARLA's Math::GetVectorAngle)."""
        n = self.length() * vector.length()
        return math.acos(max(-1.0, min(1.0, self.dot(vector) / n))) if n > 0 else 0.0

    def __repr__(self):
        return '%s(x=%f, y=%f, z=%f)' % (type(self).__name__, self.x, self.y, self.z)


class Location(Vector3D):
    """carla.Location(x=0, y=0, z=0) or carla.Location(vector3d)."""
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

    def _rotate(self, v):
        m = self._matrix()
        return (m[0][0] * v[0] + m[0][1] * v[1] + m[0][2] * v[2], m[1][0] * v[0] + m[1][1] * v[1] + m[1][2] * v[2],
                m[2][0] * v[0] + m[2][1] * v[1] + m[2][2] * v[2])

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

    def __ne__(self, o):
        return not self == o

    def __hash__(self):
        return hash((self.pitch, self.yaw, self.roll))

    def __repr__(self):
        return 'Rotation(pitch=%f, yaw=%f, roll=%f)' % (self.pitch, self.yaw, self.roll)


class Transform:
    __slots__ = ('location', 'rotation')

    def __init__(self, location=None, rotation=None):
        self.location = Location(location) if location is not None else Location()
        self.rotation = Rotation(rotation.pitch, rotation.yaw, rotation.roll) if rotation is not None else Rotation()

    def transform(self, in_point):
        """A point in this transform's frame -> world, in place (CARLA's TransformPoint) and
        returned; a list of points is transformed in place (None returned, as CARLA's)."""
        if isinstance(in_point, list):
            for p in in_point:
                self.transform(p)
            return None
        x, y, z = self.rotation._rotate((in_point.x, in_point.y, in_point.z))
        in_point.x, in_point.y, in_point.z = x + self.location.x, y + self.location.y, z + self.location.z
        return in_point

    def transform_vector(self, in_point):
        """Rotates the vector into world axes, in place, and returns it (CARLA's TransformVector)."""
        in_point.x, in_point.y, in_point.z = self.rotation._rotate((in_point.x, in_point.y, in_point.z))
        return in_point

    def inverse_transform(self, in_point):
        m = self.rotation._matrix()
        d = (in_point.x - self.location.x, in_point.y - self.location.y, in_point.z - self.location.z)
        in_point.x = m[0][0] * d[0] + m[1][0] * d[1] + m[2][0] * d[2]
        in_point.y = m[0][1] * d[0] + m[1][1] * d[1] + m[2][1] * d[2]
        in_point.z = m[0][2] * d[0] + m[1][2] * d[1] + m[2][2] * d[2]
        return in_point

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

    def __ne__(self, o):
        return not self == o

    def __hash__(self):
        return hash((self.location, self.rotation))

    def __repr__(self):
        return 'Transform(%r, %r)' % (self.location, self.rotation)


class BoundingBox:
    """carla.BoundingBox(location, extent, rotation): the box's centre and rotation in its
    parent's frame, half sizes in `extent` (CARLA's geom::BoundingBox)."""

    def __init__(self, location=None, extent=None, rotation=None):
        self.location = Location(location) if location is not None else Location()
        self.extent = Vector3D(extent) if extent is not None else Vector3D()
        self.rotation = Rotation(rotation.pitch, rotation.yaw, rotation.roll) if rotation is not None else Rotation()
        self.actor_id = 0

    def contains(self, point, bbox_transform):
        p = bbox_transform.inverse_transform(Location(point)) - self.location
        return -self.extent.x <= p.x <= self.extent.x and -self.extent.y <= p.y <= self.extent.y and \
            -self.extent.z <= p.z <= self.extent.z

    def get_local_vertices(self):
        e, c = self.extent, self.location
        out = []
        for sx in (-1, 1):
            for sy in (-1, 1):
                for sz in (-1, 1):
                    x, y, z = self.rotation._rotate((sx * e.x, sy * e.y, sz * e.z))
                    out.append(Location(c.x + x, c.y + y, c.z + z))
        return out

    def get_world_vertices(self, bbox_transform):
        return [bbox_transform.transform(v) for v in self.get_local_vertices()]

    def __eq__(self, o):
        return (isinstance(o, BoundingBox) and self.location == o.location and self.extent == o.extent
                and self.rotation == o.rotation)

    def __ne__(self, o):
        return not self == o

    def __hash__(self):
        return hash((self.location, self.extent, self.rotation))

    def __repr__(self):
        e = self.extent
        return 'BoundingBox(%r, Extent(x=%f, y=%f, z=%f), %r)' % (self.location, e.x, e.y, e.z, self.rotation)


class Color:
    def __init__(self, r=0, g=0, b=0, a=255):
        self.r, self.g, self.b, self.a = int(r), int(g), int(b), int(a)

    def __eq__(self, o):
        return isinstance(o, Color) and (self.r, self.g, self.b, self.a) == (o.r, o.g, o.b, o.a)

    def __ne__(self, o):
        return not self == o

    def __hash__(self):
        return hash((self.r, self.g, self.b, self.a))

    def __repr__(self):
        return 'Color(%d,%d,%d,%d)' % (self.r, self.g, self.b, self.a)


class GeoLocation:
    def __init__(self, latitude=0.0, longitude=0.0, altitude=0.0):
        self.latitude, self.longitude, self.altitude = float(latitude), float(longitude), float(altitude)

    def __eq__(self, o):
        return (isinstance(o, GeoLocation) and (self.latitude, self.longitude, self.altitude)
                == (o.latitude, o.longitude, o.altitude))

    def __ne__(self, o):
        return not self == o

    def __hash__(self):
        return hash((self.latitude, self.longitude, self.altitude))

    def __repr__(self):
        return 'GeoLocation(latitude=%f, longitude=%f, altitude=%f)' % (self.latitude, self.longitude, self.altitude)


class GeoEllipsoid:
    """carla.GeoEllipsoid (CARLA 0.9.16): semi-major axis `a` (m) and inverse flattening."""

    def __init__(self, a=6378137.0, f_inv=298.257223563):
        self.a, self.f_inv = float(a), float(f_inv)

    def __eq__(self, o):
        return isinstance(o, GeoEllipsoid) and (self.a, self.f_inv) == (o.a, o.f_inv)

    def __ne__(self, o):
        return not self == o

    def __hash__(self):
        return hash((self.a, self.f_inv))

    def __repr__(self):
        return 'GeoEllipsoid(a=%f, f_inv=%f)' % (self.a, self.f_inv)


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


def shift_up(transform, dz):
    """`transform` moved by `dz` m along its own up axis: between a vehicle's box centre
    (Lockstep's wire pose) and CARLA's vehicle origin, the base of the box (dz = -half height)."""
    loc = transform.transform(Location(0.0, 0.0, dz))
    return Transform(loc, transform.rotation)


def from_enu_vector(v, cls=Vector3D):
    return cls(v[0], -v[1], v[2])


def to_enu_vector(v):
    return (v.x, -v.y, v.z)
