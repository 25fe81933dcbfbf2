"""How an unsupported call fails: loudly, naming the call and why (never a silent no-op)."""

__all__ = ['LockstepUnsupported', 'unsupported', 'add_unsupported']


class LockstepUnsupported(RuntimeError):
    """A carla call Lockstep cannot do (yet); the message names the call and why."""


def unsupported(call, why):
    raise LockstepUnsupported('%s is not supported by Lockstep: %s (docs/compatibility.md)' % (call, why))


def add_unsupported(cls, why_by_name):
    """Gives `cls` a method per name that raises LockstepUnsupported naming
    '<class>.<name>' and why, so a CARLA call Lockstep lacks never ends in AttributeError."""
    for name, why in why_by_name.items():
        if name in cls.__dict__:
            continue  # the class implements it (an implementation wins over the fallback)
        def method(self, *args, _call='%s.%s' % (cls.__name__, name), _why=why, **kwargs):
            unsupported(_call, _why)
        method.__name__ = name
        method.__doc__ = 'Not supported by Lockstep: %s.' % why
        setattr(cls, name, method)
