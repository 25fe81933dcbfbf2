"""CARLA's world-level calls that generate_traffic.py makes, against a running simulation:
set_pedestrians_cross_factor (the coordinator checks 0..1), set_pedestrians_seed (seeds
get_random_location_from_navigation), TrafficLight.reset_group and
World.reset_all_traffic_lights (the group's first light green, the others red, from 0 s)."""
import math

import pytest

import carla
import lockstep

from conftest import has_service

pytestmark = pytest.mark.skipif(not has_service('ground_sim'), reason='needs the ground_sim service')


def _groups(world):
    """{group: [light states by id]} as ground_sim reports them."""
    out = {}
    for l in sorted(world._client.traffic_lights(), key=lambda l: l['id']):
        out.setdefault(l['group'], []).append(l)
    return out


def _at_cycle_start(lights, dt):
    return (lights[0]['state'] == 'green' and all(l['state'] == 'red' for l in lights[1:])
            and all(l['elapsed'] <= 1.5 * dt for l in lights))


def test_pedestrians_cross_factor_is_accepted_in_range_and_refused_outside(world):
    world.set_pedestrians_cross_factor(0.0)
    world.set_pedestrians_cross_factor(1.0)
    world.set_pedestrians_cross_factor(0.25)
    world.tick()
    for bad in (1.5, -0.1, float('nan')):
        with pytest.raises(lockstep.CommandRejected) as e:
            world.set_pedestrians_cross_factor(bad)
        assert 'pedestrians cross factor' in e.value.reason
        assert ('NaN' in e.value.reason) if math.isnan(bad) else ('outside [0, 1]' in e.value.reason)


def test_pedestrians_seed_repeats_the_random_navigation_locations(world):
    def draw(seed):
        world.set_pedestrians_seed(seed)
        return [(p.x, p.y, p.z) for p in (world.get_random_location_from_navigation() for _ in range(8))]
    first = draw(7)
    assert first == draw(7)
    assert first != draw(8)


def test_reset_group_and_reset_all_put_the_lights_back_to_the_cycle_start(world):
    dt = world.get_settings().fixed_delta_seconds
    groups = [g for g in _groups(world).values() if len(g) >= 2]
    if len(groups) < 2:
        pytest.skip('the town has fewer than two signalled junctions')
    a, b = groups[0], groups[1]
    # Both groups away from the start: their last light green.
    world.get_actor(a[-1]['id']).set_state(carla.TrafficLightState.Green)
    world.get_actor(b[-1]['id']).set_state(carla.TrafficLightState.Green)
    for _ in range(3):
        world.tick()
    now = _groups(world)
    assert now[a[0]['group']][-1]['state'] == 'green' and now[b[0]['group']][-1]['state'] == 'green'
    world.get_actor(a[0]['id']).reset_group()
    world.tick()
    now = _groups(world)
    assert _at_cycle_start(now[a[0]['group']], dt), now[a[0]['group']]
    assert not _at_cycle_start(now[b[0]['group']], dt)  # the other group runs on
    world.reset_all_traffic_lights()
    world.tick()
    for g, lights in _groups(world).items():
        assert _at_cycle_start(lights, dt), (g, lights)


def test_pedestrians_seed_reaches_the_walker_ai(sim):
    """set_pedestrians_seed reaches ground_sim's AI controllers: in a reloaded world, the same
    walkers started at the same sidewalk points walk the same way with the same seed, and
    another way with another seed (their first choice of direction is drawn)."""
    client = carla.Client('localhost', 2000)
    client.set_timeout(30)

    def walk(seed):
        world = client.reload_world(False)  # keep synchronous mode (CARLA resets to asynchronous by default)
        world.set_pedestrians_seed(seed)
        carla_map = world.get_map()
        library = world.get_blueprint_library()
        walkers = []
        for sp in carla_map.get_spawn_points()[:6:2]:
            wp = carla_map.get_waypoint(sp.location, project_to_road=True, lane_type=carla.LaneType.Sidewalk)
            walker = world.try_spawn_actor(library.find('walker.pedestrian.0001'),
                                           carla.Transform(wp.transform.location + carla.Location(z=1.0)))
            assert walker is not None
            walkers.append(walker)
        world.tick()
        controllers = [world.spawn_actor(library.find('controller.ai.walker'), carla.Transform(), attach_to=w)
                       for w in walkers]
        world.tick()
        for c in controllers:
            c.start()
            c.set_max_speed(1.4)
        path = []
        for k in range(200):
            world.tick()
            if k % 20 == 19:
                path.append([(round(w.get_location().x, 3), round(w.get_location().y, 3)) for w in walkers])
        return path

    first = walk(7)
    assert first[0] != first[-1], 'the walkers did not walk'
    assert walk(7) == first
    assert walk(8) != first
