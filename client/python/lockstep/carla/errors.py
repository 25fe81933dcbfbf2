"""How an unsupported call fails: loudly, naming the call and why (never a silent no-op)."""

__all__ = ['LockstepUnsupported', 'unsupported']


class LockstepUnsupported(RuntimeError):
    """A carla call Lockstep cannot do (yet); the message names the call and why."""


def unsupported(call, why):
    raise LockstepUnsupported('%s is not supported by Lockstep: %s (docs/compatibility.md)' % (call, why))
