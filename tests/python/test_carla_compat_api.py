"""Issue 19: the carla API surface CARLA's own example scripts use, as CARLA's bindings do it:
the geom operators and constructors, destroy() of an actor already gone, recommended values,
steps above 1 s, the physics control right after spawn, Map.to_opendrive, the blueprints and
attributes of CARLA 0.9.15 / 0.9.16, snapshots, world.tick() asynchronous, reload_world's
reset_settings, the geolocation calls, the vehicle reference point, and component / bone
queries with a fixed walker skeleton."""
import math

import pytest

import carla
import lockstep

from conftest import has_service

ground = pytest.mark.skipif(not has_service('ground_sim'), reason='needs the ground_sim service')


def _close(a, b, tol=1e-9):
    return abs(a.x - b.x) <= tol and abs(a.y - b.y) <= tol and abs(a.z - b.z) <= tol


# --- geometry (no simulation) --------------------------------------------------------------

def test_location_from_a_vector_and_back():
    v = carla.Vector3D(1, -2, 3)
    loc = carla.Location(v)  # BasicAgent: carla.Location(forward_vector * distance)
    assert type(loc) is carla.Location and (loc.x, loc.y, loc.z) == (1, -2, 3)
    assert carla.Vector3D(loc) == v and carla.Location(x=1, z=3) == carla.Location(1, 0, 3)
    fwd = carla.Transform(carla.Location(), carla.Rotation(yaw=90)).get_forward_vector()
    ahead = carla.Location(fwd * 2.0)
    assert ahead.x == pytest.approx(0.0, abs=1e-12) and ahead.y == pytest.approx(2.0)


def test_vector_operators_follow_libcarla():
    a, b = carla.Location(1, 2, 3), carla.Location(4, 6, 3)
    assert type(a - b) is carla.Vector3D and a - b == carla.Vector3D(-3, -4, 0)
    assert 2 * a == a * 2 == carla.Vector3D(2, 4, 6)
    assert a / 2 == carla.Vector3D(0.5, 1, 1.5)
    assert 2 / carla.Vector3D(2, 4, 8) == carla.Vector3D(1, 2, 4)  # LibCarla: k / v divides v by k
    assert abs(carla.Location(-1, 2, -3)) == carla.Location(1, 2, 3)
    c = carla.Location(1, 1, 1)
    same = c
    c += carla.Vector3D(1, 0, 0)
    c *= 2
    assert c is same and c == carla.Location(4, 2, 2)
    assert a != b and not (a != carla.Location(1, 2, 3))
    assert a.distance_squared_2d(b) == 25 and a.distance_2d(b) == 5 and a.distance_squared(b) == 25
    assert a.squared_length() == 14 and carla.Vector3D(3, 4, 0).length() == 5
    assert carla.Vector3D(1, 0, 0).cross(carla.Vector3D(0, 1, 0)) == carla.Vector3D(0, 0, 1)
    assert a.dot(b) == 25 and a.dot_2d(b) == 16
    assert carla.Vector3D(1, 0, 0).get_vector_angle(carla.Vector3D(0, 2, 0)) == pytest.approx(math.pi / 2)
    assert carla.Vector3D(0, 3, 4).make_unit_vector() == carla.Vector3D(0, 0.6, 0.8)


def test_vector2d_operators():
    v = carla.Vector2D(3, 4)
    assert v.length() == 5 and v.squared_length() == 25 and v.make_unit_vector() == carla.Vector2D(0.6, 0.8)
    assert v + carla.Vector2D(1, 1) == carla.Vector2D(4, 5) and v - v == carla.Vector2D()
    assert v * 2 == 2 * v == carla.Vector2D(6, 8) and v / 2 == carla.Vector2D(1.5, 2)
    w = v
    w += carla.Vector2D(1, 0)
    assert w is v and v == carla.Vector2D(4, 4) and v != carla.Vector2D(4, 5)


def test_transforms_change_points_in_place_as_carla():
    t = carla.Transform(carla.Location(10, 0, 0), carla.Rotation(yaw=90))
    p = carla.Location(1, 0, 0)
    out = t.transform(p)
    assert out is p and _close(p, carla.Location(10, 1, 0), 1e-12)
    v = carla.Vector3D(1, 0, 0)
    assert t.transform_vector(v) is v and _close(v, carla.Vector3D(0, 1, 0), 1e-12)
    q = t.inverse_transform(carla.Location(10, 1, 0))
    assert _close(q, carla.Location(1, 0, 0), 1e-12)
    pts = [carla.Location(1, 0, 0), carla.Location(0, 1, 0)]
    assert t.transform(pts) is None and _close(pts[1], carla.Location(9, 0, 0), 1e-12)
    assert t == carla.Transform(carla.Location(10, 0, 0), carla.Rotation(yaw=90)) and t != carla.Transform()
    assert carla.Rotation(1, 2, 3) != carla.Rotation(1, 2, 4)


def test_bounding_box_rotation_and_equality():
    box = carla.BoundingBox(carla.Location(0, 0, 1), carla.Vector3D(2, 1, 1), carla.Rotation(yaw=90))
    v = box.get_local_vertices()
    assert len(v) == 8 and _close(v[0], carla.Location(1, -2, 0), 1e-12)  # (-x, -y, -z) turned 90 deg
    assert box.contains(carla.Location(0, 0, 1), carla.Transform())
    assert box == carla.BoundingBox(carla.Location(0, 0, 1), carla.Vector3D(2, 1, 1), carla.Rotation(yaw=90))
    assert box != carla.BoundingBox(carla.Location(0, 0, 1), carla.Vector3D(2, 1, 1))
    assert carla.GeoLocation(1, 2, 3) == carla.GeoLocation(1, 2, 3) != carla.GeoLocation(1, 2, 4)
    assert carla.GeoEllipsoid().a == 6378137.0


def test_settings_steps_above_one_second_and_none_for_zero():
    s = carla.WorldSettings(synchronous_mode=True, fixed_delta_seconds=3.0)
    assert s._to_wire()['fixed_delta_seconds'] == 3.0
    assert 'fixed_delta_seconds' not in carla.WorldSettings(fixed_delta_seconds=0.0)._to_wire()  # CARLA: <= 0 is None


def test_lockstep_attributes_are_hidden_from_carla_blueprints():
    decl = {'id': 'vehicle.x.y', 'tags': '', 'kind': 'vehicle', 'half_extents': (2, 1, 0.7),
            'attributes': [{'id': 'color', 'type': 'rgb', 'default': '1,2,3', 'min': 0, 'max': 0,
                            'recommended_values': ['1,2,3'], 'restricted': False, 'modifiable': True},
                           {'id': '_physics.body', 'type': 'string', 'default': '1500 0.3 0 0 -0.2', 'min': 0,
                            'max': 0, 'recommended_values': [], 'restricted': False, 'modifiable': False}]}
    bp = carla.ActorBlueprint(decl)
    assert [a.id for a in bp] == ['color'] and not bp.has_attribute('_physics.body')


def test_walker_pose_types_exist():
    control = carla.WalkerBoneControlIn([('crl_hand__R', carla.Transform(carla.Location(0.1, 0, 0)))])
    assert control.bone_transforms[0].bone_name == 'crl_hand__R'
    assert carla.OpendriveGenerationParameters(vertex_distance=1.0).vertex_distance == 1.0
    assert issubclass(carla.TrafficLight, carla.TrafficSign)


def test_traffic_manager_calls_of_carla_exist():
    # Implemented (python.traffic_manager runs them against ground_sim): not the fallback.
    for name in ('vehicle_lane_offset', 'global_lane_offset', 'collision_detection',
                 'set_boundaries_respawn_dormant_vehicles'):
        assert name in carla.TrafficManager.__dict__
        assert 'Not supported' not in (getattr(carla.TrafficManager, name).__doc__ or '')
    sensor = carla.Sensor.__new__(carla.Sensor)
    sensor.enable_gbuffers(True)  # tutorial_gbuffer.py: implemented (gbuffer.py, python.carla_conventions)
    # A fallback never replaces an implementation.
    from lockstep.carla.errors import add_unsupported

    class Implemented:
        def call(self):
            return 1
    add_unsupported(Implemented, {'call': 'no', 'other': 'no'})
    assert Implemented().call() == 1
    with pytest.raises(carla.LockstepUnsupported):
        Implemented().other()


# --- against a simulation ------------------------------------------------------------------

def _free_spawn(world, bp, start=3):
    for p in world.get_map().get_spawn_points()[start::5]:
        a = world.try_spawn_actor(bp, p)
        if a is not None:
            return a, p
    raise AssertionError('no free spawn point')


def test_fixed_delta_seconds_above_one_second_is_accepted(world):
    s = world.get_settings()
    old = s.fixed_delta_seconds
    s.fixed_delta_seconds = 3.0  # lidar_to_camera.py
    world.apply_settings(s)
    try:
        assert world.get_settings().fixed_delta_seconds == 3.0
        frame = world.tick()
        snap = world.get_snapshot()
        assert snap.frame == frame and snap.timestamp.delta_seconds == 3.0
    finally:
        s.fixed_delta_seconds = old
        world.apply_settings(s)


def test_recommended_values_list_the_default_where_carla_does(world):
    lib = world.get_blueprint_library()
    for bp in lib:
        for a in bp:
            if a.is_modifiable:
                assert a.recommended_values, (bp.id, a.id)
                assert a.as_str() in a.recommended_values or a.id in ('color', 'driver_id', 'role_name'), (bp.id, a.id)
    if has_service('sensors'):
        lidar = lib.find('sensor.lidar.ray_cast')
        assert lidar.get_attribute('dropoff_general_rate').recommended_values[0] == '0.45'
        lidar.set_attribute('dropoff_general_rate', lidar.get_attribute('dropoff_general_rate').recommended_values[0])


@ground
def test_carlas_catalogue_and_walker_attributes(world):
    lib = world.get_blueprint_library()
    for bp_id in ('vehicle.carlamotors.european_hgv', 'vehicle.dodge.charger_police', 'vehicle.mercedes.coupe',
                  'vehicle.micro.microlino', 'vehicle.mini.cooper_s', 'vehicle.nissan.patrol',
                  'vehicle.dodge.charger_police_2020', 'vehicle.mercedes.coupe_2020', 'vehicle.mini.cooper_s_2021',
                  'vehicle.nissan.patrol_2021', 'vehicle.sixwheeltruck.sixwheeltruck'):
        lib.find(bp_id)
    w = lib.filter('walker.pedestrian.*')[0]
    assert w.has_attribute('can_use_wheelchair')
    w.set_attribute('use_wheelchair', 'true')  # generate_traffic.py
    speeds = w.get_attribute('speed').recommended_values
    assert len(speeds) == 3 and float(speeds[0]) == 0 and 0 < float(speeds[1]) < float(speeds[2])


@pytest.mark.skipif(not has_service('render'), reason='needs the render service')
def test_camera_post_process_attributes(world):
    cam = world.get_blueprint_library().find('sensor.camera.rgb')
    for name, default in (('bloom_intensity', 0.675), ('lens_flare_intensity', 0.1), ('focal_distance', 1000.0),
                          ('blur_amount', 1.0), ('blur_radius', 0.0), ('fstop', 1.4), ('min_fstop', 1.2),
                          ('slope', 0.88), ('toe', 0.55), ('shoulder', 0.26), ('black_clip', 0.0),
                          ('white_clip', 0.04), ('temp', 6500.0), ('tint', 0.0),
                          ('chromatic_aberration_intensity', 0.0), ('chromatic_aberration_offset', 0.0)):
        assert cam.get_attribute(name).as_float() == pytest.approx(default), name
    assert cam.get_attribute('blade_count').as_int() == 5
    cam.set_attribute('bloom_intensity', '0.5')
    sensor = world.spawn_actor(cam, carla.Transform(carla.Location(0, 0, 30)))
    world.tick()
    assert sensor.destroy()


@ground
def test_physics_control_answers_right_after_spawn(world):
    bp = world.get_blueprint_library().find('vehicle.tesla.model3')
    car, _ = _free_spawn(world, bp)
    try:
        before = car.get_physics_control()  # vehicle_physics.py: no tick yet
        world.tick()
        world.tick()
        after = car.get_physics_control()
        assert before.mass == after.mass and before.max_rpm == after.max_rpm
        assert [(g.ratio, g.up_ratio) for g in before.forward_gears] == [(g.ratio, g.up_ratio) for g in after.forward_gears]
        assert [(v.x, v.y) for v in before.torque_curve] == [(v.x, v.y) for v in after.torque_curve]
        assert before.wheels[0].radius == after.wheels[0].radius
        assert before.wheels[0].max_steer_angle == pytest.approx(after.wheels[0].max_steer_angle)
    finally:
        car.destroy()


@ground
def test_destroy_of_an_actor_already_gone_warns_and_returns_false(world, capfd):
    bp = world.get_blueprint_library().find('vehicle.audi.tt')
    car, _ = _free_spawn(world, bp)
    world.tick()
    assert car.destroy() is True
    world.tick()
    capfd.readouterr()
    assert car.destroy() is False  # a second destroy
    err = capfd.readouterr().err
    assert 'WARNING: attempting to destroy an actor that is already dead: Actor %d (vehicle.audi.tt)' % car.id in err


@ground
def test_destroying_a_parent_leaves_its_sensor_detached_where_it_was(world):
    # CARLA destroys only the actor (UActorDispatcher::DestroyActor); Unreal detaches what was
    # attached to it keeping its world transform: the sensor lives on, standing there.
    lib = world.get_blueprint_library()
    gnss = lib.filter('sensor.other.gnss')
    if not len(gnss):
        pytest.skip('no GNSS blueprint')
    car, _ = _free_spawn(world, lib.find('vehicle.audi.tt'))
    sensor = world.spawn_actor(gnss[0], carla.Transform(carla.Location(x=1.0, z=2.0)), attach_to=car)
    got = []
    sensor.listen(got.append)
    try:
        for _ in range(10):
            world.tick()
        assert got and got[-1].transform.location.distance(sensor.get_transform().location) < 0.01
        before = sensor.get_transform()
        assert car.destroy() is True
        for _ in range(3):
            world.tick()
        assert sensor.is_alive and sensor.parent is None
        assert sensor.get_transform().location.distance(before.location) < 0.01
        n = len(got)
        world.tick()
        world.tick()
        assert len(got) > n  # it samples on, where it stood
        assert got[-1].transform.location.distance(before.location) < 0.01
    finally:
        sensor.stop()
    assert sensor.destroy() is True  # on its own


@ground
def test_destroy_frees_the_place_at_once_while_free_running(world):
    """vehicle_gallery.py: destroy, then spawn the next car at the same place."""
    bp = world.get_blueprint_library().find('vehicle.audi.tt')
    car, spawn = _free_spawn(world, bp, start=9)
    for _ in range(5):
        world.tick()
    s = world.get_settings()
    s.synchronous_mode = False
    world.apply_settings(s)
    try:
        world.wait_for_tick()
        world.wait_for_tick()
        assert car.destroy()
        again = world.spawn_actor(bp, spawn)  # CommandRejected (collision with the destroyed car) before
        assert again.destroy()
    finally:
        s.synchronous_mode = True
        world.apply_settings(s)


@ground
def test_constant_velocity_is_kept_in_the_vehicles_frame(world):
    car, _ = _free_spawn(world, world.get_blueprint_library().find('vehicle.tesla.model3'), start=8)
    try:
        for _ in range(20):
            world.tick()
        car.enable_constant_velocity(carla.Vector3D(4.0, 0, 0))  # constant_velocity_agent.py
        for _ in range(40):
            world.tick()
        v, fwd = car.get_velocity(), car.get_transform().get_forward_vector()
        assert v.dot(fwd) == pytest.approx(4.0, abs=0.3)
        car.disable_constant_velocity()
        car.apply_control(carla.VehicleControl(brake=1.0))
        for _ in range(60):
            world.tick()
        assert car.get_velocity().length() < 0.5
    finally:
        car.destroy()


@ground
def test_semantic_tags_attributes_and_snapshot_fields(world):
    lib = world.get_blueprint_library()
    car, _ = _free_spawn(world, lib.find('vehicle.carlamotors.carlacola'))
    walker = world.spawn_actor(lib.filter('walker.pedestrian.*')[0],
                               carla.Transform(world.get_random_location_from_navigation() + carla.Location(z=1)))
    try:
        world.tick()
        assert car.semantic_tags == [15] and walker.semantic_tags == [12]  # Truck, Pedestrian
        assert car.attributes['base_type'] == 'truck' and car.attributes['number_of_wheels'] == '4'
        assert not any(k.startswith('_') for k in car.attributes)
        snap = world.get_snapshot()
        assert snap.frame_count == snap.frame == snap.timestamp.frame
        assert snap.elapsed_seconds == snap.timestamp.elapsed_seconds and snap.delta_seconds == 0.05
        assert snap.platform_timestamp == snap.timestamp.platform_timestamp
        assert snap.timestamp.frame_count == snap.frame
    finally:
        car.destroy()
        walker.destroy()


@ground
def test_vehicle_origin_is_the_base_of_its_box(world):
    bp = world.get_blueprint_library().find('vehicle.lincoln.mkz_2020')
    car, spawn = _free_spawn(world, bp, start=4)
    try:
        half_z = bp._decl['half_extents'][2]
        # Right after spawn, before any state: the spawn transform is CARLA's origin.
        assert car.get_transform().location.distance(spawn.location) < 1e-6
        for _ in range(30):
            world.tick()
        t = car.get_transform()
        box = car.bounding_box
        assert box.location.z == pytest.approx(half_z) and box.extent.z == pytest.approx(half_z)
        centre = lockstep.carla.geometry.from_wire_pose(car._wire_pose())  # the box centre on the wire
        assert centre.location.distance(t.transform(carla.Location(box.location))) < 1e-9
        # Standing on the road, its origin is near the road surface, not half a box above it.
        road = world.get_map().get_waypoint(t.location).transform.location
        assert abs(t.location.z - road.z) < 0.25
        snap = world.get_snapshot()
        assert snap.find(car.id).get_transform() == t  # the same frame, the same transform
        # set_transform puts the origin where asked (physics off: nothing moves it).
        car.set_simulate_physics(False)
        target = carla.Transform(t.location + carla.Location(x=2.0), t.rotation)
        car.set_transform(target)
        world.tick()
        world.tick()
        assert car.get_transform().location.distance(target.location) < 1e-3
    finally:
        car.destroy()


@ground
def test_component_and_bone_queries(world):
    lib = world.get_blueprint_library()
    audi, _ = _free_spawn(world, lib.find('vehicle.audi.tt'), start=6)
    ped = world.spawn_actor(lib.filter('walker.pedestrian.*')[1],
                            carla.Transform(world.get_random_location_from_navigation() + carla.Location(z=1)))
    try:
        world.tick()
        t = audi.get_transform()
        c = audi.get_component_world_transform('front-blinker-r-1')  # get_component_test.py
        local = t.inverse_transform(carla.Location(c.location))
        ext = audi.bounding_box.extent
        assert local.x == pytest.approx(ext.x) and local.y > 0  # front, right
        assert 'front-blinker-r-1' in audi.get_component_names()
        with pytest.raises(RuntimeError, match='no component'):
            audi.get_component_world_transform('no-such-component')
        assert audi.get_bone_names()[0] == 'Root' and len(audi.get_bone_world_transforms()) == 5
        bones = ped.get_bones()  # draw_skeleton.py
        names = [b.name for b in bones.bone_transforms]
        assert names[0] == 'crl_root' and {'crl_Head__C', 'crl_hand__L', 'crl_toeEnd__R'} <= set(names)
        by = {b.name: b for b in bones.bone_transforms}
        pt = ped.get_transform()
        height = float(ped.attributes['height'])
        head = pt.inverse_transform(carla.Location(by['crl_Head__C'].world.location))
        foot = pt.inverse_transform(carla.Location(by['crl_foot__L'].world.location))
        assert head.z > foot.z + 0.6 * height and foot.y < 0  # upright; left is -y in CARLA
        # A custom pose blends in: blend_pose(1) shows it, hide_pose the skeleton's own.
        ped.set_bones(carla.WalkerBoneControlIn([('crl_hand__R', carla.Transform(carla.Location(0, 0, 0.5)))]))
        ped.blend_pose(1.0)
        raised = {b.name: b for b in ped.get_bones().bone_transforms}['crl_hand__R'].component.location
        ped.hide_pose()
        down = {b.name: b for b in ped.get_bones().bone_transforms}['crl_hand__R'].component.location
        assert raised.z > down.z + 0.3
        with pytest.raises(RuntimeError, match='no bone'):
            ped.set_bones(carla.WalkerBoneControlIn([('tail', carla.Transform())]))
    finally:
        audi.destroy()
        ped.destroy()


def test_map_to_opendrive_and_geolocation(world):
    m = world.get_map()
    text = m.to_opendrive()
    assert '<OpenDRIVE' in text and carla.Map('copy', text).get_topology()
    wp = m.get_waypoint(m.get_spawn_points()[0].location)
    assert wp.is_intersection == wp.is_junction
    loc = carla.Location(120.5, -33.25, 2.0)
    geo = m.transform_to_geolocation(loc)
    back = m.geolocation_to_transform(geo)
    assert back.distance(loc) < 1e-6
    origin = m.get_geo_reference()
    assert isinstance(origin, carla.GeoLocation) and m.transform_to_geolocation(carla.Location()).latitude == \
        pytest.approx(origin.latitude)


def test_ground_projection_finds_the_road_below(world):
    spawn = world.get_map().get_spawn_points()[0]
    road = world.get_map().get_waypoint(spawn.location).transform.location
    above = carla.Location(spawn.location.x, spawn.location.y, road.z + 2.0)
    hit = world.ground_projection(above, 5.0)  # automatic_control.py --agent Constant
    assert isinstance(hit, carla.LabelledPoint) and hit.label == carla.CityObjectLabel.Roads
    assert hit.location.z == pytest.approx(road.z, abs=0.05) and hit.location.x == above.x
    assert world.ground_projection(above, 1.0) is None  # too far below
    any_lane = world.get_map().get_waypoint(spawn.location, lane_type=carla.LaneType.Any)  # raised TypeError
    assert any_lane is not None and any_lane.lane_type == carla.LaneType.Driving


def test_tick_while_asynchronous_returns_the_next_frame(world):
    s = world.get_settings()
    assert s.synchronous_mode
    s.synchronous_mode = False
    world.apply_settings(s)
    try:
        frame = world.tick()  # CARLA: no raise, the next frame
        assert frame >= 1 and world.get_snapshot().frame >= frame
    finally:
        s.synchronous_mode = True
        world.apply_settings(s)


def test_reload_world_resets_or_keeps_the_settings(world):
    """Last: a reload ends every actor of the run."""
    client = carla.Client('localhost', 2000)
    client.set_timeout(30)
    assert world.get_settings().synchronous_mode
    client.reload_world(False)  # keeps them
    assert world.get_settings().synchronous_mode
    client.reload_world()  # CARLA's default: reset to its default settings (asynchronous)
    try:
        assert not world.get_settings().synchronous_mode
    finally:
        s = world.get_settings()
        s.synchronous_mode = True
        world.apply_settings(s)
