"""carla.Map, Waypoint, LaneType, LaneChange, LaneMarking... over Lockstep's map library
(the same OpenDRIVE queries the services use), built from the map the coordinator publishes."""
import math

from .geometry import BoundingBox, GeoLocation, Location, Rotation, Transform, Vector3D

__all__ = ['LaneType', 'LaneChange', 'LaneMarkingType', 'LaneMarkingColor', 'LaneMarking', 'Waypoint', 'Map',
           'Junction', 'Landmark', 'LandmarkOrientation', 'LandmarkType']


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


def _xodr_id(text):
    """An OpenDRIVE id as CARLA gives it: an int (ids of CARLA's towns are numbers)."""
    try:
        return int(text)
    except ValueError:
        return text


class LandmarkOrientation:
    Positive = 0
    Negative = 1
    Both = 2


class LandmarkType:
    """CARLA's OpenDRIVE signal type codes (strings, as in the file)."""
    Danger = '101'
    LanesMerging = '121'
    CautionPedestrian = '133'
    CautionBicycle = '138'
    LevelCrossing = '150'
    StopSign = '206'
    YieldSign = '205'
    MandatoryTurnDirection = '209'
    MandatoryLeftRightDirection = '211'
    TwoChoiceTurnDirection = '214'
    Roundabout = '215'
    PassRightLeft = '222'
    AccessForbidden = '250'
    AccessForbiddenMotorvehicles = '251'
    AccessForbiddenTrucks = '253'
    AccessForbiddenBicycle = '254'
    AccessForbiddenWeight = '263'
    AccessForbiddenWidth = '264'
    AccessForbiddenHeight = '265'
    AccessForbiddenWrongDirection = '267'
    ForbiddenUTurn = '272'
    MaximumSpeed = '274'
    ForbiddenOvertakingMotorvehicles = '276'
    ForbiddenOvertakingTrucks = '277'
    AbsoluteNoStop = '283'
    RestrictedStop = '286'
    HasWayNextIntersection = '301'
    PriorityWay = '306'
    PriorityWayEnd = '307'
    CityBegin = '310'
    CityEnd = '311'
    Highway = '330'
    DeadEnd = '357'
    RecomendedSpeed = '380'
    RecomendedSpeedEnd = '381'
    LightPost = '1000001'


class Landmark:
    """carla.Landmark: an OpenDRIVE <signal> (or a <signalReference> to one) met on a road."""

    def __init__(self, d, carla_map, waypoint=None):
        self._map = carla_map
        self.id = d['id']
        self.name = d['name']
        self.road_id = _xodr_id(d['road_id'])
        self.distance = d.get('distance', 0.0)
        self.s, self.t = d['s'], d['t']
        self.is_dynamic = d['dynamic']
        o = d['orientation']
        self.orientation = (LandmarkOrientation.Positive if o == '+' else LandmarkOrientation.Negative if o == '-'
                            else LandmarkOrientation.Both)
        self.z_offset, self.h_offset = d['z_offset'], d['h_offset']
        self.pitch, self.roll = 0.0, 0.0
        self.country, self.type, self.sub_type = d['country'], d['type'], d['subtype']
        self.value = d['value'] if d['value'] == d['value'] else -1.0  # NaN: absent
        self.unit, self.height, self.width, self.text = d['unit'], d['height'], d['width'], d['text']
        self.transform = _transform(d['pose'])
        self.waypoint = waypoint
        self._validity = [tuple(v) for v in d['validity']]

    def get_lane_validities(self):
        return list(self._validity)

    def __repr__(self):
        return 'Landmark(id=%s, type=%s, road_id=%s, s=%.2f)' % (self.id, self.type, self.road_id, self.s)


class Junction:
    """carla.Junction: id (OpenDRIVE), bounding_box (world, CARLA's frame), get_waypoints."""

    def __init__(self, d, carla_map):
        self._map = carla_map
        self._index = d['index']
        self.id = _xodr_id(d['id'])
        (x, y, z), (ex, ey, ez), _ = d['bounding_box']
        self.bounding_box = BoundingBox(Location(x, -y, z), Vector3D(ex, ey, ez))

    def get_waypoints(self, lane_type=None):
        lane_type = LaneType.Driving if lane_type is None else lane_type
        return [(Waypoint(a, self._map), Waypoint(b, self._map))
                for a, b in self._map._native.junction_waypoints(self._index, _lane_mask(lane_type))]

    def __eq__(self, o):
        return isinstance(o, Junction) and self.id == o.id

    def __hash__(self):
        return hash(self.id)

    def __repr__(self):
        return 'Junction(id=%s)' % self.id


def _lane_mask(lane_type):
    """CARLA's LaneType bits as the map library's mask (an int32: LaneType.Any is 0xFFFFFFFE,
    whose top bit no lane type uses)."""
    return int(lane_type) & 0x7FFFFFFF


def _native_from_text(name, text):
    import os
    import tempfile
    from lockstep._lockstep import Map as _NativeMap
    d = tempfile.mkdtemp(prefix='lockstep-map-')
    path = os.path.join(d, os.path.basename(str(name)) or 'map')
    if not path.endswith('.xodr'):
        path += '.xodr'
    try:
        with open(path, 'w') as f:
            f.write(text)
        return _NativeMap.load(path)
    finally:
        try:
            os.remove(path)
            os.rmdir(d)
        except OSError:
            pass


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
        self.road_id = _xodr_id(native.road_xodr)
        self.section_id = native.section
        self.lane_id = native.lane
        self.s = native.s
        self.junction_id = _xodr_id(native.junction_xodr)
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
    def is_intersection(self):
        """CARLA's deprecated name of is_junction."""
        return self.is_junction

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
        """The carla.Junction the waypoint is in, None outside junctions (as CARLA)."""
        d = self._map._native.junction(self._w)
        return Junction(d, self._map) if d is not None else None

    def get_landmarks(self, distance, stop_at_junction=False):
        """Signals ahead on this lane (every branch) within `distance` m, nearest first."""
        return [Landmark(d, self._map, Waypoint(d['waypoint'], self._map))
                for d in self._map._native.landmarks_ahead(self._w, float(distance), bool(stop_at_junction))]

    def get_landmarks_of_type(self, distance, type, stop_at_junction=False):
        return [l for l in self.get_landmarks(distance, stop_at_junction) if l.type == str(type)]

    def __eq__(self, o):
        return isinstance(o, Waypoint) and self.id == o.id

    def __hash__(self):
        return hash(self.id)

    def __repr__(self):
        return 'Waypoint(road=%d, section=%d, lane=%d, s=%.3f)' % (self.road_id, self.section_id, self.lane_id, self.s)


class Map:
    """carla.Map. `carla.Map(name, xodr_content)` builds one from OpenDRIVE text, as CARLA's."""

    def __init__(self, native, opendrive_name):
        if isinstance(native, str):  # CARLA's Map(name, xodr_content)
            name, text = native, opendrive_name
            native = _native_from_text(name, text)
            from .world import _remember_opendrive
            _remember_opendrive(None, native.name or name, text)
            opendrive_name = name
        self._native = native
        self.name = native.name or opendrive_name

    def get_spawn_points(self):
        return [_transform(p) for p in self._native.spawn_points(25.0)]

    def get_waypoint(self, location, project_to_road=True, lane_type=LaneType.Driving):
        w = self._native.waypoint(location.x, -location.y, location.z, project_to_road, _lane_mask(lane_type))
        return Waypoint(w, self) if w is not None else None

    def get_waypoint_xodr(self, road_id, lane_id, s):
        w = self._native.waypoint_xodr(str(road_id), int(lane_id), float(s))
        return Waypoint(w, self) if w is not None else None

    def generate_waypoints(self, distance):
        return [Waypoint(w, self) for w in self._native.generate_waypoints(distance)]

    def get_topology(self):
        return [(Waypoint(a, self), Waypoint(b, self)) for a, b in self._native.topology()]

    def _geo_reference(self):
        lat = lon = 0.0  # as the GNSS sensor: a missing reference is (0, 0)
        for token in self._native.geo_reference.split():
            key, _, value = token.partition('=')
            try:
                if key == '+lat_0':
                    lat = float(value)
                elif key == '+lon_0':
                    lon = float(value)
            except ValueError:
                pass
        return lat, lon

    def get_geo_reference(self):
        """The map's origin as a carla.GeoLocation (OpenDRIVE <geoReference> +lat_0, +lon_0)."""
        lat0, lon0 = self._geo_reference()
        return GeoLocation(lat0, lon0, 0.0)

    get_georeference = get_geo_reference

    def geolocation_to_transform(self, geo_location, ellipsoid=None):
        """The inverse of transform_to_geolocation: a carla.Location (z = altitude)."""
        lat0, lon0 = self._geo_reference()
        r = float(ellipsoid.a) if ellipsoid is not None else 6378137.0
        scale = math.cos(math.radians(lat0))
        mx0 = scale * math.radians(lon0) * r
        my0 = scale * r * math.log(math.tan(math.radians(90.0 + lat0) / 2.0))
        mx = scale * math.radians(geo_location.longitude) * r
        my = scale * r * math.log(math.tan(math.radians(90.0 + geo_location.latitude) / 2.0))
        return Location(mx - mx0, -(my - my0), geo_location.altitude)

    def transform_to_geolocation(self, location, ellipsoid=None):
        """CARLA's GeoLocation::Transform: a Mercator projection scaled at the
        OpenDRIVE <geoReference> latitude (+lat_0, +lon_0), altitude = z; the radius is the
        ellipsoid's semi-major axis (CARLA 0.9.16's GeoEllipsoid; WGS84's by default)."""
        lat0, lon0 = self._geo_reference()
        r = float(ellipsoid.a) if ellipsoid is not None else 6378137.0
        scale = math.cos(math.radians(lat0))
        mx = scale * math.radians(lon0) * r + location.x
        my = scale * r * math.log(math.tan(math.radians(90.0 + lat0) / 2.0)) - location.y
        lon = mx * 180.0 / (math.pi * r * scale)
        lat = 360.0 * math.atan(math.exp(my / (r * scale))) / math.pi - 90.0
        return GeoLocation(lat, lon, location.z)

    def to_opendrive(self):
        """The map's OpenDRIVE text."""
        from .world import opendrive_text
        text = opendrive_text(self.name, self._native)
        if text is None:
            raise RuntimeError("Map.to_opendrive: the OpenDRIVE text of map '%s' was loaded by another process and "
                               'no %s.xodr on the maps path (LOCKSTEP_MAPS_PATH) matches it' % (self.name, self.name))
        return text

    def get_all_landmarks(self):
        """One carla.Landmark per <signal> and per <signalReference> of the OpenDRIVE file
        (CARLA's get_all_landmarks; their waypoint is None, as CARLA's)."""
        return [Landmark(d, self) for d in self._native.all_landmarks()]

    def get_all_landmarks_from_id(self, opendrive_id):
        return [l for l in self.get_all_landmarks() if l.id == str(opendrive_id)]

    def get_all_landmarks_of_type(self, type):
        return [l for l in self.get_all_landmarks() if l.type == str(type)]

    def get_landmark_group(self, landmark):
        """The landmarks of the signals that share a <controller> with this one."""
        for ids in self._native.landmark_groups().values():
            if landmark.id in ids:
                return [l for l in self.get_all_landmarks() if l.id in ids]
        return [landmark]

    def get_crosswalks(self):
        """Crosswalk polygons (OpenDRIVE objects of type crosswalk) one after another, each
        closed (first corner repeated), as carla.Locations (CARLA's flat list)."""
        return [Location(x, -y, z) for x, y, z in self._native.crosswalks()]

    def _junction_id(self, index):
        d = self._native.junction_by_index(index)
        return _xodr_id(d['id']) if d is not None else None

    def _trigger_volume(self, signal_id):
        for i in self._native.traffic_light_infos():
            if i['signal_id'] == signal_id:
                return i['trigger_volume']
        return None

    def _stop_waypoints(self, signal_id):
        for i in self._native.traffic_light_infos():
            if i['signal_id'] == signal_id:
                return [Waypoint(w, self) for w in i['stop_waypoints']]
        return []

    def __repr__(self):
        return 'Map(name=%s)' % self.name
