#!/usr/bin/env python3
"""Synchronous mode with several sensors, as CARLA's synchronous_mode.py does it: one
queue per sensor, world.tick(), then every queue holds exactly that frame's data.
Run: lockstep python examples/sync_sensors.py --ticks 100"""
import argparse
import queue

import carla


def main():
    argparser = argparse.ArgumentParser(description=__doc__)
    argparser.add_argument('--ticks', default=100, type=int)
    argparser.add_argument('--sensors', default='sensor.camera.rgb,sensor.camera.depth,sensor.lidar.ray_cast,'
                           'sensor.other.imu,sensor.other.gnss,sensor.camera.semantic_segmentation')
    args = argparser.parse_args()

    client = carla.Client('localhost', 2000)
    client.set_timeout(10.0)
    world = client.get_world()
    original = world.get_settings()
    settings = world.get_settings()
    settings.synchronous_mode = True
    settings.fixed_delta_seconds = 0.05
    world.apply_settings(settings)
    library = world.get_blueprint_library()
    actors = []
    try:
        start = world.get_map().get_spawn_points()[0]
        parent = None
        vehicles = library.filter('vehicle.*')
        if len(vehicles):
            parent = world.spawn_actor(vehicles[0], start)
            actors.append(parent)
        queues = []
        for i, name in enumerate(args.sensors.split(',')):
            bp = library.find(name)
            if bp.has_attribute('image_size_x'):
                bp.set_attribute('image_size_x', '320')
                bp.set_attribute('image_size_y', '240')
            at = carla.Transform(carla.Location(x=1.5, z=2.4)) if parent else \
                carla.Transform(start.location + carla.Location(z=2.4 + i), start.rotation)
            sensor = world.spawn_actor(bp, at, attach_to=parent)
            actors.append(sensor)
            q = queue.Queue()
            sensor.listen(q.put)
            queues.append((name, q))
        world.tick()  # the spawn frame
        for _ in range(args.ticks):
            frame = world.tick()
            for name, q in queues:
                # As CARLA's synchronous_mode.py: skip what came before this frame (the spawn frame's data).
                data = q.get(timeout=2.0)
                while data.frame < frame:
                    data = q.get(timeout=2.0)
                assert data.frame == frame, '%s: frame %d, expected %d' % (name, data.frame, frame)
                assert q.empty(), '%s: more than one sample for frame %d' % (name, frame)
        print('%d ticks: every sensor delivered every frame once (%s)' % (args.ticks, ', '.join(n for n, _ in queues)))
    finally:
        for a in actors:
            if isinstance(a, carla.Sensor):
                a.stop()
        client.apply_batch([carla.command.DestroyActor(a) for a in reversed(actors)])
        world.apply_settings(original)


if __name__ == '__main__':
    main()
