"""carla.command: batch commands for Client.apply_batch / apply_batch_sync."""
import math

from .errors import unsupported
from .geometry import to_enu_vector, to_wire_pose

__all__ = ['Response', 'FutureActor', 'SpawnActor', 'DestroyActor', 'ApplyVehicleControl', 'ApplyWalkerControl',
           'ApplyTransform', 'ApplyLocation', 'SetAutopilot', 'SetSimulatePhysics', 'ApplyVehicleAckermannControl',
           'ApplyImpulse', 'ApplyForce', 'ApplyTargetVelocity', 'ApplyTargetAngularVelocity', 'SetVehicleLightState',
           'ApplyVehiclePhysicsControl', 'SetEnableGravity', 'ApplyTorque', 'ApplyAngularImpulse']

FutureActor = 0  # a SpawnActor's .then() commands refer to the actor it spawns


def _id(actor):
    return actor if isinstance(actor, int) else actor.id


class Response:
    def __init__(self, actor_id=0, error=''):
        self.actor_id = actor_id
        self.error = error

    def has_error(self):
        return bool(self.error)

    def __repr__(self):
        return 'Response(actor_id=%d, error=%r)' % (self.actor_id, self.error)


class _Command:
    def then(self, command):
        self._then = getattr(self, '_then', []) + [command]
        return self


class SpawnActor(_Command):
    def __init__(self, blueprint, transform, parent=None):
        self.blueprint, self.transform, self.parent = blueprint, transform, parent

    def to_dict(self, actor=0):
        t = getattr(self, '_wire_transform', self.transform)  # Client._prepare: CARLA's origins -> the wire's
        return {'type': 'spawn', 'blueprint': self.blueprint.id, 'transform': to_wire_pose(t),
                'attributes': self.blueprint.spawn_attributes(), 'parent': _id(self.parent) if self.parent else 0}


class DestroyActor(_Command):
    def __init__(self, actor):
        self.actor_id = _id(actor)

    def to_dict(self, actor=0):
        return {'type': 'destroy', 'actor': self.actor_id or actor}


class ApplyVehicleControl(_Command):
    def __init__(self, actor, control):
        self.actor_id, self.control = _id(actor), control

    def to_dict(self, actor=0):
        return dict(self.control._wire(), actor=self.actor_id or actor)


class ApplyWalkerControl(_Command):
    def __init__(self, actor, control):
        self.actor_id, self.control = _id(actor), control

    def to_dict(self, actor=0):
        return dict(self.control._wire(), actor=self.actor_id or actor)


class ApplyTransform(_Command):
    def __init__(self, actor, transform):
        self.actor_id, self.transform = _id(actor), transform

    def to_dict(self, actor=0):
        t = getattr(self, '_wire_transform', self.transform)  # Client._prepare: CARLA's origins -> the wire's
        return {'type': 'set_transform', 'actor': self.actor_id or actor, 'transform': to_wire_pose(t)}


class ApplyLocation(ApplyTransform):
    def __init__(self, actor, location):
        from .geometry import Transform
        super().__init__(actor, Transform(location))


class SetAutopilot(_Command):
    def __init__(self, actor, enabled, tm_port=8000):
        self.actor_id, self.enabled = _id(actor), enabled

    def to_dict(self, actor=0):
        return {'type': 'traffic_manager', 'parameter': 'autopilot', 'actor': self.actor_id or actor,
                'value': 1.0 if self.enabled else 0.0}


class _Physics(_Command):
    """An actor physics command (ground_sim); its failure there is raised by the next tick."""
    _kind = None

    def _extra(self):
        return {}

    def to_dict(self, actor=0):
        d = {'type': 'actor_physics', 'actor': self.actor_id or actor, 'kind': self._kind}
        d.update(self._extra())
        return d


class SetSimulatePhysics(_Physics):
    _kind, _watch = 'set_simulate_physics', 'command.SetSimulatePhysics'

    def __init__(self, actor, enabled):
        self.actor_id, self.enabled = _id(actor), bool(enabled)

    def _extra(self):
        return {'enabled': self.enabled}


class ApplyImpulse(_Physics):
    _kind, _watch = 'add_impulse', 'command.ApplyImpulse'

    def __init__(self, actor, impulse):
        self.actor_id, self.impulse = _id(actor), impulse

    def _extra(self):
        return {'value': to_enu_vector(self.impulse)}


class ApplyForce(_Physics):
    """ground_sim has no force: the impulse force x fixed_delta_seconds (one tick), set by
    Client.apply_batch*."""
    _kind, _watch = 'add_impulse', 'command.ApplyForce'

    def __init__(self, actor, force):
        self.actor_id, self.force = _id(actor), force
        self._dt = None

    def _extra(self):
        if self._dt is None:
            raise RuntimeError('command.ApplyForce: run it through Client.apply_batch / apply_batch_sync')
        return {'value': tuple(c * self._dt for c in to_enu_vector(self.force))}


class ApplyTargetVelocity(_Physics):
    _kind, _watch = 'set_target_velocity', 'command.ApplyTargetVelocity'

    def __init__(self, actor, velocity):
        self.actor_id, self.velocity = _id(actor), velocity

    def _extra(self):
        return {'value': to_enu_vector(self.velocity)}


class ApplyTargetAngularVelocity(_Physics):
    _kind, _watch = 'set_target_angular_velocity', 'command.ApplyTargetAngularVelocity'

    def __init__(self, actor, angular_velocity):
        self.actor_id, self.angular_velocity = _id(actor), angular_velocity

    def _extra(self):
        w = self.angular_velocity
        return {'value': (math.radians(w.x), -math.radians(w.y), -math.radians(w.z))}


class SetVehicleLightState(_Physics):
    _kind, _watch = 'set_light_state', 'command.SetVehicleLightState'

    def __init__(self, actor, light_state):
        self.actor_id, self.light_state = _id(actor), int(light_state) & 0xFFFFFFFF

    def _extra(self):
        return {'light_state': self.light_state}


class ApplyVehicleAckermannControl(_Command):
    _watch = 'command.ApplyVehicleAckermannControl'

    def __init__(self, actor, control):
        self.actor_id, self.control = _id(actor), control

    def to_dict(self, actor=0):
        return dict(self.control._wire(), actor=self.actor_id or actor)


class ApplyVehiclePhysicsControl(_Command):
    """The physics of a vehicle spawned earlier (its current values fill what the control
    leaves to ground_sim); set by Client.apply_batch*."""
    _watch = 'command.ApplyVehiclePhysicsControl'

    def __init__(self, actor, physics_control):
        self.actor_id, self.physics_control = _id(actor), physics_control
        self._current = None

    def to_dict(self, actor=0):
        if self._current is None:
            raise RuntimeError('command.ApplyVehiclePhysicsControl: run it through Client.apply_batch / '
                               'apply_batch_sync, for a vehicle that has a state')
        from .physics import to_wire
        return {'type': 'vehicle_physics', 'actor': self.actor_id or actor,
                'physics': to_wire(self.physics_control, self._current, self._watch)}


class SetEnableGravity(_Command):
    def __init__(self, actor, enabled):
        unsupported('command.SetEnableGravity', 'gravity cannot be switched off per actor on the wire')


class ApplyTorque(_Command):
    def __init__(self, actor, torque):
        unsupported('command.ApplyTorque', 'ground_sim takes no torque; use ApplyTargetAngularVelocity')


class ApplyAngularImpulse(_Command):
    def __init__(self, actor, impulse):
        unsupported('command.ApplyAngularImpulse', 'ground_sim takes no angular impulse; use '
                    'ApplyTargetAngularVelocity')
