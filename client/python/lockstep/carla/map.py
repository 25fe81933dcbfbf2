"""carla.Map, Waypoint, LaneType, LaneChange, LaneMarking... over Lockstep's map library
(the same OpenDRIVE queries the services use), built from the map the coordinator publishes."""
import math

from .errors import unsupported
from .geometry import Location, Rotation, Transform

__all__ = ['LaneType', 'LaneChange', 'LaneMarkingType', 'LaneMarkingColor', 'LaneMarking', 'Waypoint', 'Map']


class LaneType:
    NONE = 1
    Driving = 1 << 1
    Stop = 1 << 2
    Shoulder = 1 << 3
    Biking = 1 << 4
    Sidewalk = 1 << 5
    Border = 1 << 6
    Restricted = 1 << 7
    Parking = 1 << 8
    Bidirectional = 1 << 9
    Median = 1 << 10
    Special1 = 1 << 11
    Special2 = 1 << 12
    Special3 = 1 << 13
    RoadWorks = 1 << 14
    Tram = 1 << 15
    Rail = 1 << 16
    Entry = 1 << 17
    Exit = 1 << 18
    OffRamp = 1 << 19
    OnRamp = 1 << 20
    Any = 0xFFFFFFFE


class LaneChange:
    NONE = 0
    Right = 1
    Left = 2
    Both = 3


class LaneMarkingType:
    NONE = 0
    Other = 1
    Broken = 2
    Solid = 3
    SolidSolid = 4
    SolidBroken = 5
    BrokenSolid = 6
    BrokenBroken = 7
    BottsDots = 8
    Grass = 9
    Curb = 10


class LaneMarkingColor:
    Standard = 0
    White = 0
    Blue = 1
    Green = 2
    Red = 3
    Yellow = 4
    Other = 5


# Lockstep's RoadMarkType order (map library) -> CARLA's LaneMarkingType.
_MARK_TYPES = [LaneMarkingType.NONE, LaneMarkingType.Solid, LaneMarkingType.Broken, LaneMarkingType.SolidSolid,
               LaneMarkingType.SolidBroken, LaneMarkingType.BrokenSolid, LaneMarkingType.BrokenBroken,
               LaneMarkingType.BottsDots, LaneMarkingType.Grass, LaneMarkingType.Curb, LaneMarkingType.Other,
               LaneMarkingType.Other]
_MARK_COLORS = [LaneMarkingColor.Standard, LaneMarkingColor.White, LaneMarkingColor.Yellow, LaneMarkingColor.Blue,
                LaneMarkingColor.Green, LaneMarkingColor.Red, LaneMarkingColor.Other, LaneMarkingColor.Other,
                LaneMarkingColor.Other]
# The wire's LaneMarkingType (sensor.idl) -> CARLA's.
_WIRE_MARKS = [LaneMarkingType.NONE, LaneMarkingType.Solid, LaneMarkingType.Broken, LaneMarkingType.SolidSolid,
               LaneMarkingType.SolidBroken, LaneMarkingType.BrokenSolid, LaneMarkingType.BrokenBroken,
               LaneMarkingType.BottsDots, LaneMarkingType.Grass, LaneMarkingType.Curb, LaneMarkingType.Other]


class LaneMarking:
    def __init__(self, type=LaneMarkingType.NONE, color=LaneMarkingColor.Standard, lane_change=LaneChange.NONE, width=0.0):
        self.type, self.color, self.lane_change, self.width = type, color, lane_change, width

    @classmethod
    def from_wire(cls, type_index, color, width, left, right):
        colors = {'white': LaneMarkingColor.White, 'yellow': LaneMarkingColor.Yellow, 'blue': LaneMarkingColor.Blue,
                  'green': LaneMarkingColor.Green, 'red': LaneMarkingColor.Red}
        change = (LaneChange.Left if left else 0) | (LaneChange.Right if right else 0)
        return cls(_WIRE_MARKS[type_index] if type_index < len(_WIRE_MARKS) else LaneMarkingType.Other,
                   colors.get(color, LaneMarkingColor.Standard), change, width)

    def __repr__(self):
        return 'LaneMarking(type=%s, width=%g)' % (self.type, self.width)


def _transform(pose6):
    """(x, y, z, yaw, pitch, roll) ENU radians -> carla.Transform."""
    x, y, z, yaw, pitch, roll = pose6
    return Transform(Location(x, -y, z), Rotation(-math.degrees(pitch), -math.degrees(yaw), math.degrees(roll)))


class Waypoint:
    __slots__ = ('_w', '_map', 'id', 'road_id', 'section_id', 'lane_id', 's', 'is_junction', 'lane_width', 'lane_type',
                 'junction_id', '_transform')

    def __init__(self, native, carla_map):
        self._w = native
        self._map = carla_map
        self.id = native.id
        self.road_id = native.road
        self.section_id = native.section
        self.lane_id = native.lane
        self.s = native.s
        self.junction_id = native.junction
        self.is_junction = native.junction >= 0
        self.lane_width = native.lane_width
        self.lane_type = native.lane_type
        self._transform = None

    @property
    def transform(self):
        if self._transform is None:
            self._transform = _transform(self._w.pose)
        return self._transform

    @property
    def lane_change(self):
        return self._map._native.lane_change(self._w)

    def _marking(self, left):
        m = self._map._native.marking(self._w, left)
        if m is None:
            return None
        t, c, change, width = m
        return LaneMarking(_MARK_TYPES[t], _MARK_COLORS[c], change, width)

    @property
    def left_lane_marking(self):
        return self._marking(True)

    @property
    def right_lane_marking(self):
        return self._marking(False)

    def _wrap(self, natives):
        return [Waypoint(w, self._map) for w in natives]

    def next(self, distance):
        return self._wrap(self._map._native.next(self._w, distance))

    def previous(self, distance):
        return self._wrap(self._map._native.previous(self._w, distance))

    def next_until_lane_end(self, distance):
        return self._wrap(self._map._native.next_until_lane_end(self._w, distance))

    def previous_until_lane_start(self, distance):
        out = []
        wp = self
        while True:
            prev = [p for p in wp.previous(distance) if p.road_id == wp.road_id and p.lane_id == wp.lane_id]
            if not prev:
                return out
            wp = prev[0]
            out.append(wp)

    def get_left_lane(self):
        w = self._map._native.left_lane(self._w)
        return Waypoint(w, self._map) if w is not None else None

    def get_right_lane(self):
        w = self._map._native.right_lane(self._w)
        return Waypoint(w, self._map) if w is not None else None

    def get_junction(self):
        unsupported('Waypoint.get_junction', 'carla.Junction objects are not built by the client yet; '
                    'use Waypoint.junction_id and Map.get_topology()')

    def get_landmarks(self, distance, stop_at_junction=False):
        unsupported('Waypoint.get_landmarks', 'landmarks (signs) are not exposed over the wire')

    def __eq__(self, o):
        return isinstance(o, Waypoint) and self.id == o.id

    def __hash__(self):
        return hash(self.id)

    def __repr__(self):
        return 'Waypoint(road=%d, section=%d, lane=%d, s=%.3f)' % (self.road_id, self.section_id, self.lane_id, self.s)


class Map:
    def __init__(self, native, opendrive_name):
        self._native = native
        self.name = native.name or opendrive_name

    def get_spawn_points(self):
        return [_transform(p) for p in self._native.spawn_points(25.0)]

    def get_waypoint(self, location, project_to_road=True, lane_type=LaneType.Driving):
        w = self._native.waypoint(location.x, -location.y, location.z, project_to_road, int(lane_type))
        return Waypoint(w, self) if w is not None else None

    def get_waypoint_xodr(self, road_id, lane_id, s):
        return Waypoint(self._native.make_waypoint(road_id, -1, lane_id, s), self)

    def generate_waypoints(self, distance):
        return [Waypoint(w, self) for w in self._native.generate_waypoints(distance)]

    def get_topology(self):
        return [(Waypoint(a, self), Waypoint(b, self)) for a, b in self._native.topology()]

    def transform_to_geolocation(self, location):
        unsupported('Map.transform_to_geolocation', "the map's geo reference is not exposed to clients yet; "
                    'attach a sensor.other.gnss for WGS84 positions')

    def to_opendrive(self):
        unsupported('Map.to_opendrive', 'read the .xodr file the run was started with')

    def get_all_landmarks(self):
        unsupported('Map.get_all_landmarks', 'landmarks (signs) are not exposed over the wire')

    def get_crosswalks(self):
        unsupported('Map.get_crosswalks', 'crosswalks are not exposed over the wire')

    def __repr__(self):
        return 'Map(name=%s)' % self.name
