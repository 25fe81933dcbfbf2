"""CARLA-Air's joint workload in ticks per second: 100 vehicles under the Traffic Manager,
50 pedestrians under CARLA's walker AI, one drone, and 8 sensors: 4 cameras on a car
(front, rear, left, right), 2 on the drone (down, forward), a LiDAR, and an IMU and a
GNSS, all in one synchronous world (ground_sim, air_sim, sensors, render). CARLA-Air
reports 19.8 FPS for its joint run (8 x 720p streams, one drone, Town10HD, RTX-3080-class
GPU).

    build/bin/lockstep python -m lockstep.benchmarks.joint --ticks 100 --width 1280 --height 720
"""
import argparse
import json
import os
import random
import sys
import time

from . import episodes as episodes_mod
from . import runner

GROUND = {'front': (1.5, 0.0, 2.0, 0.0), 'rear': (-2.0, 0.0, 2.0, 180.0), 'left': (0.0, -1.0, 2.0, -90.0),
          'right': (0.0, 1.0, 2.0, 90.0)}
AERIAL = {'down': (-90.0, 0.0), 'forward': (-20.0, 0.0)}


def run(ctx, air, ticks, width, height, vehicles=100, walkers=50, seed=0, warmup=5):
    carla = ctx.carla
    rng = random.Random(seed)
    # The car on a straight street (the drone takes off 6 m to its right, clear of walls and trees).
    _, tasks = episodes_mod.load(ctx.map.name)
    sx, sy, sz, syaw = tasks['Straight'][0]['start']
    start = carla.Transform(carla.Location(sx, sy, sz + 0.3), carla.Rotation(yaw=syaw))
    actors = []
    try:
        car = ctx.world.spawn_actor(ctx.ego_blueprint(), start)
        actors.append(car)
        drone, spawn = runner.drone_beside(ctx, carla.Location(sx, sy, sz), syaw, 'joint_drone')
        actors.append(drone)
        for _ in range(20):
            ctx.world.tick()
        # The drone up first, then the traffic (a crowd around it kept it from taking off once).
        runner.take_off(air, 'joint_drone')
        actors += runner.spawn_traffic(ctx, rng, vehicles, walkers, (start.location.x, start.location.y))
        n_vehicles = sum(1 for a in actors if a.type_id.startswith('vehicle.'))
        n_walkers = sum(1 for a in actors if a.type_id.startswith('walker.'))
        sensors = []

        def camera(parent, transform):
            b = ctx.lib.find('sensor.camera.rgb')
            b.set_attribute('image_size_x', str(width))
            b.set_attribute('image_size_y', str(height))
            return ctx.world.spawn_actor(b, transform, attach_to=parent)

        for x, y, z, cyaw in GROUND.values():
            sensors.append(camera(car, carla.Transform(carla.Location(x, y, z), carla.Rotation(yaw=cyaw))))
        for pitch, cyaw in AERIAL.values():
            sensors.append(camera(drone, carla.Transform(carla.Location(z=-0.2), carla.Rotation(pitch=pitch, yaw=cyaw))))
        sensors.append(ctx.world.spawn_actor(ctx.lib.find('sensor.lidar.ray_cast'), carla.Transform(carla.Location(z=2.4)),
                                             attach_to=car))
        sensors.append(ctx.world.spawn_actor(ctx.lib.find('sensor.other.imu'), carla.Transform(), attach_to=car))
        sensors.append(ctx.world.spawn_actor(ctx.lib.find('sensor.other.gnss'), carla.Transform(), attach_to=car))
        actors += sensors
        ctx.world.tick()
        car.set_autopilot(True)
        counts = [0] * len(sensors)
        for i, s in enumerate(sensors):
            s.listen(lambda data, i=i: counts.__setitem__(i, counts[i] + 1))

        def step():
            c, v = car.get_location(), car.get_velocity()
            air.trackTargetAsync(runner.ned(spawn, c, 10.0), runner.ned_velocity(v), 12.0, 1.0,
                                 vehicle_name='joint_drone')
            ctx.world.tick()

        for _ in range(warmup):
            step()
        before = list(counts)
        started = time.time()
        for _ in range(ticks):
            step()
        wall = time.time() - started
        for s in sensors:
            s.stop()
        every = all(c - b == ticks for c, b in zip(counts, before))
        airborne = drone.get_location().z - car.get_location().z > 5.0
        return {'workload': 'carla_air_joint', 'ticks': ticks, 'wall_s': round(wall, 2), 'drone_airborne': airborne,
                'ticks_per_s': round(ticks / wall, 2), 'vehicles': n_vehicles, 'walkers': n_walkers, 'drones': 1,
                'cameras': len(GROUND) + len(AERIAL), 'image_size': [width, height], 'sensors': len(sensors),
                'every_sensor_every_tick': every, 'carla_air_fps': 19.8}
    finally:
        runner.release(ctx, actors, air, 'joint_drone')


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--ticks', type=int, default=100)
    ap.add_argument('--width', type=int, default=1280)
    ap.add_argument('--height', type=int, default=720)
    ap.add_argument('--town', default='Town01')
    runner.workload_args(ap, connect=False)
    args = ap.parse_args(argv)
    out = runner.out_dir(args.out, 'joint')
    sim = runner.own_simulation(args.town, args.domain, out, dt=0.05, air=True, cameras=True)
    try:
        import airsim
        ctx = runner.Context(dt=0.05)
        r = run(ctx, airsim.MultirotorClient(), args.ticks, args.width, args.height)
        print(json.dumps(r))
        with open(os.path.join(out, 'joint.json'), 'w') as f:
            json.dump(r, f, indent=1)
        return 0 if r['every_sensor_every_tick'] else 1
    finally:
        sim.stop()


if __name__ == '__main__':
    sys.exit(main())
