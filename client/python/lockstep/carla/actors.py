"""carla.Actor, Vehicle, Walker, TrafficLight, Sensor, WalkerAIController and their
controls, over the states the physics services publish (GroundState, AirState)."""
import math
import threading

from .errors import unsupported
from .geometry import (BoundingBox, Location, Transform, Vector3D, from_enu_vector, from_wire_pose, to_enu_vector,
                       to_wire_pose)
from .physics import VehicleAckermannControl  # noqa: F401 (carla.VehicleAckermannControl)
from .physics import from_wire as _physics_from_wire
from .physics import to_wire as _physics_to_wire
from .sensor_data import make_sensor_data

__all__ = ['VehicleControl', 'WalkerControl', 'TrafficLightState', 'AttachmentType', 'ActorState', 'Actor', 'Vehicle',
           'Walker', 'TrafficLight', 'Sensor', 'ServerSideSensor', 'WalkerAIController', 'ActorList', 'make_actor',
           'VehicleLightState', 'VehicleDoor', 'VehicleWheelLocation', 'VehicleAckermannControl']


class VehicleControl:
    def __init__(self, throttle=0.0, steer=0.0, brake=0.0, hand_brake=False, reverse=False, manual_gear_shift=False, gear=0):
        self.throttle, self.steer, self.brake = float(throttle), float(steer), float(brake)
        self.hand_brake, self.reverse = bool(hand_brake), bool(reverse)
        self.manual_gear_shift, self.gear = bool(manual_gear_shift), int(gear)

    def _wire(self):
        return {'type': 'vehicle_control', 'throttle': self.throttle, 'steer': self.steer, 'brake': self.brake,
                'hand_brake': self.hand_brake, 'reverse': self.reverse, 'manual_gear_shift': self.manual_gear_shift,
                'gear': self.gear}

    def __eq__(self, o):
        return isinstance(o, VehicleControl) and self.__dict__ == o.__dict__

    def __repr__(self):
        return ('VehicleControl(throttle=%f, steer=%f, brake=%f, hand_brake=%s, reverse=%s, manual_gear_shift=%s, gear=%d)'
                % (self.throttle, self.steer, self.brake, self.hand_brake, self.reverse, self.manual_gear_shift, self.gear))


class WalkerControl:
    def __init__(self, direction=None, speed=0.0, jump=False):
        self.direction = direction if direction is not None else Vector3D(1, 0, 0)
        self.speed, self.jump = float(speed), bool(jump)

    def _wire(self):
        return {'type': 'walker_control', 'direction': to_enu_vector(self.direction), 'speed': self.speed, 'jump': self.jump}


class TrafficLightState:
    Red = 0
    Yellow = 1
    Green = 2
    Off = 3
    Unknown = 4


_LIGHT_NAMES = ['red', 'yellow', 'green', 'off', 'unknown']


class AttachmentType:
    Rigid = 0
    SpringArm = 1
    SpringArmGhost = 2


class ActorState:
    Invalid = 0
    Active = 1
    Dormant = 2


class VehicleLightState:
    NONE = 0
    Position = 1
    LowBeam = 2
    HighBeam = 4
    Brake = 8
    RightBlinker = 16
    LeftBlinker = 32
    Reverse = 64
    Fog = 128
    Interior = 256
    Special1 = 512
    Special2 = 1024
    All = 0xFFFFFFFF


class VehicleDoor:
    FL = 0
    FR = 1
    RL = 2
    RR = 3
    All = 6


class VehicleWheelLocation:
    FL_Wheel = 0
    FR_Wheel = 1
    BL_Wheel = 2
    BR_Wheel = 3


def _qmul(a, b):
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return (aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw)


def _qrot(q, v):
    w, x, y, z = q
    p = _qmul(_qmul(q, (0.0,) + tuple(v)), (w, -x, -y, -z))
    return p[1:]


class Actor:
    def __init__(self, world, info):
        self._world = world
        self._info = info
        self.id = info['id']
        self.type_id = info['blueprint']
        self.attributes = dict(info.get('attributes', {}))
        self.semantic_tags = []
        self._destroyed = False

    # --- state ---
    def _state(self):
        return self._world._client.state(self.id)

    def _wire_pose(self):
        s = self._state()
        if s is not None:
            return s['transform']
        parent = self._info.get('parent', 0)
        rel = self._info.get('spawn_transform', (0, 0, 0, 1, 0, 0, 0))
        if parent:
            p = self._world._client.state(parent)
            if p is None:
                pa = self._world.get_actor(parent)
                if pa is None:
                    return rel
                pp = pa._wire_pose()
            else:
                pp = p['transform']
            pos = _qrot(pp[3:], rel[:3])
            q = _qmul(pp[3:], rel[3:])
            return (pp[0] + pos[0], pp[1] + pos[1], pp[2] + pos[2]) + q
        return rel

    @property
    def parent(self):
        p = self._info.get('parent', 0)
        return self._world.get_actor(p) if p else None

    @property
    def is_alive(self):
        return not self._destroyed and self._world._client.actor(self.id) is not None

    @property
    def bounding_box(self):
        s = self._state()
        e = s['half_extents'] if s else (0.0, 0.0, 0.0)
        return BoundingBox(Location(0, 0, 0), Vector3D(*e))

    def get_world(self):
        return self._world

    def get_transform(self):
        return from_wire_pose(self._wire_pose())

    def get_location(self):
        return self.get_transform().location

    def get_velocity(self):
        s = self._state()
        return from_enu_vector(s['velocity']) if s else Vector3D()

    def get_angular_velocity(self):
        s = self._state()
        if not s:
            return Vector3D()
        w = s['angular_velocity']
        # deg/s in CARLA's (Unreal's) world frame: a pseudovector under the y mirror, (-x, y, -z).
        return Vector3D(-math.degrees(w[0]), math.degrees(w[1]), -math.degrees(w[2]))

    def get_acceleration(self):
        s = self._state()
        return from_enu_vector(s['acceleration']) if s else Vector3D()

    def set_transform(self, transform):
        self._world._client.submit({'type': 'set_transform', 'actor': self.id, 'transform': to_wire_pose(transform)})

    def set_location(self, location):
        t = self.get_transform()
        self.set_transform(Transform(location, t.rotation))

    # --- physics (ground_sim's actors; a failure there is raised by the next world.tick()) ---
    def _physics(self, call, kind, **kw):
        self._world._require('ground_sim', call)
        cmd = {'type': 'actor_physics', 'actor': self.id, 'kind': kind}
        cmd.update(kw)
        reply = self._world._client.submit(cmd, watch=call)
        self._world._note_applied(cmd, reply[3])

    def set_simulate_physics(self, enabled=True):
        self._physics('Actor.set_simulate_physics', 'set_simulate_physics', enabled=bool(enabled))

    def set_enable_gravity(self, enabled):
        unsupported('Actor.set_enable_gravity', 'gravity cannot be switched off per actor on the wire')

    def add_impulse(self, impulse):
        """N s, world (CARLA's frame), applied at the next tick."""
        self._physics('Actor.add_impulse', 'add_impulse', value=to_enu_vector(impulse))

    def add_force(self, force):
        """N, world: ground_sim has no force command; the force acts for one tick, as
        CARLA's does for one physics step: the impulse force x fixed_delta_seconds."""
        dt = self._world._dt()
        self._physics('Actor.add_force', 'add_impulse', value=tuple(c * dt for c in to_enu_vector(force)))

    def add_angular_impulse(self, angular_impulse):
        unsupported('Actor.add_angular_impulse', 'ground_sim takes no angular impulse; use set_target_angular_velocity')

    def add_torque(self, torque):
        unsupported('Actor.add_torque', 'ground_sim takes no torque; use set_target_angular_velocity')

    def set_target_velocity(self, velocity):
        """m/s, world (CARLA's frame), set at the next tick."""
        self._physics('Actor.set_target_velocity', 'set_target_velocity', value=to_enu_vector(velocity))

    def set_target_angular_velocity(self, angular_velocity):
        """deg/s, world (CARLA's frame and sense, as get_angular_velocity returns it)."""
        w = angular_velocity
        self._physics('Actor.set_target_angular_velocity', 'set_target_angular_velocity',
                      value=(-math.radians(w.x), math.radians(w.y), -math.radians(w.z)))

    def enable_constant_velocity(self, velocity):
        unsupported('Actor.enable_constant_velocity', 'ground_sim has no constant-velocity mode; call '
                    'set_target_velocity every tick')

    def disable_constant_velocity(self):
        unsupported('Actor.disable_constant_velocity', 'ground_sim has no constant-velocity mode')

    def destroy(self):
        if self._destroyed:
            return False
        self._world._client.destroy(self.id)
        self._destroyed = True
        return True

    def __eq__(self, o):
        return isinstance(o, Actor) and self.id == o.id

    def __hash__(self):
        return hash(self.id)

    def __repr__(self):
        return 'Actor(id=%d, type=%s)' % (self.id, self.type_id)


class Vehicle(Actor):
    def apply_control(self, control):
        self._world._client.submit(dict(control._wire(), actor=self.id))

    def get_control(self):
        s = self._state()
        c = s.get('control') if s else None
        return VehicleControl(**c) if c else VehicleControl()

    def set_autopilot(self, enabled=True, port=8000):
        self._world._require('ground_sim', 'Vehicle.set_autopilot')
        self._world._client.submit({'type': 'traffic_manager', 'parameter': 'autopilot', 'actor': self.id,
                                    'value': 1.0 if enabled else 0.0})

    def get_speed_limit(self):
        s = self._state()
        return s['speed_limit'] * 3.6 if s and 'speed_limit' in s else 0.0  # km/h, as CARLA

    def get_traffic_light(self):
        s = self._state()
        tl = s.get('traffic_light', 0) if s else 0
        return self._world.get_actor(tl) if tl else None

    def get_traffic_light_state(self):
        tl = self.get_traffic_light()
        return tl.get_state() if tl else TrafficLightState.Green

    def is_at_traffic_light(self):
        return self.get_traffic_light() is not None

    def _physics_wire(self, call):
        self._world._require('ground_sim', call)
        d = self._world._client.vehicle_physics(self.id)
        if d is None:
            raise RuntimeError('%s: vehicle %d has no state yet (tick once after spawning it)' % (call, self.id))
        return self._world._applied_value(self.id, 'physics', d)

    def get_physics_control(self):
        """The vehicle's physics: what this client applied last until the GroundState of
        the frame that applies it arrives (so it reads back at once, as CARLA), then what
        ground_sim reports."""
        s = self._state()
        return _physics_from_wire(self._physics_wire('Vehicle.get_physics_control'), from_wire_pose(s['transform']),
                                  s['half_extents'])

    def apply_physics_control(self, physics_control):
        call = 'Vehicle.apply_physics_control'
        cmd = {'type': 'vehicle_physics', 'actor': self.id,
               'physics': _physics_to_wire(physics_control, self._physics_wire(call), call)}
        self._world._note_applied(cmd, self._world._client.submit(cmd, watch=call)[3])

    def set_light_state(self, light_state):
        self._physics('Vehicle.set_light_state', 'set_light_state', light_state=int(light_state) & 0xFFFFFFFF)

    def get_light_state(self):
        """As get_physics_control: this client's last set_light_state until its frame's state."""
        s = self._state()
        bits = s.get('light_state', VehicleLightState.NONE) if s else VehicleLightState.NONE
        return self._world._applied_value(self.id, 'light_state', bits)

    def apply_ackermann_control(self, control):
        self._world._require('ground_sim', 'Vehicle.apply_ackermann_control')
        self._world._client.submit(dict(control._wire(), actor=self.id), watch='Vehicle.apply_ackermann_control')

    def get_ackermann_controller_settings(self):
        unsupported('Vehicle.get_ackermann_controller_settings', "ground_sim's Ackermann controller has fixed gains")

    def apply_ackermann_controller_settings(self, settings):
        unsupported('Vehicle.apply_ackermann_controller_settings', "ground_sim's Ackermann controller has fixed gains")

    def open_door(self, door):
        unsupported('Vehicle.open_door', 'doors are not simulated')

    def enable_carsim(self, path):
        unsupported('Vehicle.enable_carsim', 'CarSim is an Unreal plug-in')

    def get_wheel_steer_angle(self, wheel):
        return self.get_control().steer * 70.0


class Walker(Actor):
    def apply_control(self, control):
        self._world._client.submit(dict(control._wire(), actor=self.id))

    def get_control(self):
        s = self._state()
        if not s:
            return WalkerControl()
        v = from_enu_vector(s['velocity'])
        speed = v.length()
        return WalkerControl(v.make_unit_vector() if speed > 0 else Vector3D(1, 0, 0), speed)


class WalkerAIController(Actor):
    """controller.ai.walker, spawned attached to its walker; ground_sim walks it."""

    def _ai(self, call, kind, **kw):
        self._world._require('ground_sim', call)
        cmd = {'type': 'walker_ai', 'actor': self.id, 'kind': kind}
        cmd.update(kw)
        self._world._client.submit(cmd, watch=call)

    def start(self):
        self._ai('WalkerAIController.start', 'start')

    def go_to_location(self, location):
        self._ai('WalkerAIController.go_to_location', 'go_to_location', location=to_enu_vector(location))

    def set_max_speed(self, speed=1.4):
        self._ai('WalkerAIController.set_max_speed', 'set_max_speed', max_speed=float(speed))

    def stop(self):
        self._ai('WalkerAIController.stop', 'stop')


class TrafficLight(Actor):
    def _light(self):
        s = self._state()
        if not s or 'light' not in s:
            raise RuntimeError('traffic light %d has no state: is ground_sim running?' % self.id)
        return s['light']

    def get_state(self):
        return _LIGHT_NAMES.index(self._light()['state'])

    @property
    def state(self):
        return self.get_state()

    def _command(self, **kw):
        self._world._require('ground_sim', 'TrafficLight.set_state')
        cmd = {'type': 'traffic_light', 'actor': self.id, 'state': self._light()['state']}
        cmd.update(kw)
        self._world._client.submit(cmd)

    def set_state(self, state):
        self._command(state=_LIGHT_NAMES[state])

    def get_elapsed_time(self):
        return self._light()['elapsed']

    def get_green_time(self):
        return self._light()['green_time']

    def get_yellow_time(self):
        return self._light()['yellow_time']

    def get_red_time(self):
        return self._light()['red_time']

    def set_green_time(self, t):
        self._command(green_time=float(t))

    def set_yellow_time(self, t):
        self._command(yellow_time=float(t))

    def set_red_time(self, t):
        self._command(red_time=float(t))

    def freeze(self, freeze):
        self._command(freeze=bool(freeze))

    def is_frozen(self):
        return self._light()['frozen']

    def get_opendrive_id(self):
        return self._light()['opendrive_id']

    def get_group_traffic_lights(self):
        g = self._light()['group']
        return [self._world.get_actor(l['id']) for l in self._world._client.traffic_lights() if l['group'] == g]

    def get_pole_index(self):
        return 0

    def get_stop_waypoints(self):
        """One waypoint per controlled lane, at its stop line (from the map's signal)."""
        return self._world.get_map()._stop_waypoints(self.get_opendrive_id())

    def get_affected_lane_waypoints(self):
        """CARLA's: for every landmark of this light's signal (the signal and its
        references), a waypoint at the landmark's s on each lane its validities name."""
        m = self._world.get_map()
        out = []
        for l in m.get_all_landmarks_from_id(self.get_opendrive_id()):
            for a, b in l.get_lane_validities():
                step = 1 if a <= b else -1
                for lane in range(a, b + step, step):
                    w = m.get_waypoint_xodr(l.road_id, lane, l.s) if lane != 0 else None
                    if w is not None:
                        out.append(w)
        return out

    @property
    def trigger_volume(self):
        """carla.TrafficSign.trigger_volume: where an approaching vehicle reacts (3 m of
        the controlled lanes before the stop line), in the light's frame, as CARLA."""
        box = self._world.get_map()._trigger_volume(self.get_opendrive_id())
        if box is None:
            return BoundingBox()
        (x, y, z), extent, _ = box
        local = self.get_transform().inverse_transform(Location(x, -y, z))
        return BoundingBox(Location(local.x, local.y, local.z), Vector3D(*extent))

    def reset_group(self):
        """This light's group back to the start of its cycle (its first light green)."""
        self._world._require('ground_sim', 'TrafficLight.reset_group')
        self._world._client.submit({'type': 'traffic_light', 'actor': self.id, 'action': 'reset_group'},
                                   watch='TrafficLight.reset_group')


class Sensor(Actor):
    def __init__(self, world, info):
        super().__init__(world, info)
        self._callback = None

    def listen(self, callback):
        """CARLA's listen: `callback(data)` for every frame, once and in order, on the
        client's dispatch thread. In synchronous mode world.tick() returns after the
        frame's data was delivered (or raises lockstep.SensorLate naming the sensor)."""
        world = self._world

        def deliver(sample):
            callback(make_sensor_data(sample, world))

        self._callback = deliver
        world._client.listen(self.id, deliver)

    def stop(self):
        self._world._client.stop(self.id)
        self._callback = None

    @property
    def is_listening(self):
        return self._world._client.is_listening(self.id)

    def destroy(self):
        if self.is_listening:
            self.stop()
        return super().destroy()


ServerSideSensor = Sensor


class ActorList(list):
    def filter(self, wildcard_pattern):
        import fnmatch
        return ActorList(a for a in self if fnmatch.fnmatchcase(a.type_id, wildcard_pattern))

    def find(self, actor_id):
        for a in self:
            if a.id == actor_id:
                return a
        return None


_KINDS = {'vehicle': Vehicle, 'walker': Walker, 'sensor': Sensor, 'traffic_light': TrafficLight,
          'controller': WalkerAIController}


def make_actor(world, info):
    return _KINDS.get(info['kind'], Actor)(world, info)


# Actor ids and threading: the world's callbacks may run on the dispatch thread.
_lock = threading.Lock()
