"""CARLA-Air's synchronized multi-modal dataset: a car under the Traffic Manager with a
drone following 10 m above it, ground and aerial cameras, a LiDAR, an IMU and a GNSS, one
sample of every sensor per tick, written in a KITTI-like layout with calibration files,
and an alignment check that reads the dataset back.

    build/bin/lockstep python -m lockstep.benchmarks.dataset --ticks 200 --out out/dataset

Layout (KITTI raw / odometry names where KITTI has them):

    calib.txt              P_front, P_rear, P_aerial (3x4 camera matrices), Tr_velo_to_front,
                           Tr_imu_to_velo (3x4, KITTI's camera axes: x right, y down, z forward)
    times.txt              one line per index: the tick's frame and simulated time (s)
    image_front/000000.png, image_rear/, image_aerial/   RGB
    velodyne/000000.bin    float32 x, y, z, intensity (CARLA's sensor frame)
    oxts/000000.txt        lat lon alt, IMU ax ay az (m/s^2), wx wy wz (rad/s), compass (rad)
    <sensor>/timestamps.txt   each sample's own frame and time, one line per index

The check (`check_alignment`): for every index, every sensor's own frame (its
timestamps.txt, written from the sample's `frame`) equals the tick's frame in times.txt,
and every index has its file. CARLA-Air reports at most one tick of misalignment; in
lock-step there must be none."""
import argparse
import json
import math
import os
import queue
import sys
import time

import numpy as np

from . import episodes as episodes_mod
from . import runner

CAMERAS = {
    # name: (parent, x, y, z, pitch, yaw)
    'image_front': ('car', 1.5, 0.0, 2.0, 0.0, 0.0),
    'image_rear': ('car', -2.0, 0.0, 2.0, 0.0, 180.0),
    'image_aerial': ('drone', 0.0, 0.0, -0.2, -90.0, 0.0),
}
SENSORS = list(CAMERAS) + ['velodyne', 'oxts_imu', 'oxts_gnss']


def intrinsics(width, height, fov_deg):
    f = width / (2.0 * math.tan(math.radians(fov_deg) / 2.0))
    return np.array([[f, 0, width / 2.0, 0], [0, f, height / 2.0, 0], [0, 0, 1, 0]])


def _kitti_from_carla(t):
    """4x4 from a CARLA sensor frame (x forward, y right, z up) to KITTI's camera axes."""
    m = np.zeros((4, 4))
    m[0, 1] = 1.0    # x_cam = y_carla (right)
    m[1, 2] = -1.0   # y_cam = -z_carla (down)
    m[2, 0] = 1.0    # z_cam = x_carla (forward)
    m[3, 3] = 1.0
    return m


def _mount(x, y, z, pitch=0.0, yaw=0.0):
    """4x4 pose of a sensor in its parent's frame (CARLA's axes; yaw, pitch in degrees)."""
    cy, sy = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
    cp, sp = math.cos(math.radians(pitch)), math.sin(math.radians(pitch))
    r = np.array([[cp * cy, -sy, -sp * cy], [cp * sy, cy, -sp * sy], [sp, 0, cp]])
    m = np.eye(4)
    m[:3, :3] = r
    m[:3, 3] = (x, y, z)
    return m


def _row(m):
    return ' '.join('%.9e' % v for v in np.asarray(m)[:3, :4].reshape(-1))


def write_calib(path, width, height, fov, lidar_mount, imu_mount):
    k = intrinsics(width, height, fov)
    lines = ['P_%s: %s' % (name.replace('image_', ''), _row(k)) for name in CAMERAS]
    front = _mount(*CAMERAS['image_front'][1:4], pitch=CAMERAS['image_front'][4], yaw=CAMERAS['image_front'][5])
    velo_to_front = _kitti_from_carla(None) @ np.linalg.inv(front) @ lidar_mount
    lines.append('Tr_velo_to_front: %s' % _row(velo_to_front))
    lines.append('Tr_imu_to_velo: %s' % _row(np.linalg.inv(lidar_mount) @ imu_mount))
    with open(path, 'w') as f:
        f.write('\n'.join(lines) + '\n')


def record(ctx, air, out, ticks, width=400, height=300, fov=90.0, seed=0, every=1):
    """Drives the scene for `ticks` ticks and writes the dataset to `out`; returns a summary."""
    carla = ctx.carla
    _, tasks = episodes_mod.load('Town01')
    ep = tasks['Navigation'][seed % len(tasks['Navigation'])]
    sx, sy, sz, syaw = ep['start']
    actors = []
    try:
        car = ctx.world.spawn_actor(ctx.ego_blueprint(), carla.Transform(carla.Location(sx, sy, sz + 0.3),
                                                                         carla.Rotation(yaw=syaw)))
        actors.append(car)
        drone, spawn = runner.drone_beside(ctx, carla.Location(sx, sy, sz), syaw, 'dataset_drone')
        actors.append(drone)
        parents = {'car': car, 'drone': drone}
        sensors = {}
        for name, (parent, x, y, z, pitch, syaw_) in CAMERAS.items():
            b = ctx.lib.find('sensor.camera.rgb')
            for k, v in (('image_size_x', width), ('image_size_y', height), ('fov', fov)):
                b.set_attribute(k, str(v))
            sensors[name] = ctx.world.spawn_actor(b, carla.Transform(carla.Location(x, y, z),
                                                                     carla.Rotation(pitch=pitch, yaw=syaw_)),
                                                  attach_to=parents[parent])
        lb = ctx.lib.find('sensor.lidar.ray_cast')
        for k, v in (('channels', '32'), ('range', '50'), ('points_per_second', '100000'), ('rotation_frequency', '20')):
            lb.set_attribute(k, v)
        lidar_mount = _mount(0.0, 0.0, 2.4)
        imu_mount = _mount(0.0, 0.0, 0.5)
        sensors['velodyne'] = ctx.world.spawn_actor(lb, carla.Transform(carla.Location(z=2.4)), attach_to=car)
        sensors['oxts_imu'] = ctx.world.spawn_actor(ctx.lib.find('sensor.other.imu'),
                                                    carla.Transform(carla.Location(z=0.5)), attach_to=car)
        sensors['oxts_gnss'] = ctx.world.spawn_actor(ctx.lib.find('sensor.other.gnss'),
                                                     carla.Transform(carla.Location(z=0.5)), attach_to=car)
        actors += list(sensors.values())
        for _ in range(20):
            ctx.world.tick()
        runner.take_off(air, 'dataset_drone')
        tm = ctx.client.get_trafficmanager()
        car.set_autopilot(True, tm.get_port())
        tm.auto_lane_change(car, False)
        ctx.world.tick()
        tm.set_path(car, [carla.Location(*p) for p in ep['path'] if math.hypot(p[0] - sx, p[1] - sy) > 10.0][:256])
        os.makedirs(out, exist_ok=True)
        for name in SENSORS:
            if name != 'oxts_gnss':
                os.makedirs(os.path.join(out, name if name != 'oxts_imu' else 'oxts'), exist_ok=True)
        write_calib(os.path.join(out, 'calib.txt'), width, height, fov, lidar_mount, imu_mount)
        queues = {n: queue.Queue() for n in sensors}
        for n, s in sensors.items():
            s.listen(queues[n].put)
        stamps = {n: open(os.path.join(out, n if n.startswith('image') or n == 'velodyne' else 'oxts',
                                       'timestamps.txt' if n not in ('oxts_gnss',) else 'timestamps_gnss.txt'), 'w')
                  for n in sensors}
        times = open(os.path.join(out, 'times.txt'), 'w')

        started = time.time()
        written = 0
        for k in range(ticks):
            c, v = car.get_location(), car.get_velocity()
            air.trackTargetAsync(runner.ned(spawn, c, 10.0), runner.ned_velocity(v), 12.0, 1.0,
                                 vehicle_name='dataset_drone')
            frame = ctx.world.tick()
            snap = ctx.world.get_snapshot()
            samples = {}
            for n, q in queues.items():
                # tick() returned after every listened sensor delivered this frame: take all
                # that arrived, the last is this tick's (a sensor behind would show here).
                got = []
                while not q.empty():
                    got.append(q.get_nowait())
                samples[n] = got[-1] if got else None
            if k % every:
                continue
            idx = '%06d' % written
            times.write('%d %.6f\n' % (frame, snap.timestamp.elapsed_seconds))
            for n, s in samples.items():
                if s is None:
                    stamps[n].write('-1 nan\n')
                    continue
                stamps[n].write('%d %.6f\n' % (s.frame, s.timestamp))
                if n.startswith('image'):
                    a = s.to_numpy()
                    from lockstep.carla.sensor_data import write_png
                    write_png(os.path.join(out, n, idx + '.png'), np.ascontiguousarray(a[..., [2, 1, 0]]))
                elif n == 'velodyne':
                    np.asarray(s.to_numpy(), dtype=np.float32).tofile(os.path.join(out, n, idx + '.bin'))
            imu, gnss = samples['oxts_imu'], samples['oxts_gnss']
            if imu is not None and gnss is not None:
                with open(os.path.join(out, 'oxts', idx + '.txt'), 'w') as f:
                    f.write('%.9f %.9f %.4f %.6f %.6f %.6f %.6f %.6f %.6f %.6f\n' % (
                        gnss.latitude, gnss.longitude, gnss.altitude, imu.accelerometer.x, imu.accelerometer.y,
                        imu.accelerometer.z, imu.gyroscope.x, imu.gyroscope.y, imu.gyroscope.z, imu.compass))
            written += 1
        wall = time.time() - started
        times.close()
        for f in stamps.values():
            f.close()
        for s in sensors.values():
            s.stop()
        return {'ticks': ticks, 'indices': written, 'wall_s': round(wall, 2), 'ticks_per_s': round(ticks / wall, 2),
                'sensors': len(sensors), 'image_size': [width, height]}
    finally:
        runner.release(ctx, actors, air, 'dataset_drone')


def _read_stamps(path):
    out = []
    with open(path) as f:
        for line in f:
            parts = line.split()
            out.append(int(parts[0]))
    return out


def check_alignment(out):
    """{'indices', 'misaligned' (indices where some sensor's frame differs from the tick's or
    a file is missing), 'per_sensor'}."""
    ticks = _read_stamps(os.path.join(out, 'times.txt'))
    files = {'image_front': ('image_front', 'timestamps.txt', '.png'), 'image_rear': ('image_rear', 'timestamps.txt', '.png'),
             'image_aerial': ('image_aerial', 'timestamps.txt', '.png'),
             'velodyne': ('velodyne', 'timestamps.txt', '.bin'), 'oxts_imu': ('oxts', 'timestamps.txt', '.txt'),
             'oxts_gnss': ('oxts', 'timestamps_gnss.txt', '.txt')}
    bad = set()
    per = {}
    for name, (folder, stamp_file, ext) in files.items():
        stamps = _read_stamps(os.path.join(out, folder, stamp_file))
        wrong = [i for i, t in enumerate(ticks) if i >= len(stamps) or stamps[i] != t or
                 not os.path.exists(os.path.join(out, folder, '%06d%s' % (i, ext)))]
        wrong += list(range(len(ticks), len(stamps)))   # extra samples are misaligned too
        per[name] = len(wrong)
        bad.update(wrong)
    return {'indices': len(ticks), 'misaligned': len(bad), 'per_sensor': per}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--ticks', type=int, default=200)
    ap.add_argument('--width', type=int, default=400)
    ap.add_argument('--height', type=int, default=300)
    runner.workload_args(ap)
    args = ap.parse_args(argv)
    out = runner.out_dir(args.out, 'dataset')
    sim = None if args.connect else runner.own_simulation('Town01', args.domain, out, dt=0.05, air=True, cameras=True)
    try:
        import airsim
        ctx = runner.Context(dt=0.05)
        air = airsim.MultirotorClient()
        summary = record(ctx, air, out, args.ticks, args.width, args.height)
        summary['alignment'] = check_alignment(out)
        print(json.dumps(summary))
        return 0 if summary['alignment']['misaligned'] == 0 else 1
    finally:
        if sim is not None:
            sim.stop()


if __name__ == '__main__':
    sys.exit(main())
