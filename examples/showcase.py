#!/usr/bin/env python3
"""The main job (`./dev run`): every service on this machine, the training town, an ego
car under the Traffic Manager with NPC cars and pedestrians, a drone following the ego at
10 m, ground and aerial cameras, a LiDAR, an IMU and a GNSS, all in one synchronous
clock. Written on the public carla / airsim API: copy it.

Writes to --out: images/, lidar/ (PLY), ticks.csv (one line per tick), summary.json and
summary.txt (ticks per second, frames per sensor, ground/air frame alignment,
infractions) and town.png (the town from above with every trajectory).

Run: build/bin/lockstep python examples/showcase.py [--ticks 400] [--out out/showcase]
     (--connect: use a simulation that is already running instead of starting one)
"""
import argparse
import json
import math
import os
import random
import signal
import subprocess
import sys
import time

import numpy as np

import airsim
import carla

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BUILD = os.environ.get('LOCKSTEP_BUILD_DIR') or os.path.join(ROOT, 'build')


def progress(done, total, started, extra=''):
    width = 40
    filled = int(width * done / max(total, 1))
    rate = done / max(time.time() - started, 1e-9)
    sys.stdout.write('\r[%s%s] %d/%d ticks  %.1f ticks/s %s' % ('#' * filled, '.' * (width - filled), done, total, rate,
                                                                 extra))
    sys.stdout.flush()


def write_config(out, seed):
    """A launch config with every service built on this machine (air_sim always; ground_sim,
    sensors, render when their programs exist), synchronous, in the training town."""
    bin_dir = os.path.join(BUILD, 'bin')
    services = ['  - {name: air_sim, kind: air_sim}']
    for kind, perception in (('ground_sim', False), ('sensors', True), ('render', True)):
        if os.path.exists(os.path.join(bin_dir, 'lockstep_' + kind)):
            services.append('  - {name: %s, kind: %s, perception: %s}' % (kind, kind, 'true' if perception else 'false'))
    # The recorder writes the whole run as a Lockstep log: run1/recording.lslog (docs/recorder.md).
    services.append('  - {name: recorder, kind: recorder, perception: true, args: [--record-run]}')
    text = '\n'.join([
        '# Written by examples/showcase.py: every service built on this machine.',
        'name: showcase', 'domain_id: 0', 'seed: %d' % seed,
        'map: %s' % os.path.join(BUILD, 'maps', 'generated', 'LockstepTown1.xodr'),
        'output_dir: %s' % os.path.abspath(out),
        'world:', '  synchronous_mode: true', '  fixed_delta_seconds: 0.05', '  service_timeout: 60',
        'services:'] + services) + '\n'
    path = os.path.join(out, 'showcase.yaml')
    with open(path, 'w') as f:
        f.write(text)
    return path


def town_picture(world_map, trajectories, path, size=1024):
    """The road network from above, with each trajectory drawn over it (PNG)."""
    from lockstep.carla.sensor_data import write_png
    pts = [(w.transform.location.x, w.transform.location.y) for w in world_map.generate_waypoints(2.0)]
    for tr in trajectories.values():
        pts += [(x, y) for x, y in tr['xy']]
    xs, ys = [p[0] for p in pts], [p[1] for p in pts]
    x0, x1, y0, y1 = min(xs) - 10, max(xs) + 10, min(ys) - 10, max(ys) + 10
    scale = (size - 1) / max(x1 - x0, y1 - y0)
    img = np.full((int((y1 - y0) * scale) + 1, int((x1 - x0) * scale) + 1, 3), 245, dtype=np.uint8)

    def to_px(x, y):
        # CARLA y grows "down" on a map seen from above (left-handed), like image rows.
        return int((x - x0) * scale), int((y - y0) * scale)

    def dot(x, y, color, r):
        cx, cy = to_px(x, y)
        img[max(cy - r, 0):max(cy + r + 1, 0), max(cx - r, 0):max(cx + r + 1, 0)] = color

    for x, y in pts[:len(pts) - sum(len(t['xy']) for t in trajectories.values())]:
        dot(x, y, (150, 150, 150), 1)
    for tr in trajectories.values():
        for x, y in tr['xy']:
            dot(x, y, tr['color'], tr.get('width', 1))
        if tr['xy']:
            dot(*tr['xy'][0], (0, 0, 0), 3)
    write_png(path, img)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('--ticks', type=int, default=400)
    parser.add_argument('--out', default=os.path.join(ROOT, 'out', 'showcase'))
    parser.add_argument('--config', default='', help='launch config; default: every service built, written to --out')
    parser.add_argument('--connect', action='store_true', help='use the simulation already running')
    parser.add_argument('--cars', type=int, default=12)
    parser.add_argument('--walkers', type=int, default=10)
    parser.add_argument('--save-every', type=int, default=10, help='save images and point clouds every N ticks')
    parser.add_argument('--seed', type=int, default=42)
    args = parser.parse_args()
    random.seed(args.seed)
    os.makedirs(args.out, exist_ok=True)

    sim = None
    if not args.connect and not args.config:
        args.config = write_config(args.out, args.seed)
    if not args.connect:
        os.environ.setdefault('LOCKSTEP_DOMAIN', str(int(os.environ.get('LOCKSTEP_DOMAIN', '0'))))
        print('starting the simulation: %s (DDS domain %s)' % (os.path.relpath(args.config), os.environ['LOCKSTEP_DOMAIN']))
        sim = subprocess.Popen([os.path.join(BUILD, 'bin', 'lockstep'), 'up', args.config,
                                '--domain', os.environ['LOCKSTEP_DOMAIN']],
                               stdout=open(os.path.join(args.out, 'services.log'), 'w'), stderr=subprocess.STDOUT)
    actors = []
    try:
        client = carla.Client('localhost', 2000)
        client.set_timeout(60.0)
        world = client.get_world()
        world._client.wait_ready(120)
        settings = world.get_settings()
        settings.synchronous_mode = True
        settings.fixed_delta_seconds = 0.05
        world.apply_settings(settings)
        world_map = world.get_map()
        library = world.get_blueprint_library()
        members = [m[0] for m in world._client.run_status()['members']]
        print('town %s, services: %s, %d blueprints' % (world_map.name, ', '.join(members), len(library)))
        spawn_points = world_map.get_spawn_points()
        random.shuffle(spawn_points)

        # --- ground traffic (ground_sim) ---
        tm = client.get_trafficmanager()
        vehicle_bps = library.filter('vehicle.*')
        ego, npcs, walkers, controllers = None, [], [], []
        if len(vehicle_bps):
            tm.set_random_device_seed(args.seed)
            ego_bp = vehicle_bps[0]
            ego_bp.set_attribute('role_name', 'hero')
            ego = world.spawn_actor(ego_bp, spawn_points[0])
            actors.append(ego)
            batch = [carla.command.SpawnActor(random.choice(vehicle_bps), t)
                     .then(carla.command.SetAutopilot(carla.command.FutureActor, True))
                     for t in spawn_points[1:1 + args.cars]]
            for r in client.apply_batch_sync(batch):
                if not r.error:
                    npcs.append(world.get_actor(r.actor_id))
            actors += [a for a in npcs if a is not None]
            walker_bps = library.filter('walker.pedestrian.*')
            for _ in range(args.walkers if len(walker_bps) else 0):
                loc = world.get_random_location_from_navigation()
                w = world.try_spawn_actor(random.choice(walker_bps), carla.Transform(loc + carla.Location(z=1.0)))
                if w is not None:
                    walkers.append(w)
            actors += walkers
            # CARLA's walker AI: without a goal they wander the sidewalks and cross at crosswalks.
            controller_bps = library.filter('controller.ai.walker')
            controllers = [world.spawn_actor(controller_bps[0], carla.Transform(), w) for w in walkers
                           if len(controller_bps)]
            actors += controllers
        else:
            print('no vehicle blueprints (ground_sim not running): drones and sensors only')
        ego_start = ego.get_transform() if ego else spawn_points[0]

        # --- the drone that follows the ego at 10 m (air_sim) ---
        drone_bp = library.find('drone.generic_quad')
        drone_bp.set_attribute('role_name', 'follower')
        drone_spawn = carla.Transform(ego_start.location + carla.Location(x=-5.0, z=0.2))
        drone = world.spawn_actor(drone_bp, drone_spawn)
        actors.append(drone)

        # --- sensors (render: cameras; sensors: LiDAR, IMU, GNSS, collision, lane invasion) ---
        mount = ego if ego else drone
        wanted = [
            ('ground_camera', 'sensor.camera.rgb', carla.Transform(carla.Location(x=1.5, z=2.4)), mount,
             {'image_size_x': '640', 'image_size_y': '360'}),
            ('aerial_camera', 'sensor.camera.rgb', carla.Transform(carla.Location(z=-0.2), carla.Rotation(pitch=-60)),
             drone, {'image_size_x': '640', 'image_size_y': '360'}),
            ('lidar', 'sensor.lidar.ray_cast', carla.Transform(carla.Location(z=2.5)), mount,
             {'channels': '32', 'range': '50', 'points_per_second': '200000', 'rotation_frequency': '20'}),
            ('imu', 'sensor.other.imu', carla.Transform(), mount, {}),
            ('gnss', 'sensor.other.gnss', carla.Transform(), mount, {}),
        ]
        events = [('collision', 'sensor.other.collision'), ('lane_invasion', 'sensor.other.lane_invasion')]
        sensors, frames, infractions, latest = {}, {}, {'collision': 0, 'lane_invasion': 0}, {}
        for name, bp_id, where, parent, attrs in wanted:
            if not len(library.filter(bp_id)):
                print('  %-14s skipped: no service declares %s' % (name, bp_id))
                continue
            bp = library.find(bp_id)
            for k, v in attrs.items():
                if bp.has_attribute(k):
                    bp.set_attribute(k, v)
            sensors[name] = world.spawn_actor(bp, where, attach_to=parent)
            actors.append(sensors[name])
        if ego:
            for name, bp_id in events:
                if len(library.filter(bp_id)):
                    sensors[name] = world.spawn_actor(library.find(bp_id), carla.Transform(), attach_to=ego)
                    actors.append(sensors[name])
        world.tick()  # the spawn frame
        for c in controllers:
            c.start()
            c.set_max_speed(1.4)
        # Let the drone come to rest: like AirSim, air_sim refuses a takeoff while it moves.
        for _ in range(20):
            world.tick()

        out_dirs = {n: os.path.join(args.out, d) for n, d in (('ground_camera', 'images/ground'),
                                                               ('aerial_camera', 'images/aerial'),
                                                               ('lidar', 'lidar'))}

        def listener(name):
            frames[name] = []

            def on_data(data):
                frames[name].append(data.frame)
                latest[name] = data
                if name in infractions:
                    infractions[name] += 1
                elif name in out_dirs and data.frame % args.save_every == 0:
                    data.save_to_disk(os.path.join(out_dirs[name], '%06d' % data.frame))
            return on_data

        for name, s in sensors.items():
            s.listen(listener(name))
        # Every tick from here on (the takeoff's included) delivers one frame per camera,
        # LiDAR, IMU and GNSS; the event sensors only when something happens.
        first_listened = world.get_snapshot().frame + 1

        air = airsim.MultirotorClient()
        air.enableApiControl(True, 'follower')
        air.armDisarm(True, 'follower')
        if not air.takeoffAsync(vehicle_name='follower').join():
            print('warning: the drone did not finish its takeoff in time')
        if ego:
            ego.set_autopilot(True)

        # --- the run ---
        trajectories = {'ego': {'xy': [], 'color': (220, 30, 30), 'width': 2},
                        'drone': {'xy': [], 'color': (30, 160, 30), 'width': 1}}
        for i, a in enumerate(npcs):
            trajectories['npc%d' % i] = {'xy': [], 'color': (60, 90, 220)}
        for i, w in enumerate(walkers):
            trajectories['walker%d' % i] = {'xy': [], 'color': (200, 120, 0)}
        csv = open(os.path.join(args.out, 'ticks.csv'), 'w')
        csv.write('frame,sim_time,wall_s,ego_x,ego_y,ego_speed,drone_x,drone_y,drone_z,ground_frame,air_frame,%s\n'
                  % ','.join('%s_frame' % n for n in sensors))
        aligned = 0
        started = time.time()
        target = ego if ego else None
        for t in range(args.ticks):
            if target is not None:
                # 10 m above the ego, in the drone's NED frame (from its spawn point), with the ego's
                # velocity as feed-forward: trackTargetAsync is re-sent every tick.
                c, v = target.get_location(), target.get_velocity()
                air.trackTargetAsync((drone_spawn.location.y - c.y, c.x - drone_spawn.location.x,
                                      -(c.z + 10.0 - drone_spawn.location.z)), (-v.y, v.x, -v.z), 15, 1.0,
                                     vehicle_name='follower')
            elif t == 0:
                air.moveOnPathAsync([airsim.Vector3r(0, 40, -15), airsim.Vector3r(40, 40, -15),
                                     airsim.Vector3r(40, 0, -15), airsim.Vector3r(0, 0, -15)], 6,
                                    vehicle_name='follower')
            frame = world.tick()
            _, snap_frame, sim_time, ground_frame, air_frame = world._client.snapshot_frame()
            has_ground = ego is not None
            if air_frame == frame and (not has_ground or ground_frame == frame):
                aligned += 1
            d = drone.get_location()
            trajectories['drone']['xy'].append((d.x, d.y))
            e = ego.get_location() if ego else None
            if e:
                trajectories['ego']['xy'].append((e.x, e.y))
            for i, a in enumerate(npcs):
                if t % 5 == 0 and a is not None:
                    loc = a.get_location()
                    trajectories['npc%d' % i]['xy'].append((loc.x, loc.y))
            for i, w in enumerate(walkers):
                if t % 5 == 0:
                    loc = w.get_location()
                    trajectories['walker%d' % i]['xy'].append((loc.x, loc.y))
            speed = ego.get_velocity().length() if ego else 0.0
            csv.write('%d,%.3f,%.3f,%s,%s,%.3f,%.3f,%.3f,%.3f,%d,%d,%s\n' % (
                frame, sim_time, time.time() - started, '%.3f' % e.x if e else '', '%.3f' % e.y if e else '', speed,
                d.x, d.y, d.z, ground_frame, air_frame,
                ','.join(str(frames[n][-1]) if frames.get(n) else '' for n in sensors)))
            if t % 5 == 0 or t == args.ticks - 1:
                progress(t + 1, args.ticks, started, 'drone %.1f m up' % d.z)
        wall = time.time() - started
        print()
        csv.close()

        summary = {
            'town': world_map.name,
            'services': members,
            'ticks': args.ticks,
            'wall_s': round(wall, 3),
            'ticks_per_second': round(args.ticks / wall, 2),
            'real_time_factor': round(args.ticks * 0.05 / wall, 3),
            'frames_per_sensor': {n: len(f) for n, f in frames.items()},
            'frames_since_listen': frame - first_listened + 1,
            'sensor_frames_in_order_once': {n: f == sorted(set(f)) for n, f in frames.items()},
            'every_frame_once': {n: f == list(range(first_listened, frame + 1)) for n, f in frames.items()
                                 if n not in infractions},
            'ground_air_frame_alignment': '%d/%d ticks' % (aligned, args.ticks),
            'infractions': infractions,
            'cars': (1 if ego else 0) + len(npcs),
            'walkers': len(walkers),
            'ego_distance_m': round(sum(math.dist(a, b) for a, b in zip(trajectories['ego']['xy'],
                                                                          trajectories['ego']['xy'][1:])), 1),
            'drone_height_above_ego_m': round(d.z - (e.z if e else ego_start.location.z), 1),
            'drone_distance_m': round(sum(math.dist(a, b) for a, b in zip(trajectories['drone']['xy'],
                                                                            trajectories['drone']['xy'][1:])), 1),
        }
        with open(os.path.join(args.out, 'summary.json'), 'w') as f:
            json.dump(summary, f, indent=2)
        lines = ['Lockstep showcase: %s' % summary['town'],
                 '  %d ticks in %.1f s: %.1f ticks/s (real-time factor %.2f)' % (args.ticks, wall, summary['ticks_per_second'],
                                                                                summary['real_time_factor']),
                 '  services: %s' % ', '.join(members),
                 '  actors: %d cars, %d walkers, 1 drone' % (summary['cars'], summary['walkers']),
                 '  frames per sensor (%d frames since listen(), the takeoff included; every one once and in order: %s): %s' % (
                     summary['frames_since_listen'], 'yes' if all(summary['every_frame_once'].values()) else 'NO',
                     ', '.join('%s %d' % kv for kv in summary['frames_per_sensor'].items())),
                 '  ground/air frame alignment: %s' % summary['ground_air_frame_alignment'],
                 '  infractions: %d collision event(s), %d lane invasion(s)' % (infractions['collision'],
                                                                                 infractions['lane_invasion']),
                 '  ego drove %.1f m, the drone flew %.1f m and ended %.1f m above the ego' % (
                     summary['ego_distance_m'], summary['drone_distance_m'], summary['drone_height_above_ego_m']),
                 '  output: %s (images/, lidar/, ticks.csv, summary.json, town.png, run1/recording.lslog)' % os.path.relpath(args.out),
                 '  driving benchmarks (CoRL 2017, NoCrash, Leaderboard routes; docs/benchmarks.md): '
                 'build/bin/lockstep python -m lockstep.benchmarks corl2017 --agent autopilot --episodes 2']
        with open(os.path.join(args.out, 'summary.txt'), 'w') as f:
            f.write('\n'.join(lines) + '\n')
        town_picture(world_map, trajectories, os.path.join(args.out, 'town.png'))
        print('\n'.join(lines))
    finally:
        try:
            for s in [a for a in actors if isinstance(a, carla.Sensor)]:
                s.stop()
        except Exception:  # noqa: BLE001 - the simulation may already be gone
            pass
        if sim is not None:
            sim.send_signal(signal.SIGINT)
            try:
                sim.wait(20)
            except subprocess.TimeoutExpired:
                sim.kill()


if __name__ == '__main__':
    main()
