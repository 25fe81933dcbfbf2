"""Lockstep's Python client. `lockstep.carla` mirrors the carla module, `lockstep.airsim`
the airsim module; both run over the native client in `lockstep._lockstep`."""
import threading
import weakref

from lockstep._lockstep import (Client, ClientError, CommandRejected, Coordinator, SensorLate, SensorSample,  # noqa: F401
                                Multirotor, CommandFuture, Map, Waypoint, default_domain)

_sessions = weakref.WeakValueDictionary()   # DDS domain -> the process's shared Client
_sessions_lock = threading.Lock()


def session(timeout=10.0):
    """The process's one DDS session on the default domain ($LOCKSTEP_DOMAIN), shared by
    every carla.Client and airsim.MultirotorClient of this process: what one of them ticks
    or spawns, the others see at once, as all clients of one CARLA server do. It lives
    while any of them holds it; `timeout` bounds the connection of the first."""
    domain = default_domain()
    with _sessions_lock:
        client = _sessions.get(domain)
        if client is None:
            client = Client(domain=domain, timeout=timeout)
            _sessions[domain] = client
        return client
