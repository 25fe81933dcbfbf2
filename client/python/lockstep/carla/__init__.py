"""lockstep.carla: the `carla` Python API over Lockstep. Same names, same conventions
(left-handed locations: y = -ENU y; angles in degrees). `import carla` resolves here when
the drop-in package is on the path (`lockstep python script.py`). Calls Lockstep cannot do
raise LockstepUnsupported naming the call and why; docs/compatibility.md lists them all."""
from lockstep import ClientError, CommandRejected, SensorLate  # noqa: F401

from . import command  # noqa: F401
from .actors import *  # noqa: F401,F403
from .blueprints import *  # noqa: F401,F403
from .errors import LockstepUnsupported  # noqa: F401
from .geometry import *  # noqa: F401,F403
from .map import *  # noqa: F401,F403
from .physics import *  # noqa: F401,F403
from .sensor_data import *  # noqa: F401,F403
from .world import *  # noqa: F401,F403
from . import unsupported as _unsupported  # noqa: F401 (installs the calls that raise)

cc = ColorConverter  # noqa: F405


class MapLayer:
    NONE = 0
    Buildings = 1
    Decals = 2
    Foliage = 4
    Ground = 8
    ParkedVehicles = 16
    Particles = 32
    Props = 64
    StreetLights = 128
    Walls = 256
    All = 0xFFFF


class CityObjectLabel:
    NONE = 0
    Roads = 1
    Sidewalks = 2
    Buildings = 3
    Walls = 4
    Fences = 5
    Poles = 6
    TrafficLight = 7
    TrafficSigns = 8
    Vegetation = 9
    Terrain = 10
    Sky = 11
    Pedestrians = 12
    Rider = 13
    Car = 14
    Truck = 15
    Bus = 16
    Train = 17
    Motorcycle = 18
    Bicycle = 19
    Static = 20
    Dynamic = 21
    Other = 22
    Water = 23
    RoadLines = 24
    Ground = 25
    Bridge = 26
    RailTrack = 27
    GuardRail = 28
    Any = 0xFF
