#!/usr/bin/env python3
"""A drone follows a car at 10 m: the car comes from the carla API (Traffic Manager
autopilot), the drone from the airsim API, both in one synchronous world.
Run: lockstep python examples/drone_follow_car.py --ticks 300"""
import argparse
import math

import airsim
import carla

HEIGHT = 10.0


def main():
    argparser = argparse.ArgumentParser(description=__doc__)
    argparser.add_argument('--ticks', default=300, type=int)
    args = argparser.parse_args()

    client = carla.Client('localhost', 2000)
    world = client.get_world()
    original = world.get_settings()
    settings = world.get_settings()
    settings.synchronous_mode = True
    settings.fixed_delta_seconds = 0.05
    world.apply_settings(settings)
    library = world.get_blueprint_library()
    spawn = world.get_map().get_spawn_points()[3]
    actors = []
    try:
        car = world.spawn_actor(library.filter('vehicle.*')[0], spawn)
        actors.append(car)
        car.set_autopilot(True)
        # The drone starts beside the road; AirSim's NED frame is anchored at its spawn point.
        drone_spawn = carla.Transform(spawn.location + carla.Location(x=-6.0, z=0.2), spawn.rotation)
        drone_bp = library.find('drone.generic_quad')
        drone_bp.set_attribute('role_name', 'follower')
        drone = world.spawn_actor(drone_bp, drone_spawn)
        actors.append(drone)
        world.tick()
        # Let the drone come to rest: like AirSim, air_sim refuses a takeoff while it moves.
        for _ in range(20):
            world.tick()

        air = airsim.MultirotorClient()
        air.enableApiControl(True, 'follower')
        air.armDisarm(True, 'follower')
        air.takeoffAsync(vehicle_name='follower').join()

        def ned(location, up):
            # carla (x east, y south-ish: left-handed) -> NED from the drone's spawn point
            return (drone_spawn.location.y - location.y, location.x - drone_spawn.location.x,
                    -(location.z + up - drone_spawn.location.z))

        distances = []
        for _ in range(args.ticks):
            # The car's position and velocity, re-sent every tick (Lockstep's trackTargetAsync;
            # moveToPositionAsync would restart its path each tick).
            v = car.get_velocity()
            air.trackTargetAsync(ned(car.get_location(), HEIGHT), (-v.y, v.x, -v.z), 12, 1.0, vehicle_name='follower')
            world.tick()
            p = drone.get_location()
            c = car.get_location()
            distances.append(math.sqrt((p.x - c.x) ** 2 + (p.y - c.y) ** 2 + (p.z - c.z - HEIGHT) ** 2))
        print('car drove %.1f m; drone-to-target distance: mean %.2f m, last %.2f m'
              % (car.get_location().distance(spawn.location), sum(distances) / len(distances), distances[-1]))
        air.landAsync(vehicle_name='follower')
    finally:
        client.apply_batch([carla.command.DestroyActor(a) for a in actors])
        world.apply_settings(original)


if __name__ == '__main__':
    main()
