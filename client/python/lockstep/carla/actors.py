"""carla.Actor, Vehicle, Walker, TrafficLight, Sensor, WalkerAIController and their
controls, over the states the physics services publish (GroundState, AirState)."""
import enum
import math
import sys
import threading

import lockstep

from . import components as _components
from .components import WalkerBoneControlOut, BoneTransformDataOut
from .errors import unsupported
from .geometry import (BoundingBox, Location, Rotation, Transform, Vector3D, from_enu_vector, from_wire_pose, shift_up,
                       to_enu_vector, to_wire_pose)
from .physics import VehicleAckermannControl  # noqa: F401 (carla.VehicleAckermannControl)
from .physics import from_wire as _physics_from_wire
from .physics import to_wire as _physics_to_wire
from .sensor_data import make_sensor_data

__all__ = ['VehicleControl', 'WalkerControl', 'TrafficLightState', 'AttachmentType', 'ActorState', 'Actor', 'Vehicle',
           'Walker', 'TrafficLight', 'Sensor', 'ServerSideSensor', 'WalkerAIController', 'ActorList', 'make_actor',
           'VehicleLightState', 'VehicleDoor', 'VehicleWheelLocation', 'VehicleAckermannControl', 'TrafficSign',
           'WalkerBoneControlIn', 'WalkerBoneControlOut', 'BoneTransformDataIn', 'BoneTransformDataOut',
           'state_transform']

from .components import BoneTransformDataIn, WalkerBoneControlIn  # noqa: E402 (carla.* names)


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


class VehicleLightState(enum.IntFlag):
    """CARLA's bit flags: combined with | & ^, and callable on an int of bits
    (manual_control.py: carla.VehicleLightState(current_lights))."""
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


# CARLA's semantic tags (carla.CityObjectLabel) of an actor, by kind and base_type.
_TAGS_BY_BASE_TYPE = {'car': 14, 'van': 14, 'truck': 15, 'bus': 16, 'motorcycle': 18, 'bicycle': 19}


def _semantic_tags(kind, attributes):
    if kind == 'vehicle':
        tags = [_TAGS_BY_BASE_TYPE.get(attributes.get('base_type', 'car'), 14)]
        if tags[0] in (18, 19):
            tags.append(13)  # the rider
        return sorted(tags)
    return {'walker': [12], 'traffic_light': [7], 'traffic_sign': [8], 'prop': [20]}.get(kind, [])


def state_transform(state):
    """carla.Transform of an actor state dict: the wire pose, and for vehicles CARLA's
    origin (the base of the box, not its centre)."""
    t = from_wire_pose(state['transform'])
    if state.get('kind') == 'vehicle':
        t = shift_up(t, -state['half_extents'][2])
    return t


def _warn(message):
    sys.stderr.write('WARNING: %s\n' % message)
    sys.stderr.flush()


def _compose(a, b):
    """Transform a then b (b given in a's frame), by rotation matrices."""
    loc = a.transform(Location(b.location))
    ma, mb = a.rotation._matrix(), b.rotation._matrix()
    m = [[sum(ma[i][k] * mb[k][j] for k in range(3)) for j in range(3)] for i in range(3)]
    pitch = math.degrees(math.asin(max(-1.0, min(1.0, m[2][0]))))
    yaw = math.degrees(math.atan2(m[1][0], m[0][0]))
    roll = math.degrees(math.atan2(-m[2][1], m[2][2]))
    return Transform(loc, Rotation(pitch, yaw, roll))


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
        # CARLA's actor attributes: every attribute of the blueprint, with the values spawned.
        decl = world._declaration(self.type_id)
        attrs = {a['id']: a['default'] for a in decl['attributes'] if not a['id'].startswith('_')} if decl else {}
        attrs.update(info.get('attributes', {}))
        self.attributes = attrs
        self.semantic_tags = _semantic_tags(info.get('kind', ''), attrs)
        self._destroyed = False

    # --- state ---
    def _state(self):
        return self._world._client.state(self.id)

    def _live_info(self):
        """The client's current record: an actor attached to a parent that was destroyed is
        detached there (parent 0, its last world pose), as CARLA's."""
        info = self._world._client.actor(self.id)
        return info if info is not None else self._info

    def _wire_pose(self):
        s = self._state()
        if s is not None:
            return s['transform']
        info = self._live_info()
        parent = info.get('parent', 0)
        rel = info.get('spawn_transform', (0, 0, 0, 1, 0, 0, 0))
        if parent:
            p = self._world._client.state(parent)
            if p is None:
                pa = self._world.get_actor(parent)
                if pa is None:
                    return rel
                pp = pa._wire_pose()
            else:
                pp = p['transform']
                if p.get('kind') in ('vehicle', 'walker'):
                    # Mounted where the services mount it (CARLA's vehicle origin): the box bottom.
                    down = _qrot(pp[3:], (0.0, 0.0, -p['half_extents'][2]))
                    pp = (pp[0] + down[0], pp[1] + down[1], pp[2] + down[2]) + tuple(pp[3:])
            pos = _qrot(pp[3:], rel[:3])
            q = _qmul(pp[3:], rel[3:])
            return (pp[0] + pos[0], pp[1] + pos[1], pp[2] + pos[2]) + q
        return rel

    @property
    def parent(self):
        p = self._live_info().get('parent', 0)
        return self._world.get_actor(p) if p else None

    @property
    def is_alive(self):
        return not self._destroyed and self._world._client.actor(self.id) is not None

    def _half_extents(self):
        s = self._state()
        if s:
            return tuple(s['half_extents'])
        decl = self._world._declaration(self.type_id)
        return tuple(decl['half_extents']) if decl else (0.0, 0.0, 0.0)

    def _base_offset(self):
        """m from the wire pose (the box centre) down to CARLA's actor origin: 0 but for vehicles."""
        return 0.0

    @property
    def bounding_box(self):
        """In the actor's frame, as CARLA's: a vehicle's box centre is above its origin."""
        return BoundingBox(Location(0, 0, self._base_offset()), Vector3D(*self._half_extents()))

    def get_world(self):
        return self._world

    def get_transform(self):
        t = from_wire_pose(self._wire_pose())
        dz = self._base_offset()
        return shift_up(t, -dz) if dz else t

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

    def _to_wire_transform(self, transform):
        dz = self._base_offset()
        return shift_up(transform, dz) if dz else transform

    def set_transform(self, transform):
        self._world._client.submit({'type': 'set_transform', 'actor': self.id,
                                    'transform': to_wire_pose(self._to_wire_transform(transform))})

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
        """m/s in the actor's frame (CARLA's): kept by a set_target_velocity, turned into the
        world by the actor's current rotation, before every tick this client drives (tick)
        or sees (wait_for_tick); CARLA's physics enforces it every step. Needs ground_sim."""
        self._world._require('ground_sim', 'Actor.enable_constant_velocity')
        self._world._constant_velocity[self.id] = Vector3D(velocity)
        self._world._apply_constant_velocities()

    def disable_constant_velocity(self):
        self._world._constant_velocity.pop(self.id, None)

    def destroy(self):
        """True once destroyed. An actor already gone (destroyed before) logs CARLA's warning
        and returns False, as CARLA's Actor::Destroy. Only this actor goes: what is attached to
        it stays, detached at its last world pose (CARLA's Unreal keeps their world transform)."""
        if self._destroyed or self._world._client.actor(self.id) is None:
            return self._already_dead()
        try:
            self._world._client.destroy(self.id)
        except lockstep.CommandRejected as e:
            if 'unknown actor' not in str(getattr(e, 'reason', e)):
                raise
            return self._already_dead()
        self._destroyed = True
        self._wait_gone()
        return True

    def _wait_gone(self):
        """CARLA's destroy returns once the actor is gone from the world. Free-running, wait
        (a few frames at most) for the first state without it, so a spawn at its place that
        follows is not refused as a collision with it (vehicle_gallery.py)."""
        client = self._world._client
        if client.state(self.id) is None or client.world_info()['settings']['synchronous_mode']:
            return
        for _ in range(10):
            try:
                client.wait_for_tick(1.0)
            except lockstep.ClientError:
                return
            if client.state(self.id) is None:
                return

    def _already_dead(self):
        self._destroyed = True
        _warn('attempting to destroy an actor that is already dead: Actor %d (%s)' % (self.id, self.type_id))
        return False

    # --- components, bones and sockets (CARLA 0.9.15) ---
    def _components(self):
        """{name: Transform relative to the actor's origin}."""
        return {'RootComponent': Transform()}

    def _bones(self):
        """[(name, parent, Transform relative to the actor's origin)]."""
        return []

    def get_component_names(self):
        return list(self._components())

    def _component(self, component_name):
        comps = self._components()
        if component_name not in comps:
            raise RuntimeError("Actor %d (%s) has no component '%s' (it has: %s)"
                               % (self.id, self.type_id, component_name, ', '.join(comps)))
        return comps[component_name]

    def get_component_relative_transform(self, component_name):
        return Transform(self._component(component_name).location, self._component(component_name).rotation)

    def get_component_world_transform(self, component_name):
        return _compose(self.get_transform(), self._component(component_name))

    def get_bone_names(self):
        return [b[0] for b in self._bones()]

    def get_bone_relative_transforms(self):
        return [Transform(b[2].location, b[2].rotation) for b in self._bones()]

    def get_bone_world_transforms(self):
        t = self.get_transform()
        return [_compose(t, b[2]) for b in self._bones()]

    def get_socket_names(self):
        return []

    def get_socket_relative_transforms(self):
        return []

    def get_socket_world_transforms(self):
        return []

    def __eq__(self, o):
        return isinstance(o, Actor) and self.id == o.id

    def __hash__(self):
        return hash(self.id)

    def __repr__(self):
        return 'Actor(id=%d, type=%s)' % (self.id, self.type_id)


class Vehicle(Actor):
    def _base_offset(self):
        return self._half_extents()[2]

    def _components(self):
        return _components.vehicle_components(self._half_extents())

    def _bones(self):
        return [(n, p, Transform(loc)) for n, p, loc in _components.vehicle_bones(self._half_extents())]

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
            # Spawned, not simulated yet: the physics ground_sim declares for the blueprint.
            d = _physics_from_declaration(self._world._declaration(self.type_id))
            if d is None:
                raise RuntimeError('%s: vehicle %d (%s) has no state yet and its blueprint declares no physics'
                                   % (call, self.id, self.type_id))
        return self._world._applied_value(self.id, 'physics', d)

    def get_physics_control(self):
        """The vehicle's physics: what this client applied last until the GroundState of
        the frame that applies it arrives (so it reads back at once, as CARLA), then what
        ground_sim reports; before its first state, what its blueprint declares."""
        wire = self._physics_wire('Vehicle.get_physics_control')
        centre = from_wire_pose(self._wire_pose())
        return _physics_from_wire(wire, centre, self._half_extents())

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
        return VehicleLightState(int(self._world._applied_value(self.id, 'light_state', bits)) & 0xFFFFFFFF)

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
    """CARLA's walker, with one fixed skeleton (CARLA's bone names) standing upright; the
    pose calls blend a custom pose (set_bones) with it, as CARLA's blend the animation."""

    def __init__(self, world, info):
        super().__init__(world, info)
        self._custom_pose = {}
        self._blend = 0.0

    def _height(self):
        try:
            return float(self.attributes.get('height', 2 * self._half_extents()[2]))
        except ValueError:
            return 2 * self._half_extents()[2]

    def _components(self):
        h = self._height()
        return {'CollisionCylinder': Transform(), 'CharacterMesh0': Transform(Location(0, 0, -h / 2))}

    def _animation(self):
        """[(name, parent, relative Transform to the parent bone)] of the fixed skeleton."""
        bones = _components.walker_bones(self._height())
        comp = {n: loc for n, _, loc in bones}
        return [(n, p, Transform(loc - comp[p] if p else loc)) for n, p, loc in bones]

    def _posed(self):
        """[(name, parent, relative, component)] with the custom pose blended in."""
        out, comp = [], {}
        for name, parent, rel in self._animation():
            custom = self._custom_pose.get(name)
            if custom is not None and self._blend > 0:
                k = min(1.0, self._blend)
                a, b = rel, custom
                rel = Transform(a.location + (b.location - a.location) * k,
                                Rotation(a.rotation.pitch + (b.rotation.pitch - a.rotation.pitch) * k,
                                         a.rotation.yaw + (b.rotation.yaw - a.rotation.yaw) * k,
                                         a.rotation.roll + (b.rotation.roll - a.rotation.roll) * k))
            c = _compose(comp[parent], rel) if parent else Transform(rel.location, rel.rotation)
            comp[name] = c
            out.append((name, parent, rel, c))
        return out

    def _bones(self):
        return [(n, p, c) for n, p, _, c in self._posed()]

    def get_bones(self):
        """carla.WalkerBoneControlOut: every bone's world, component and relative transform."""
        t = self.get_transform()
        return WalkerBoneControlOut([BoneTransformDataOut(n, _compose(t, c), c, r) for n, _, r, c in self._posed()])

    def set_bones(self, bones):
        """A custom pose: bone name -> transform relative to its parent bone."""
        names = {n for n, _, _ in self._animation()}
        for b in bones.bone_transforms:
            name, t = (b.bone_name, b.transform) if hasattr(b, 'bone_name') else (b[0], b[1])  # (name, Transform)
            if name not in names:
                raise RuntimeError("Walker %d: no bone '%s' in its skeleton" % (self.id, name))
            self._custom_pose[name] = Transform(t.location, t.rotation)

    def blend_pose(self, blend):
        """0: the skeleton's own pose; 1: the custom pose; between: interpolated."""
        self._blend = max(0.0, min(1.0, float(blend)))

    def show_pose(self):
        self._blend = 1.0

    def hide_pose(self):
        self._blend = 0.0

    def get_pose_from_animation(self):
        """The custom pose becomes the current pose."""
        self._custom_pose = {n: r for n, _, r, _ in self._posed()}

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


class TrafficSign(Actor):
    """carla.TrafficSign: a sign actor with the volume where vehicles react to it."""

    @property
    def trigger_volume(self):
        return BoundingBox()


class TrafficLight(TrafficSign):
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

    def send(self, message):
        """CARLA 0.9.16's sensor.other.v2x_custom send(): the text goes out from this sensor at
        the next step (the last text sent before it), to the other v2x_custom sensors in range.
        Another actor raises CommandRejected (CARLA: an actor type mismatch)."""
        self._world._client.submit({'type': 'v2x_send', 'sensor': self.id, 'data': str(message)})

    # --- G-buffers: companion cameras of the render service's passes (gbuffer.py) ---
    def listen_to_gbuffer(self, gbuffer_id, callback):
        from .gbuffer import GBuffers
        if getattr(self, '_gbuffers', None) is None:
            self._gbuffers = GBuffers(self)
        self._gbuffers.listen(gbuffer_id, callback)

    def stop_gbuffer(self, gbuffer_id):
        if getattr(self, '_gbuffers', None) is not None:
            self._gbuffers.stop(gbuffer_id)

    def is_listening_gbuffer(self, gbuffer_id):
        return getattr(self, '_gbuffers', None) is not None and self._gbuffers.is_listening(gbuffer_id)

    def enable_gbuffers(self, enabled=True):
        """CARLA renders the G-buffers only when asked; here each texture's pass is made on
        its first listen_to_gbuffer, so this only records the wish."""
        self._gbuffers_enabled = bool(enabled)

    def destroy(self):
        if getattr(self, '_gbuffers', None) is not None:
            self._gbuffers.close()
        if self._callback is not None or self.is_listening:
            try:
                self.stop()
            except lockstep.ClientError:
                pass  # a sensor already gone: CARLA's warning below
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
          'traffic_sign': TrafficSign, 'controller': WalkerAIController}


# ground_sim declares each vehicle blueprint's physics (what it simulates from the spawn on)
# in attributes that CARLA's blueprints do not have, hidden by the carla package: '_physics.*',
# numbers separated by spaces, SI units (idl/lockstep/command.idl VehiclePhysicsControl).
def _physics_from_declaration(decl):
    if not decl:
        return None
    a = {x['id']: x['default'] for x in decl['attributes'] if x['id'].startswith('_physics.')}
    if not {'_physics.engine', '_physics.torque_curve', '_physics.gears', '_physics.body',
            '_physics.wheels'} <= set(a):
        return None

    def nums(key):
        return [float(v) for v in a[key].split()]

    max_rpm, moi, damping, autobox, switch, clutch, final_ratio = nums('_physics.engine')
    curve = nums('_physics.torque_curve')
    gears = nums('_physics.gears')
    mass, drag, cx, cy, cz = nums('_physics.body')
    (friction, radius, steer, brake, handbrake, stiffness, sdamping, wheelbase, track) = nums('_physics.wheels')
    return {'torque_curve': [(curve[i], curve[i + 1]) for i in range(0, len(curve) - 1, 2)], 'max_rpm': max_rpm,
            'moi': moi, 'damping_rate_full_throttle': damping, 'use_gear_autobox': autobox != 0.0,
            'gear_switch_time': switch, 'clutch_strength': clutch, 'final_ratio': final_ratio,
            'forward_gears': [tuple(gears[i:i + 3]) for i in range(0, len(gears) - 2, 3)], 'mass': mass,
            'drag_coefficient': drag, 'center_of_mass': (cx, cy, cz), 'tire_friction': friction,
            'wheel_radius': radius, 'max_steer_angle': steer, 'max_brake_torque': brake,
            'max_handbrake_torque': handbrake, 'suspension_stiffness': stiffness, 'suspension_damping': sdamping,
            'wheelbase': wheelbase, 'track': track}


def make_actor(world, info):
    return _KINDS.get(info['kind'], Actor)(world, info)


# Actor ids and threading: the world's callbacks may run on the dispatch thread.
_lock = threading.Lock()
