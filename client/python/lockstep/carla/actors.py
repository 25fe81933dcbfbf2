"""carla.Actor, Vehicle, Walker, TrafficLight, Sensor, WalkerAIController and their
controls, over the states the physics services publish (GroundState, AirState)."""
import math
import threading

from .errors import unsupported
from .geometry import (BoundingBox, Location, Transform, Vector3D, from_enu_vector, from_wire_pose, to_enu_vector,
                       to_wire_pose)
from .sensor_data import make_sensor_data

__all__ = ['VehicleControl', 'WalkerControl', 'TrafficLightState', 'AttachmentType', 'ActorState', 'Actor', 'Vehicle',
           'Walker', 'TrafficLight', 'Sensor', 'ServerSideSensor', 'WalkerAIController', 'ActorList', 'make_actor',
           'VehicleLightState', 'VehicleDoor', 'VehicleWheelLocation']


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
        return Vector3D(math.degrees(w[0]), -math.degrees(w[1]), -math.degrees(w[2]))  # deg/s, CARLA's sense

    def get_acceleration(self):
        s = self._state()
        return from_enu_vector(s['acceleration']) if s else Vector3D()

    def set_transform(self, transform):
        self._world._client.submit({'type': 'set_transform', 'actor': self.id, 'transform': to_wire_pose(transform)})

    def set_location(self, location):
        t = self.get_transform()
        self.set_transform(Transform(location, t.rotation))

    def set_simulate_physics(self, enabled=True):
        unsupported('Actor.set_simulate_physics', 'physics cannot be switched off per actor on the wire')

    def set_enable_gravity(self, enabled):
        unsupported('Actor.set_enable_gravity', 'gravity cannot be switched off per actor on the wire')

    def add_impulse(self, impulse):
        unsupported('Actor.add_impulse', 'no impulse command on the wire')

    def add_force(self, force):
        unsupported('Actor.add_force', 'no force command on the wire')

    def set_target_velocity(self, velocity):
        unsupported('Actor.set_target_velocity', 'no velocity command on the wire for ground actors')

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

    def get_physics_control(self):
        unsupported('Vehicle.get_physics_control', 'vehicle physics parameters are not exposed over the wire')

    def apply_physics_control(self, physics_control):
        unsupported('Vehicle.apply_physics_control', 'vehicle physics parameters are not exposed over the wire')

    def set_light_state(self, light_state):
        unsupported('Vehicle.set_light_state', 'vehicle lights are not simulated')

    def get_light_state(self):
        return VehicleLightState.NONE

    def apply_ackermann_control(self, control):
        unsupported('Vehicle.apply_ackermann_control', 'the wire carries throttle/steer/brake control only')

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
    def start(self):
        unsupported('WalkerAIController.start', 'there is no walker-AI command on the wire yet; '
                    'drive walkers with Walker.apply_control')

    def go_to_location(self, location):
        unsupported('WalkerAIController.go_to_location', 'there is no walker-AI command on the wire yet')

    def set_max_speed(self, speed):
        unsupported('WalkerAIController.set_max_speed', 'there is no walker-AI command on the wire yet')

    def stop(self):
        unsupported('WalkerAIController.stop', 'there is no walker-AI command on the wire yet')


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

    def reset_group(self):
        unsupported('TrafficLight.reset_group', 'no group reset command on the wire')


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
