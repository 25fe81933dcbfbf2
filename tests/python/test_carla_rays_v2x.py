"""CARLA 0.9.12+'s World.cast_ray / project_point / ground_projection against the town's
meshes and the actors' boxes (answered in the client, as the LiDAR sees the world), and
CARLA 0.9.16's V2X sensors: CAMs between two cars (carla.CAMEvent, CARLA's dict) and
send() of sensor.other.v2x_custom."""
import queue

import pytest

import carla

from conftest import has_service

needs_ground = pytest.mark.skipif(not has_service('ground_sim'), reason='ground_sim is not built')
needs_sensors = pytest.mark.skipif(not (has_service('ground_sim') and has_service('sensors')),
                                   reason='ground_sim and the sensors service are not built')


@pytest.fixture(scope='module')
def world(sim):
    client = carla.Client('localhost', 2000)
    client.set_timeout(30)
    w = client.get_world()
    assert w.get_settings().synchronous_mode
    return w


def _car_blueprint(world):
    return world.get_blueprint_library().filter('vehicle.*')[0]


def _spawn_cars(world, n, within=80.0):
    """n cars on spawn points 12..within m from the first."""
    points = world.get_map().get_spawn_points()
    chosen = [points[0]]
    for sp in points[1:]:
        if len(chosen) >= n:
            break
        if 12.0 < sp.location.distance(points[0].location) < within and all(
                sp.location.distance(o.location) > 12.0 for o in chosen):
            chosen.append(sp)
    if len(chosen) < n:
        pytest.skip('the town has no %d spawn points close together' % n)
    cars = [world.spawn_actor(_car_blueprint(world), sp) for sp in chosen]
    for _ in range(3):
        world.tick()
    return cars


@needs_ground
def test_cast_ray_hits_a_spawned_car_then_the_road_below_it(world):
    car, = _spawn_cars(world, 1)
    try:
        t = car.get_transform()
        box = car.bounding_box
        roof = t.location.z + box.location.z + box.extent.z
        road = world.get_map().get_waypoint(t.location).transform.location.z
        top, bottom = carla.Location(t.location.x, t.location.y, roof + 10), carla.Location(t.location.x, t.location.y, road - 10)
        hits = world.cast_ray(top, bottom)
        assert [type(h) for h in hits] == [carla.LabelledPoint] * len(hits)
        assert len(hits) >= 2, hits
        assert hits[0].label == car.semantic_tags[0]  # the car's class (Car, Truck, ...)
        assert hits[0].location.z == pytest.approx(roof, abs=0.02)
        assert hits[0].location.x == pytest.approx(t.location.x, abs=1e-3)
        assert hits[0].location.y == pytest.approx(t.location.y, abs=1e-3)  # CARLA's y (right)
        assert hits[1].label == carla.CityObjectLabel.Roads
        assert hits[1].location.z == pytest.approx(road, abs=0.05)
        assert [h.location.z for h in hits] == sorted((h.location.z for h in hits), reverse=True)  # nearest first
        assert world.cast_ray(top, carla.Location(top.x, top.y, top.z + 50)) == []  # the sky: nothing

        # project_point: the first surface only; None beyond search_distance or with no direction.
        p = world.project_point(top, carla.Vector3D(0, 0, -1), 20.0)
        assert isinstance(p, carla.LabelledPoint) and p.label == hits[0].label
        assert p.location.z == pytest.approx(roof, abs=0.02)
        assert world.project_point(top, carla.Vector3D(0, 0, -1), 5.0) is None
        assert world.project_point(top, carla.Vector3D(0, 0, 0), 20.0) is None
        # ground_projection is project_point straight down (CARLA's World::GroundProjection).
        g = world.ground_projection(top, 20.0)
        assert g.label == p.label and g.location.z == pytest.approx(p.location.z, abs=1e-6)
    finally:
        car.destroy()
        world.tick()
    # The car is gone from the next frame's state: the ray reaches the road.
    hits = world.cast_ray(top, bottom)
    assert hits and hits[0].label == carla.CityObjectLabel.Roads


def _collect(sensor):
    q = queue.Queue()
    sensor.listen(q.put)
    return q


def _drain(q):
    out = []
    while True:
        try:
            out.append(q.get_nowait())
        except queue.Empty:
            return out


@needs_sensors
def test_two_cars_hear_each_others_cams(world):
    cars = _spawn_cars(world, 2)
    bp = world.get_blueprint_library().find('sensor.other.v2x')
    assert bp.get_attribute('path_loss_model').as_str() == 'winner'
    assert bp.get_attribute('scenario').recommended_values == ['highway', 'rural', 'urban']
    bp.set_attribute('path_loss_model', 'geometric')  # V2XDemo.py's choice
    sensors = [world.spawn_actor(bp, carla.Transform(), attach_to=c) for c in cars]
    queues = [_collect(s) for s in sensors]
    try:
        for _ in range(50):  # 2.5 s: parked cars send at gen_cam_max (1 s)
            world.tick()
        for me, other, q in ((0, 1, queues[0]), (1, 0, queues[1])):
            events = _drain(q)
            assert events, 'car %d heard no CAM' % me
            e = events[0]
            assert isinstance(e, carla.CAMEvent) and e.get_message_count() == len(e) >= 1
            m = e[0]
            assert isinstance(m, carla.CAMMessage) and -99.0 <= m.power <= 31.5
            d = m.get()
            assert d['Header'] == {'Protocol Version': 2, 'Message ID': 'CAM', 'Station ID': cars[other].id}
            params = d['Message']['CAM Parameters']
            assert params['High Frequency Container']['High Frequency Container Present'] == \
                'Basic Vehicle Container High Frequency'
            hf = params['High Frequency Container']['Basic Vehicle Container High Frequency']
            assert hf['Speed']['Value'] < 50  # parked: below 0.5 m/s
            yaw = cars[other].get_transform().rotation.yaw  # CARLA: clockwise from east; heading from north
            diff = (hf['Heading']['Value'] - (yaw + 90.0) * 10) % 3600
            assert min(diff, 3600 - diff) <= 15, (hf['Heading'], yaw)
            assert str(m).startswith('CAMData(power=')
    finally:
        for s in sensors:
            s.stop()
            s.destroy()
        for c in cars:
            c.destroy()
        world.tick()


@needs_sensors
def test_custom_v2x_send_reaches_the_other_custom_sensor_once(world):
    cars = _spawn_cars(world, 2)
    bp = world.get_blueprint_library().find('sensor.other.v2x_custom')
    a, b = (world.spawn_actor(bp, carla.Transform(), attach_to=c) for c in cars)
    cam = world.spawn_actor(world.get_blueprint_library().find('sensor.other.v2x'), carla.Transform(), attach_to=cars[1])
    qb = _collect(b)
    try:
        world.tick()
        a.send('hello from a')
        for _ in range(5):
            world.tick()
        events = _drain(qb)
        assert len(events) == 1 and isinstance(events[0], carla.CustomV2XEvent)
        msg = events[0][0]
        assert isinstance(msg, carla.CustomV2XData)
        assert msg.get() == {'Header': {'Protocol Version': 2, 'Message ID': 'CUSTOM', 'Station ID': cars[0].id},
                             'Message': 'hello from a'}
        with pytest.raises(RuntimeError, match='not a sensor.other.v2x_custom'):
            cam.send('a CAM sensor takes no text')  # CARLA: actor type mismatch
    finally:
        b.stop()
        for s in (a, b, cam):
            s.destroy()
        for c in cars:
            c.destroy()
        world.tick()
