"""Lockstep's Python client. `lockstep.carla` mirrors the carla module, `lockstep.airsim`
the airsim module; both run over the native client in `lockstep._lockstep`."""
from lockstep._lockstep import (Client, ClientError, CommandRejected, SensorLate, SensorSample,  # noqa: F401
                                Multirotor, CommandFuture, Map, Waypoint, default_domain)
