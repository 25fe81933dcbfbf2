"""Frames for the airsim module: AirSim's world NED (x north, y east, z down) and body FRD
against Lockstep's world ENU and body FLU; AirSim's angles (Roll Pitch Yaw in degrees of
settings.json, radians of to_quaternion)."""
import math

from .types import Quaternionr, Vector3r, _rotate_vector

_H = math.sqrt(0.5)


def qmul(a, b):
    """(w, x, y, z) tuples."""
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return (aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw)


def _swap(q):
    """ENU/FLU <-> NED/FRD (the same map both ways): world 180 deg about (1,1,0)/sqrt2, body 180 deg about x."""
    r = qmul(qmul((0.0, _H, _H, 0.0), q), (0.0, 1.0, 0.0, 0.0))
    n = math.sqrt(sum(v * v for v in r)) or 1.0
    s = (-1.0 if r[0] < 0 else 1.0) / n
    return tuple(s * v for v in r)


def enu_to_ned_quat(q):
    """(w, x, y, z) ENU/FLU -> Quaternionr NED/FRD."""
    w, x, y, z = _swap(q)
    return Quaternionr(x, y, z, w)


def ned_to_enu_quat(q):
    """Quaternionr NED/FRD -> (w, x, y, z) ENU/FLU."""
    return _swap((q.w_val, q.x_val, q.y_val, q.z_val))


def ned_to_enu_pos(p, home):
    """NED (x, y, z) from `home` (ENU tuple) -> world ENU tuple."""
    x, y, z = p
    return (home[0] + y, home[1] + x, home[2] - z)


def enu_to_ned_pos(p, home):
    return (p[1] - home[1], p[0] - home[0], -(p[2] - home[2]))


def frd_euler_deg_to_quat(roll, pitch, yaw):
    """AirSim's Roll Pitch Yaw (deg, body FRD in NED) -> Quaternionr (NED)."""
    from .types import to_quaternion
    return to_quaternion(math.radians(pitch or 0.0), math.radians(roll or 0.0), math.radians(yaw or 0.0))


def frd_mount_to_flu(x, y, z, roll, pitch, yaw):
    """A mount on the vehicle, AirSim's (m, deg, FRD) -> Lockstep's pose tuple (x, y, z, qw, qx, qy, qz) in FLU."""
    q = frd_euler_deg_to_quat(roll, pitch, yaw)
    # Body-relative: FRD -> FLU is T q T with T = 180 deg about x.
    r = qmul(qmul((0.0, 1.0, 0.0, 0.0), (q.w_val, q.x_val, q.y_val, q.z_val)), (0.0, -1.0, 0.0, 0.0))
    if r[0] < 0:
        r = tuple(-v for v in r)
    return (x or 0.0, -(y or 0.0), -(z or 0.0)) + r


def compose(parent_pos, parent_q, child_pos, child_q):
    """World pose of a child mounted at (child_pos, child_q) on a parent (NED, Vector3r / Quaternionr)."""
    p = parent_pos + _rotate_vector(parent_q, child_pos)
    return p, parent_q * child_q


def vec(t):
    return Vector3r(*t)
