"""carla.TrafficManager's lane offsets, collision_detection and respawn boundaries against a
running ground_sim: each call changes what ground_sim's Traffic Manager does (before, they
raised LockstepUnsupported, and ground_sim ignored the commands)."""
import pytest

import carla
import lockstep

from conftest import Simulation, has_service

pytestmark = pytest.mark.skipif(not has_service('ground_sim'), reason='needs the ground_sim service')


@pytest.fixture(scope='module')
def sim():
    s = Simulation([('air_sim', 'air_sim', False), ('ground_sim', 'ground_sim', False)])
    yield s
    s.stop()


def _ticks(world, n):
    for _ in range(n):
        world.tick()


def _straight_start(world, ahead):
    """A spawn point whose lane runs on, outside junctions, `ahead` m and more."""
    m = world.get_map()
    for p in m.get_spawn_points():
        wp = m.get_waypoint(p.location)
        steps = [wp]
        ok = True
        for _ in range(int(ahead / 5) + 8):
            nxt = steps[-1].next(5.0)
            if len(nxt) != 1 or nxt[0].is_junction or nxt[0].road_id != wp.road_id or nxt[0].lane_id != wp.lane_id:
                ok = False
                break
            steps.append(nxt[0])
        if ok:
            return p, steps
    pytest.skip('no straight lane in the town')


def _lateral(world, actor):
    """m right of its lane's centre (CARLA's right vector)."""
    loc = actor.get_location()
    wp = world.get_map().get_waypoint(loc)
    d = loc - wp.transform.location
    r = wp.transform.get_right_vector()
    return d.x * r.x + d.y * r.y


def _spawn(world, transform):
    bp = world.get_blueprint_library().find('vehicle.audi.tt')
    actor = world.try_spawn_actor(bp, transform)
    assert actor is not None
    return actor


def test_lane_offsets_move_the_car_right_of_the_lane_centre(world):
    tm = world._carla_client.get_trafficmanager()
    start, _ = _straight_start(world, 60.0)
    car = _spawn(world, start)
    try:
        _ticks(world, 10)
        tm.global_lane_offset(0.8)
        car.set_autopilot(True)
        _ticks(world, 90)
        assert _lateral(world, car) == pytest.approx(0.8, abs=0.25)
        tm.vehicle_lane_offset(car, -0.6)  # overrides the global offset
        _ticks(world, 60)
        assert _lateral(world, car) == pytest.approx(-0.6, abs=0.25)
    finally:
        tm.global_lane_offset(0.0)
        car.set_autopilot(False)
        car.destroy()
        world.tick()


def test_collision_detection_false_ignores_the_other_car(world):
    tm = world._carla_client.get_trafficmanager()
    start, lane = _straight_start(world, 60.0)
    ahead = lane[6].transform  # 30 m on
    ahead.location.z = start.location.z
    gaps = {}
    for detect in (True, False):
        car = _spawn(world, start)
        parked = _spawn(world, ahead)
        length = 2 * car.bounding_box.extent.x
        try:
            _ticks(world, 10)
            tm.collision_detection(car, parked, detect)
            car.set_autopilot(True)
            gap = 1e9
            for _ in range(200):
                world.tick()
                gap = min(gap, car.get_location().distance(parked.get_location()))
            gaps[detect] = gap
        finally:
            car.set_autopilot(False)
            car.destroy()
            parked.destroy()
            world.tick()
    assert gaps[True] > length + 1.5  # it stops behind (distance_to_leading_vehicle)
    assert gaps[False] < length + 0.3  # it drives into the car it ignores


def test_respawn_boundaries_are_taken(world):
    tm = world._carla_client.get_trafficmanager()
    tm.set_respawn_dormant_vehicles(True)
    tm.set_boundaries_respawn_dormant_vehicles(25.0, 700.0)
    tm.set_boundaries_respawn_dormant_vehicles(lower_bound=30.0)  # upper: actor_active_distance
    _ticks(world, 2)  # ground_sim applies them: no failure raised
    with pytest.raises(lockstep.CommandRejected, match='upper bound'):
        tm.set_boundaries_respawn_dormant_vehicles(100.0, 50.0)
    tm.set_respawn_dormant_vehicles(False)
