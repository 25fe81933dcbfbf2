"""Lockstep's Python client. `lockstep.carla` mirrors the carla module, `lockstep.airsim`
the airsim module; both run over the native client in `lockstep._lockstep`."""
import atexit
import threading
import weakref

from lockstep._lockstep import (Client, ClientError, CommandRejected, Coordinator, SensorLate, SensorSample,  # noqa: F401
                                Multirotor, CommandFuture, Map, Waypoint, default_domain)

_sessions = weakref.WeakValueDictionary()   # DDS domain -> the process's shared Client
_sessions_lock = threading.Lock()
_clients = weakref.WeakSet()                # every native Client of this process, closed at exit


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
            _clients.add(client)
        return client


@atexit.register
def _close_clients():
    """Before the interpreter finalizes (atexit runs after the non-daemon threads are
    joined, before finalization): stop every client's threads and wake every call still
    waiting (daemon threads get ClientError), so no native thread calls into a Python that is
    going away. Without this, a script that ends with sensors listening or a daemon thread in
    wait_for_tick() aborts at exit."""
    from lockstep import _lockstep
    _lockstep._prepare_exit()
    for client in list(_clients):
        try:
            client.close()
        except Exception:  # noqa: BLE001 - exit goes on whatever one client says
            pass
