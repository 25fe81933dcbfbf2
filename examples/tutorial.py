#!/usr/bin/env python3
"""CARLA's tutorial.py, shaped as CARLA writes it: a vehicle on autopilot with a depth
camera saving images, a few more vehicles, then everything destroyed.
Run: lockstep python examples/tutorial.py --ticks 100"""
import argparse
import os
import random

import carla


def main():
    argparser = argparse.ArgumentParser(description=__doc__)
    argparser.add_argument('--host', default='127.0.0.1')
    argparser.add_argument('-p', '--port', default=2000, type=int)
    argparser.add_argument('--ticks', default=100, type=int)
    argparser.add_argument('--out', default='_out')
    args = argparser.parse_args()

    actor_list = []
    client = carla.Client(args.host, args.port)
    client.set_timeout(10.0)
    world = client.get_world()
    original_settings = world.get_settings()
    settings = world.get_settings()
    settings.synchronous_mode = True
    settings.fixed_delta_seconds = 0.05
    world.apply_settings(settings)
    try:
        blueprint_library = world.get_blueprint_library()
        bp = random.choice(blueprint_library.filter('vehicle'))
        if bp.has_attribute('color'):
            color = random.choice(bp.get_attribute('color').recommended_values)
            bp.set_attribute('color', color)
        transform = random.choice(world.get_map().get_spawn_points())
        vehicle = world.spawn_actor(bp, transform)
        actor_list.append(vehicle)
        print('created %s' % vehicle.type_id)
        vehicle.set_autopilot(True)

        camera_bp = blueprint_library.find('sensor.camera.depth')
        camera_transform = carla.Transform(carla.Location(x=1.5, z=2.4))
        camera = world.spawn_actor(camera_bp, camera_transform, attach_to=vehicle)
        actor_list.append(camera)
        print('created %s' % camera.type_id)
        saved = []
        camera.listen(lambda image: saved.append(
            image.save_to_disk(os.path.join(args.out, '%06d.png' % image.frame), carla.ColorConverter.LogarithmicDepth)))

        location = vehicle.get_location()
        location.x += 40
        vehicle.set_location(location)
        print('moved vehicle to %s' % location)

        transform.location += carla.Location(x=40, y=-3.2)
        transform.rotation.yaw = -180.0
        for _ in range(0, 10):
            transform.location.x += 8.0
            bp = random.choice(blueprint_library.filter('vehicle'))
            npc = world.try_spawn_actor(bp, transform)
            if npc is not None:
                actor_list.append(npc)
                npc.set_autopilot(True)
                print('created %s' % npc.type_id)

        for _ in range(args.ticks):
            world.tick()
        print('vehicle at %s after %d ticks, %d images saved' % (vehicle.get_location(), args.ticks, len(saved)))
    finally:
        print('destroying actors')
        camera.stop() if 'camera' in locals() else None
        client.apply_batch([carla.command.DestroyActor(x) for x in actor_list])
        world.apply_settings(original_settings)
        print('done.')


if __name__ == '__main__':
    main()
