#!/usr/bin/env python3
"""Cars and drones in one script and one clock: Traffic Manager cars from the carla API,
two drones from the airsim API, and a check that every tick's ground and air states
describe the same frame.
Run: lockstep python examples/cars_and_drones.py --ticks 200"""
import argparse

import airsim
import carla


def main():
    argparser = argparse.ArgumentParser(description=__doc__)
    argparser.add_argument('--ticks', default=200, type=int)
    argparser.add_argument('--cars', default=5, type=int)
    args = argparser.parse_args()

    client = carla.Client('localhost', 2000)
    world = client.get_world()
    original = world.get_settings()
    settings = world.get_settings()
    settings.synchronous_mode = True
    settings.fixed_delta_seconds = 0.05
    world.apply_settings(settings)
    library = world.get_blueprint_library()
    points = world.get_map().get_spawn_points()
    actors = []
    try:
        for i in range(args.cars):
            car = world.try_spawn_actor(library.filter('vehicle.*')[i % len(library.filter('vehicle.*'))], points[i * 7])
            if car is not None:
                car.set_autopilot(True)
                actors.append(car)
        for name, point in (('alpha', points[1]), ('bravo', points[2])):
            bp = library.find('drone.generic_quad')
            bp.set_attribute('role_name', name)
            t = carla.Transform(point.location + carla.Location(z=0.1), point.rotation)
            actors.append(world.spawn_actor(bp, t))
        world.tick()
        # Let the drone come to rest: like AirSim, air_sim refuses a takeoff while it moves.
        for _ in range(20):
            world.tick()

        air = airsim.MultirotorClient()
        futures = []
        for name in ('alpha', 'bravo'):
            air.enableApiControl(True, name)
            air.armDisarm(True, name)
            futures.append(air.takeoffAsync(vehicle_name=name))
        for f in futures:
            f.join()
        air.moveToPositionAsync(30, 0, -15, 5, vehicle_name='alpha')
        air.moveOnPathAsync([airsim.Vector3r(0, 20, -8), airsim.Vector3r(20, 20, -8)], 4, vehicle_name='bravo')

        aligned = 0
        for _ in range(args.ticks):
            frame = world.tick()
            snapshot = world.get_snapshot()
            aligned += snapshot.frame == frame
        for name in ('alpha', 'bravo'):
            p = air.getMultirotorState(vehicle_name=name).kinematics_estimated.position
            print('%s at NED (%.1f, %.1f, %.1f)' % (name, p.x_val, p.y_val, p.z_val))
        cars = [a for a in actors if a.type_id.startswith('vehicle.')]
        print('%d cars, 2 drones, %d/%d ticks with ground and air state of the same frame'
              % (len(cars), aligned, args.ticks))
    finally:
        client.apply_batch([carla.command.DestroyActor(a) for a in actors])
        world.apply_settings(original)


if __name__ == '__main__':
    main()
