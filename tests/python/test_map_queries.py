"""carla.Map queries the client answers from the OpenDRIVE file, on CARLA's Town01 and
Town02 and the generated town: geolocation through the <geoReference>, landmarks
(signals and signal references), junctions, crosswalks, OpenDRIVE ids. No simulation."""
import math
import os
import xml.etree.ElementTree as ET

import pytest

import carla
import lockstep

SOURCE = os.environ.get('LOCKSTEP_SOURCE', '')
CARLA_MAPS = os.path.join(os.path.dirname(os.path.abspath(SOURCE)), 'shared', 'maps', 'carla')
BIN = os.environ.get('LOCKSTEP_BIN', '')
GENERATED = os.path.join(os.path.dirname(os.path.abspath(BIN)), 'maps', 'generated')
R = 6378137.0


def load(path):
    return carla.Map(lockstep.Map.load(path), os.path.splitext(os.path.basename(path))[0])


def town(name):
    path = os.path.join(CARLA_MAPS, name + '.xodr')
    if not os.path.exists(path):
        pytest.skip('%s not found' % path)
    return load(path), ET.parse(path).getroot()


@pytest.fixture(scope='module', params=['Town01', 'Town02'])
def carla_town(request):
    return town(request.param)


def test_geolocation_follows_carlas_projection(tmp_path):
    m, _ = town('Town01')  # +lat_0=0 +lon_0=0
    g = m.transform_to_geolocation(carla.Location(0, 0, 0))
    assert (g.latitude, g.longitude, g.altitude) == pytest.approx((0, 0, 0), abs=1e-12)
    g = m.transform_to_geolocation(carla.Location(1000, 0, 5))
    assert g.longitude == pytest.approx(math.degrees(1000 / R), rel=1e-9)
    assert g.latitude == pytest.approx(0, abs=1e-12)
    assert g.altitude == 5
    g = m.transform_to_geolocation(carla.Location(0, 1000, 0))  # CARLA's y points south here
    assert g.latitude < 0 and g.latitude == pytest.approx(-math.degrees(1000 / R), rel=1e-6)
    # Another reference: the origin is the reference, east scales with cos(latitude).
    text = open(os.path.join(CARLA_MAPS, 'Town02.xodr')).read().replace('+lat_0=0 +lon_0=0', '+lat_0=49 +lon_0=8.4')
    assert '+lat_0=49' in text
    path = tmp_path / 'Geo.xodr'
    path.write_text(text)
    g0 = load(str(path)).transform_to_geolocation(carla.Location(0, 0, 0))
    assert (g0.latitude, g0.longitude) == pytest.approx((49, 8.4), abs=1e-9)
    g1 = load(str(path)).transform_to_geolocation(carla.Location(100, 0, 0))
    assert g1.longitude - 8.4 == pytest.approx(math.degrees(100 / (R * math.cos(math.radians(49)))), rel=1e-9)


def test_all_landmarks_are_the_signals_and_their_references(carla_town):
    m, root = carla_town
    signals = {s.get('id'): s for s in root.iter('signal')}
    refs = list(root.iter('signalReference'))
    landmarks = m.get_all_landmarks()
    assert len(landmarks) == len(signals) + len(refs) > 0
    for l in landmarks:
        sig = signals[l.id]
        assert l.type == sig.get('type') and l.name == sig.get('name')
        assert l.is_dynamic == (sig.get('dynamic') == 'yes')
        assert l.waypoint is None
    # Each signal on its own road, at its s, as in the file.
    for road in root.findall('road'):
        for sig in road.iter('signal'):
            assert any(l.id == sig.get('id') and l.road_id == int(road.get('id')) and
                       abs(l.s - float(sig.get('s'))) < 1e-9 for l in landmarks)
    sid = next(iter(signals))
    by_id = m.get_all_landmarks_from_id(sid)
    assert by_id and all(l.id == sid for l in by_id)
    assert len(by_id) == 1 + sum(r.get('id') == sid for r in refs)
    assert len(m.get_all_landmarks_of_type('1000001')) == sum(l.type == '1000001' for l in landmarks)


def test_landmark_groups_are_the_controllers(carla_town):
    m, root = carla_town
    controllers = [c for c in root.findall('controller')]
    assert controllers
    ids = [cs.get('signalId') for cs in controllers[0].findall('control')]
    l = m.get_all_landmarks_from_id(ids[0])[0]
    group = m.get_landmark_group(l)
    assert {g.id for g in group} == set(ids)


def test_waypoint_landmarks_find_the_light_ahead(carla_town):
    m, _ = carla_town
    infos = m._native.traffic_light_infos()
    assert infos
    for info in infos:
        stop = carla.Waypoint(info['stop_waypoints'][0], m)
        before = stop.previous(8.0)
        assert before, info['signal_id']
        found = before[0].get_landmarks(20.0)
        ids = [l.id for l in found]
        assert info['signal_id'] in ids, (info['signal_id'], ids)
        l = found[ids.index(info['signal_id'])]
        assert 0 <= l.distance <= 20.0 and l.waypoint is not None
        assert [x.distance for x in found] == sorted(x.distance for x in found)
        assert all(x.type == '1000001' for x in before[0].get_landmarks_of_type(12.0, '1000001'))


def test_junctions(carla_town):
    m, root = carla_town
    junction_ids = {int(j.get('id')) for j in root.findall('junction')}
    seen = set()
    for wp in m.generate_waypoints(4.0):
        j = wp.get_junction()
        if not wp.is_junction:
            assert j is None
            continue
        assert isinstance(j, carla.Junction) and j.id == wp.junction_id
        seen.add(j.id)
        b = j.bounding_box
        loc = wp.transform.location
        assert abs(loc.x - b.location.x) <= b.extent.x + 1e-6 and abs(loc.y - b.location.y) <= b.extent.y + 1e-6
    assert seen == junction_ids
    wp = next(w for w in m.generate_waypoints(4.0) if w.is_junction)
    pairs = wp.get_junction().get_waypoints(carla.LaneType.Driving)
    assert pairs and all(a.junction_id == wp.junction_id and b.junction_id == wp.junction_id for a, b in pairs)


def test_road_ids_are_the_opendrive_ids(carla_town):
    m, root = carla_town
    lengths = {int(r.get('id')): float(r.get('length')) for r in root.findall('road')}
    for wp in m.generate_waypoints(20.0)[:200]:
        assert wp.road_id in lengths
        if wp.s >= lengths[wp.road_id]:  # a lane driving against s starts at s = length: CARLA has no waypoint there
            assert m.get_waypoint_xodr(wp.road_id, wp.lane_id, wp.s) is None
            continue
        same = m.get_waypoint_xodr(wp.road_id, wp.lane_id, wp.s)
        assert same is not None and same.road_id == wp.road_id and same.lane_id == wp.lane_id
        assert same.transform.location.distance(wp.transform.location) < 0.01
    assert m.get_waypoint_xodr(999999, -1, 0.0) is None


def test_crosswalks():
    m, _ = town('Town01')
    assert m.get_crosswalks() == []  # Town01's file has no crosswalk objects (CARLA's answer too)
    path = os.path.join(GENERATED, 'LockstepTown1.xodr')
    if not os.path.exists(path):
        pytest.skip('generated town not built')
    walks = load(path).get_crosswalks()
    assert len(walks) >= 4 and all(isinstance(p, carla.Location) for p in walks)
    # Closed polygons one after another: the first corner comes back.
    assert any(p.distance(walks[0]) < 1e-9 for p in walks[1:])
