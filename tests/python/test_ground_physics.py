"""carla calls that ground_sim applies, against a running simulation: Ackermann control,
set_simulate_physics, add_impulse / add_force, set_target_velocity, get/apply_physics_control,
vehicle lights, controller.ai.walker, the Traffic Manager's per-vehicle calls, the batch
commands, and traffic lights found through landmarks. Each call must change what ground_sim
simulates, and a bad value must raise with the service's reason."""
import math

import pytest

import carla
import lockstep

from conftest import has_service

pytestmark = pytest.mark.skipif(not has_service('ground_sim'), reason='needs the ground_sim service')


def _speed(actor):
    return actor.get_velocity().length()


def _ticks(world, n):
    for _ in range(n):
        world.tick()


@pytest.fixture
def car(world):
    bp = world.get_blueprint_library().find('vehicle.tesla.model3')
    points = world.get_map().get_spawn_points()
    vehicle = None
    for p in points[20::7]:
        vehicle = world.try_spawn_actor(bp, p)
        if vehicle is not None:
            break
    assert vehicle is not None
    _ticks(world, 20)  # it lands on its wheels
    yield vehicle
    vehicle.destroy()
    world.tick()


def test_ackermann_control_drives_at_the_target_speed_and_steers(world, car):
    assert _speed(car) < 0.3
    car.apply_ackermann_control(carla.VehicleAckermannControl(speed=5.0))
    _ticks(world, 100)
    assert 4.0 < _speed(car) < 6.0
    yaw = car.get_transform().rotation.yaw
    car.apply_ackermann_control(carla.VehicleAckermannControl(speed=5.0, steer=0.3))  # rad, > 0 right
    _ticks(world, 20)
    turned = (car.get_transform().rotation.yaw - yaw + 180) % 360 - 180
    assert turned > 5  # CARLA's yaw grows clockwise: a right turn
    with pytest.raises(lockstep.CommandRejected, match='steer') as e:
        car.apply_ackermann_control(carla.VehicleAckermannControl(steer=float('nan')))
    assert 'steer' in e.value.reason


def test_simulate_physics_off_freezes_the_car_and_refuses_impulses(world, car):
    car.apply_control(carla.VehicleControl(throttle=1.0))
    car.set_simulate_physics(False)
    _ticks(world, 20)
    assert _speed(car) < 0.1 and world._client.state(car.id)['kinematic']
    car.add_impulse(carla.Vector3D(1000, 0, 0))
    with pytest.raises(lockstep.CommandRejected, match='does not simulate physics') as e:
        _ticks(world, 2)
    assert 'Actor.add_impulse' in str(e.value) and 'ground_sim' in str(e.value)
    car.set_simulate_physics(True)
    car.apply_control(carla.VehicleControl(brake=0.0))
    world.tick()
    assert not world._client.state(car.id)['kinematic']


def test_impulse_and_force_change_the_velocity_by_the_mass(world, car):
    forward = car.get_transform().get_forward_vector()
    mass = car.get_physics_control().mass
    car.add_impulse(forward * (3.0 * mass))
    world.tick()
    assert 2.0 < _speed(car) < 3.3
    car.set_target_velocity(carla.Vector3D(0, 0, 0))
    world.tick()
    assert _speed(car) < 0.5
    # add_force: the force for one tick (dt 0.05 s) = an impulse of F dt.
    car.add_force(forward * (3.0 * mass / 0.05))
    world.tick()
    assert 2.0 < _speed(car) < 3.3


def test_target_velocity_sets_the_velocity(world, car):
    forward = car.get_transform().get_forward_vector()
    car.set_target_velocity(forward * 8.0)
    world.tick()
    v = car.get_velocity()
    assert 6.0 < v.length() < 8.5 and v.dot(forward) > 0
    with pytest.raises(lockstep.CommandRejected, match='NaN'):
        car.set_target_velocity(carla.Vector3D(float('nan'), 0, 0))


def test_physics_control_reads_back_and_changes_the_dynamics(world, car):
    p = car.get_physics_control()
    assert isinstance(p, carla.VehiclePhysicsControl)
    assert len(p.wheels) == 4 and p.forward_gears and p.torque_curve and p.mass > 0
    assert p.wheels[0].max_steer_angle > 0 and p.wheels[2].max_steer_angle == 0
    assert p.wheels[0].radius > 10  # centimetres, as CARLA
    assert isinstance(p.forward_gears[0], carla.GearPhysicsControl)
    forward = car.get_transform().get_forward_vector()
    # The same impulse moves a car of twice the mass half as fast.
    heavy = 2 * p.mass
    p.mass = heavy
    car.apply_physics_control(p)
    assert car.get_physics_control().mass == pytest.approx(heavy)  # at once, as CARLA
    assert world._client.vehicle_physics(car.id)['mass'] != pytest.approx(heavy)  # ground_sim: at the tick
    world.tick()
    assert world._client.vehicle_physics(car.id)['mass'] == pytest.approx(heavy)
    assert car.get_physics_control().mass == pytest.approx(heavy)
    car.add_impulse(forward * (3.0 * heavy / 2))
    world.tick()
    assert 1.0 < _speed(car) < 1.7
    # ground_sim's reason for a value it refuses reaches the script at the next tick.
    p = car.get_physics_control()
    for w in p.wheels:
        w.radius = 1.0  # cm
    car.apply_physics_control(p)
    with pytest.raises(lockstep.CommandRejected, match='wheel radius'):
        _ticks(world, 2)
    assert car.get_physics_control().wheels[0].radius > 10
    # What ground_sim cannot simulate raises at the call.
    p = car.get_physics_control()
    p.wheels[0].tire_friction += 1.0
    with pytest.raises(carla.LockstepUnsupported, match='tire_friction'):
        car.apply_physics_control(p)
    with pytest.raises(carla.LockstepUnsupported, match='steering_curve'):
        car.apply_physics_control(carla.VehiclePhysicsControl(steering_curve=[carla.Vector2D(0, 1)]))


def test_light_state(world, car):
    assert car.get_light_state() == carla.VehicleLightState.NONE
    lights = carla.VehicleLightState.LowBeam | carla.VehicleLightState.Position
    car.set_light_state(lights)
    assert car.get_light_state() == lights  # at once, as CARLA
    world.tick()
    assert world._client.state(car.id)['light_state'] == lights
    assert car.get_light_state() == lights
    assert world.get_vehicles_light_states()[car.id] == lights


def test_batch_commands(world, car):
    forward = car.get_transform().get_forward_vector()
    responses = world._carla_client.apply_batch_sync([
        carla.command.ApplyTargetVelocity(car, forward * 4.0),
        carla.command.SetVehicleLightState(car, carla.VehicleLightState.Brake),
    ], True)
    assert [r.error for r in responses] == ['', '']
    assert 3.0 < _speed(car) < 4.5 and car.get_light_state() == carla.VehicleLightState.Brake
    p = car.get_physics_control()
    p.mass = 2500.0
    responses = world._carla_client.apply_batch_sync([carla.command.ApplyVehiclePhysicsControl(car, p),
                                                      carla.command.SetSimulatePhysics(car, False)], True)
    assert not any(r.has_error() for r in responses)
    world.tick()
    assert car.get_physics_control().mass == 2500.0 and world._client.state(car.id)['kinematic']
    world._carla_client.apply_batch_sync([carla.command.ApplyVehicleAckermannControl(car, carla.VehicleAckermannControl()),
                                          carla.command.SetSimulatePhysics(car, True)], True)
    with pytest.raises(carla.LockstepUnsupported, match='command.SetEnableGravity'):
        carla.command.SetEnableGravity(car, False)


def test_walker_ai_controller_walks_to_the_goal_and_stops(world):
    lib = world.get_blueprint_library()
    m = world.get_map()
    start = m.get_waypoint(m.get_spawn_points()[40].location, lane_type=carla.LaneType.Sidewalk)
    walker = world.spawn_actor(lib.find('walker.pedestrian.0001'),
                               carla.Transform(start.transform.location + carla.Location(z=1.0)))
    controller = world.spawn_actor(lib.find('controller.ai.walker'), carla.Transform(), walker)
    assert isinstance(controller, carla.WalkerAIController)
    try:
        _ticks(world, 10)
        here = walker.get_location()
        goal = here + start.transform.get_forward_vector() * 10.0
        controller.start()
        controller.go_to_location(goal)
        controller.set_max_speed(1.5)
        _ticks(world, 40)  # 2 s at 1.5 m/s: about 3 m
        moved = walker.get_location().distance_2d(here)
        assert 2.0 < moved < 3.5
        assert walker.get_location().distance_2d(goal) < here.distance_2d(goal) - 2.0
        assert world._client.state(walker.id)['ai_controlled']
        controller.stop()
        _ticks(world, 10)
        assert _speed(walker) < 0.2
        with pytest.raises(lockstep.CommandRejected, match='max_speed'):
            controller.set_max_speed(50.0)
    finally:
        controller.destroy()
        walker.destroy()
        world.tick()


def test_traffic_manager_per_vehicle_calls(world, car):
    tm = world._carla_client.get_trafficmanager()
    car.set_autopilot(True)
    tm.ignore_lights_percentage(car, 100)
    tm.ignore_vehicles_percentage(car, 100)
    tm.set_desired_speed(car, 18.0)  # km/h; the town's limit is 30
    tm.keep_right_rule_percentage(car, 50)
    tm.random_left_lanechange_percentage(car, 0)
    tm.random_right_lanechange_percentage(car, 0)
    top = 0.0
    for _ in range(200):
        world.tick()
        top = max(top, _speed(car))
    assert 3.5 < top < 5.6  # 18 km/h = 5 m/s
    with pytest.raises(lockstep.CommandRejected, match='percentage'):
        tm.keep_right_rule_percentage(car, 500)
    # An Ackermann control on a car the Traffic Manager drives: ground_sim's reason.
    car.apply_ackermann_control(carla.VehicleAckermannControl(speed=1.0))
    with pytest.raises(lockstep.CommandRejected, match='autopilot'):
        _ticks(world, 2)
    car.set_autopilot(False)


def test_traffic_lights_through_landmarks(world):
    lights = world.get_actors().filter('traffic.traffic_light*')
    if not lights:
        pytest.skip('the town has no traffic lights')
    tl = lights[0]
    stops = tl.get_stop_waypoints()
    assert stops
    before = stops[0].previous(8.0)[0]
    found = world.get_traffic_lights_from_waypoint(before, 20.0)
    assert tl in found
    landmark = next(l for l in before.get_landmarks(20.0) if l.id == tl.get_opendrive_id())
    assert world.get_traffic_light(landmark) == tl
    # CARLA's agents find where a light acts from its trigger volume (the light's frame).
    area = tl.get_transform().transform(tl.trigger_volume.location)
    assert min(area.distance(w.transform.location) for w in stops) < tl.trigger_volume.extent.length() + 1.0
    affected = tl.get_affected_lane_waypoints()
    assert affected and all(isinstance(w, carla.Waypoint) for w in affected)
    j = stops[0].next(3.0)[0].get_junction()
    if j is not None:
        assert tl in world.get_traffic_lights_in_junction(j.id)
