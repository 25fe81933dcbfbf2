#!/usr/bin/env python3
"""CARLA's generate_traffic.py, trimmed: vehicles under the Traffic Manager and walkers
with AI controllers, spawned in batches, in synchronous mode.
Run: lockstep python examples/spawn_traffic.py -n 20 -w 10 --ticks 200"""
import argparse
import random

import carla
from carla import command


def main():
    argparser = argparse.ArgumentParser(description=__doc__)
    argparser.add_argument('--host', default='127.0.0.1')
    argparser.add_argument('-p', '--port', default=2000, type=int)
    argparser.add_argument('-n', '--number-of-vehicles', default=20, type=int)
    argparser.add_argument('-w', '--number-of-walkers', default=10, type=int)
    argparser.add_argument('--tm-port', default=8000, type=int)
    argparser.add_argument('--seed', default=7, type=int)
    argparser.add_argument('--ticks', default=200, type=int)
    args = argparser.parse_args()
    random.seed(args.seed)

    vehicles_list, walkers_list, controllers_list = [], [], []
    client = carla.Client(args.host, args.port)
    client.set_timeout(10.0)
    world = client.get_world()
    traffic_manager = client.get_trafficmanager(args.tm_port)
    traffic_manager.set_global_distance_to_leading_vehicle(2.5)
    traffic_manager.set_random_device_seed(args.seed)
    settings = world.get_settings()
    traffic_manager.set_synchronous_mode(True)
    settings.synchronous_mode = True
    settings.fixed_delta_seconds = 0.05
    world.apply_settings(settings)
    try:
        blueprints = world.get_blueprint_library().filter('vehicle.*')
        spawn_points = world.get_map().get_spawn_points()
        random.shuffle(spawn_points)
        batch = []
        for n, transform in enumerate(spawn_points[:args.number_of_vehicles]):
            blueprint = random.choice(blueprints)
            if blueprint.has_attribute('color'):
                blueprint.set_attribute('color', random.choice(blueprint.get_attribute('color').recommended_values))
            blueprint.set_attribute('role_name', 'autopilot')
            batch.append(command.SpawnActor(blueprint, transform)
                         .then(command.SetAutopilot(command.FutureActor, True, traffic_manager.get_port())))
        for response in client.apply_batch_sync(batch, True):
            if response.error:
                print('vehicle: %s' % response.error)
            else:
                vehicles_list.append(response.actor_id)

        walker_bps = world.get_blueprint_library().filter('walker.pedestrian.*')
        batch = []
        for _ in range(args.number_of_walkers):
            loc = world.get_random_location_from_navigation()
            if loc is not None:
                batch.append(command.SpawnActor(random.choice(walker_bps), carla.Transform(loc)))
        for response in client.apply_batch_sync(batch, True):
            if response.error:
                print('walker: %s' % response.error)
            else:
                walkers_list.append(response.actor_id)
        # As generate_traffic: an AI controller per walker, started after a tick.
        controller_bps = world.get_blueprint_library().filter('controller.ai.walker')
        batch = [command.SpawnActor(controller_bps[0], carla.Transform(), w) for w in walkers_list if controller_bps]
        for response in client.apply_batch_sync(batch, True):
            if response.error:
                print('walker controller: %s' % response.error)
            else:
                controllers_list.append(response.actor_id)
        world.tick()
        for controller in world.get_actors(controllers_list):
            controller.start()
            goal = world.get_random_location_from_navigation()
            if goal is not None:
                controller.go_to_location(goal)
            controller.set_max_speed(1.4)
        print('spawned %d vehicles and %d walkers' % (len(vehicles_list), len(walkers_list)))

        for _ in range(args.ticks):
            world.tick()
        moving = sum(1 for a in world.get_actors(vehicles_list) if a.get_velocity().length() > 0.5)
        print('%d of %d vehicles moving after %d ticks' % (moving, len(vehicles_list), args.ticks))
    finally:
        for controller in world.get_actors(controllers_list):
            controller.stop()
        client.apply_batch([command.DestroyActor(x) for x in controllers_list + vehicles_list + walkers_list])
        settings.synchronous_mode = False
        world.apply_settings(settings)
        print('destroyed %d actors' % (len(vehicles_list) + len(walkers_list)))


if __name__ == '__main__':
    main()
