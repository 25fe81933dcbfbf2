"""carla.command: batch commands for Client.apply_batch / apply_batch_sync."""
from .geometry import to_wire_pose

__all__ = ['Response', 'FutureActor', 'SpawnActor', 'DestroyActor', 'ApplyVehicleControl', 'ApplyWalkerControl',
           'ApplyTransform', 'ApplyLocation', 'SetAutopilot', 'SetSimulatePhysics', 'ApplyVehicleAckermannControl']

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
        return {'type': 'spawn', 'blueprint': self.blueprint.id, 'transform': to_wire_pose(self.transform),
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
        return {'type': 'set_transform', 'actor': self.actor_id or actor, 'transform': to_wire_pose(self.transform)}


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


class SetSimulatePhysics(_Command):
    def __init__(self, actor, enabled):
        from .errors import unsupported
        unsupported('command.SetSimulatePhysics', 'physics cannot be switched off per actor on the wire')


class ApplyVehicleAckermannControl(_Command):
    def __init__(self, actor, control):
        from .errors import unsupported
        unsupported('command.ApplyVehicleAckermannControl', 'the wire carries throttle/steer/brake control only')
