"""carla.VehicleAckermannControl, AckermannControllerSettings, VehiclePhysicsControl,
WheelPhysicsControl and GearPhysicsControl, and their wire form (idl/lockstep/command.idl:
SI units, radians, ENU, all four wheels alike)."""
import math

from .errors import unsupported
from .geometry import Location, Vector2D, Vector3D

__all__ = ['VehicleAckermannControl', 'AckermannControllerSettings', 'GearPhysicsControl', 'WheelPhysicsControl',
           'VehiclePhysicsControl']


class VehicleAckermannControl:
    """steer (rad, > 0 right), steer_speed (rad/s), speed (m/s), acceleration (m/s^2), jerk (m/s^3)."""

    def __init__(self, steer=0.0, steer_speed=0.0, speed=0.0, acceleration=0.0, jerk=0.0):
        self.steer, self.steer_speed, self.speed = float(steer), float(steer_speed), float(speed)
        self.acceleration, self.jerk = float(acceleration), float(jerk)

    def _wire(self):
        return {'type': 'ackermann', 'steer': self.steer, 'steer_speed': self.steer_speed, 'speed': self.speed,
                'acceleration': self.acceleration, 'jerk': self.jerk}

    def __eq__(self, o):
        return isinstance(o, VehicleAckermannControl) and self.__dict__ == o.__dict__

    def __repr__(self):
        return ('VehicleAckermannControl(steer=%g, steer_speed=%g, speed=%g, acceleration=%g, jerk=%g)'
                % (self.steer, self.steer_speed, self.speed, self.acceleration, self.jerk))


class AckermannControllerSettings:
    """CARLA's PID settings of its Ackermann controller. ground_sim's controller has fixed
    gains: the object exists for scripts that build one; applying it raises."""

    def __init__(self, speed_kp=0.15, speed_ki=0.0, speed_kd=0.25, accel_kp=0.01, accel_ki=0.0, accel_kd=0.01):
        self.speed_kp, self.speed_ki, self.speed_kd = speed_kp, speed_ki, speed_kd
        self.accel_kp, self.accel_ki, self.accel_kd = accel_kp, accel_ki, accel_kd


class GearPhysicsControl:
    def __init__(self, ratio=1.0, down_ratio=0.5, up_ratio=0.65):
        self.ratio, self.down_ratio, self.up_ratio = float(ratio), float(down_ratio), float(up_ratio)

    def __eq__(self, o):
        return isinstance(o, GearPhysicsControl) and self.__dict__ == o.__dict__

    def __repr__(self):
        return 'GearPhysicsControl(ratio=%g, down_ratio=%g, up_ratio=%g)' % (self.ratio, self.down_ratio, self.up_ratio)


# CARLA's defaults of the fields ground_sim does not model: a control that changes them raises.
_WHEEL_UNMODELLED = {'damping_rate': 0.25, 'lat_stiff_max_load': 2.0, 'lat_stiff_value': 17.0, 'long_stiff_value': 1000.0}
_VEHICLE_UNMODELLED = {'damping_rate_zero_throttle_clutch_engaged': 2.0,
                       'damping_rate_zero_throttle_clutch_disengaged': 0.35, 'use_sweep_wheel_collision': False}


class WheelPhysicsControl:
    """CARLA's units: max_steer_angle in degrees, radius in centimetres, position in world
    centimetres (read only here)."""

    def __init__(self, tire_friction=2.0, damping_rate=0.25, max_steer_angle=70.0, radius=30.0, max_brake_torque=1500.0,
                 max_handbrake_torque=3000.0, lat_stiff_max_load=2.0, lat_stiff_value=17.0, long_stiff_value=1000.0,
                 position=None):
        self.tire_friction, self.damping_rate = float(tire_friction), float(damping_rate)
        self.max_steer_angle, self.radius = float(max_steer_angle), float(radius)
        self.max_brake_torque, self.max_handbrake_torque = float(max_brake_torque), float(max_handbrake_torque)
        self.lat_stiff_max_load, self.lat_stiff_value = float(lat_stiff_max_load), float(lat_stiff_value)
        self.long_stiff_value = float(long_stiff_value)
        self.position = position if position is not None else Vector3D()

    def __eq__(self, o):
        return isinstance(o, WheelPhysicsControl) and self.__dict__ == o.__dict__

    def __repr__(self):
        return ('WheelPhysicsControl(tire_friction=%g, max_steer_angle=%g, radius=%g, max_brake_torque=%g, '
                'max_handbrake_torque=%g)' % (self.tire_friction, self.max_steer_angle, self.radius,
                                              self.max_brake_torque, self.max_handbrake_torque))


class VehiclePhysicsControl:
    """CARLA's fields, plus Lockstep's own (metres): wheelbase, track,
    suspension_stiffness (N/m per wheel), suspension_damping (N s/m per wheel)."""

    def __init__(self, torque_curve=None, max_rpm=5000.0, moi=1.0, damping_rate_full_throttle=0.15,
                 damping_rate_zero_throttle_clutch_engaged=2.0, damping_rate_zero_throttle_clutch_disengaged=0.35,
                 use_gear_autobox=True, gear_switch_time=0.5, clutch_strength=10.0, final_ratio=4.0, forward_gears=None,
                 mass=1000.0, drag_coefficient=0.3, center_of_mass=None, steering_curve=None, wheels=None,
                 use_sweep_wheel_collision=False, wheelbase=None, track=None, suspension_stiffness=None,
                 suspension_damping=None):
        self.torque_curve = list(torque_curve) if torque_curve is not None else [Vector2D(0, 500), Vector2D(5000, 500)]
        self.max_rpm, self.moi = float(max_rpm), float(moi)
        self.damping_rate_full_throttle = float(damping_rate_full_throttle)
        self.damping_rate_zero_throttle_clutch_engaged = float(damping_rate_zero_throttle_clutch_engaged)
        self.damping_rate_zero_throttle_clutch_disengaged = float(damping_rate_zero_throttle_clutch_disengaged)
        self.use_gear_autobox, self.gear_switch_time = bool(use_gear_autobox), float(gear_switch_time)
        self.clutch_strength, self.final_ratio = float(clutch_strength), float(final_ratio)
        self.forward_gears = list(forward_gears) if forward_gears is not None else []
        self.mass, self.drag_coefficient = float(mass), float(drag_coefficient)
        self.center_of_mass = center_of_mass if center_of_mass is not None else Vector3D()
        self.steering_curve = list(steering_curve) if steering_curve is not None else [Vector2D(0, 1), Vector2D(10, 0.5)]
        self.wheels = list(wheels) if wheels is not None else []
        self.use_sweep_wheel_collision = bool(use_sweep_wheel_collision)
        self.wheelbase, self.track = wheelbase, track
        self.suspension_stiffness, self.suspension_damping = suspension_stiffness, suspension_damping
        self._steering_curve_read = None

    def __repr__(self):
        return ('VehiclePhysicsControl(max_rpm=%g, mass=%g, final_ratio=%g, gears=%d, wheels=%d)'
                % (self.max_rpm, self.mass, self.final_ratio, len(self.forward_gears), len(self.wheels)))


def _call(name):
    return 'Vehicle.apply_physics_control' if name is None else name


def from_wire(d, transform=None, half_extents=(0.0, 0.0, 0.0)):
    """The wire dict (vehicle_physics binding) -> carla.VehiclePhysicsControl. Wheel
    positions (world cm, CARLA's frame) come from `transform`, wheelbase and track."""
    wheels = []
    h = half_extents
    for i, (sx, sy) in enumerate(((1, -1), (1, 1), (-1, -1), (-1, 1))):  # FL, FR, RL, RR (CARLA y to the right)
        front = i < 2
        pos = Vector3D()
        if transform is not None:
            local = Location(sx * d['wheelbase'] / 2, sy * d['track'] / 2, d['wheel_radius'] - h[2])
            pos = transform.transform(local) * 100.0
        wheels.append(WheelPhysicsControl(
            tire_friction=d['tire_friction'], max_steer_angle=math.degrees(d['max_steer_angle']) if front else 0.0,
            radius=d['wheel_radius'] * 100.0, max_brake_torque=d['max_brake_torque'],
            max_handbrake_torque=0.0 if front else d['max_handbrake_torque'], position=pos))
    com = d['center_of_mass']
    p = VehiclePhysicsControl(
        torque_curve=[Vector2D(x, y) for x, y in d['torque_curve']], max_rpm=d['max_rpm'], moi=d['moi'],
        damping_rate_full_throttle=d['damping_rate_full_throttle'], use_gear_autobox=d['use_gear_autobox'],
        gear_switch_time=d['gear_switch_time'], clutch_strength=d['clutch_strength'], final_ratio=d['final_ratio'],
        forward_gears=[GearPhysicsControl(*g) for g in d['forward_gears']], mass=d['mass'],
        drag_coefficient=d['drag_coefficient'], center_of_mass=Vector3D(com[0], -com[1], com[2]), wheels=wheels,
        wheelbase=d['wheelbase'], track=d['track'], suspension_stiffness=d['suspension_stiffness'],
        suspension_damping=d['suspension_damping'])
    p._steering_curve_read = [(v.x, v.y) for v in p.steering_curve]
    return p


def _same(values, what, call):
    if any(abs(v - values[0]) > 1e-6 * max(1.0, abs(values[0])) for v in values[1:]):
        unsupported(call, 'ground_sim simulates the four wheels alike, and the wheels given differ in %s (%s)'
                    % (what, ', '.join('%g' % v for v in values)))
    return values[0]


def to_wire(p, current, call=None):
    """carla.VehiclePhysicsControl -> the wire dict, over `current` (the vehicle's wire dict)
    for Lockstep's own fields left None. Raises LockstepUnsupported for what ground_sim
    cannot simulate (wheels that differ, rear-wheel steering, unmodelled fields changed)."""
    call = _call(call)
    for k, default in _VEHICLE_UNMODELLED.items():
        if getattr(p, k) != default:
            unsupported(call, "'%s' is not modelled by ground_sim (leave it at CARLA's default %r)" % (k, default))
    curve = [(v.x, v.y) for v in p.steering_curve]
    if curve != (p._steering_curve_read or [(0.0, 1.0), (10.0, 0.5)]):
        unsupported(call, "'steering_curve' is not modelled by ground_sim (the front wheels reach max_steer_angle at "
                          'full steer at any speed)')
    d = dict(current)
    d.update({'torque_curve': [(v.x, v.y) for v in p.torque_curve], 'max_rpm': p.max_rpm, 'moi': p.moi,
              'damping_rate_full_throttle': p.damping_rate_full_throttle, 'use_gear_autobox': p.use_gear_autobox,
              'gear_switch_time': p.gear_switch_time, 'clutch_strength': p.clutch_strength,
              'final_ratio': p.final_ratio, 'forward_gears': [(g.ratio, g.down_ratio, g.up_ratio) for g in p.forward_gears],
              'mass': p.mass, 'drag_coefficient': p.drag_coefficient,
              'center_of_mass': (p.center_of_mass.x, -p.center_of_mass.y, p.center_of_mass.z)})
    for k in ('wheelbase', 'track', 'suspension_stiffness', 'suspension_damping'):
        if getattr(p, k) is not None:
            d[k] = float(getattr(p, k))
    if p.wheels:
        w = p.wheels
        if len(w) != 4:
            unsupported(call, 'ground_sim vehicles have four wheels (FL, FR, RL, RR), %d given' % len(w))
        for wheel in w:
            for k, default in _WHEEL_UNMODELLED.items():
                if getattr(wheel, k) != default:
                    unsupported(call, "WheelPhysicsControl.%s is not modelled by ground_sim (leave it at CARLA's "
                                      'default %r)' % (k, default))
        if any(abs(x.max_steer_angle) > 1e-9 for x in w[2:]):
            unsupported(call, 'the rear wheels of ground_sim vehicles do not steer (max_steer_angle must be 0)')
        d['tire_friction'] = _same([x.tire_friction for x in w], 'tire_friction', call)
        d['wheel_radius'] = _same([x.radius for x in w], 'radius', call) / 100.0
        d['max_brake_torque'] = _same([x.max_brake_torque for x in w], 'max_brake_torque', call)
        d['max_steer_angle'] = math.radians(_same([x.max_steer_angle for x in w[:2]], 'max_steer_angle', call))
        d['max_handbrake_torque'] = _same([x.max_handbrake_torque for x in w[2:]], 'max_handbrake_torque', call)
    return d
