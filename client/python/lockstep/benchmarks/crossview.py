"""CARLA-Air's cross-view sweep: one scene seen from the ground and from the air through
every weather preset. A car stands on a Town01 street, another 15 m ahead of it; a camera
looks ahead from the first one's bumper, and a drone (the `airsim` API) hovers `--altitude`
m above the car ahead with a camera looking straight down; each
camera has a semantic twin at the same pose. For each of CARLA's 14 weather presets
(carla.WeatherParameters: the 0.8 numbers 1-14 of runner.WEATHERS) the weather is set, the
world ticks `--settle` times, and the four images of the same tick are kept.

    build/bin/lockstep python -m lockstep.benchmarks.crossview --out out/benchmarks/crossview

Writes `<preset>_ground.png`, `<preset>_aerial.png`, `sweep.png` (every preset, ground over
aerial) and `crossview.json`: per preset the tick's frame, each image's frame, the mean
luminance of each view, and the vehicle pixels in each view (semantic tags 14-16: the car
ahead seen from the ground and from the air). CARLA-Air captures through 14 weather presets."""
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

DT = 0.05
VEHICLE_TAGS = (14, 15, 16)


def luminance(bgra):
    a = np.asarray(bgra, dtype=np.float32)
    return float((0.0722 * a[..., 0] + 0.7152 * a[..., 1] + 0.2126 * a[..., 2]).mean())


def sweep(ctx, air, out, presets, width=320, height=240, fov=90.0, altitude=15.0, settle=3, ground_fov=90.0):
    """Captures each preset; returns the per-preset records (and writes the PNGs)."""
    carla = ctx.carla
    from lockstep.carla.sensor_data import write_png
    _, tasks = episodes_mod.load('Town01')
    sx, sy, sz, syaw = tasks['Straight'][0]['start']
    actors, cams = [], {}
    try:
        ego = ctx.world.spawn_actor(ctx.ego_blueprint(), carla.Transform(carla.Location(sx, sy, sz + 0.3),
                                                                         carla.Rotation(yaw=syaw)))
        actors.append(ego)
        # The car both views look at: parked 15 m ahead of the ego in its lane.
        ahead = ctx.map.get_waypoint(ego.get_location()).next(15.0)[0].transform
        car = ctx.world.spawn_actor(ctx.lib.find('vehicle.audi.a2'), carla.Transform(
            ahead.location + carla.Location(z=0.3), ahead.rotation))
        actors.append(car)
        drone, spawn = runner.drone_beside(ctx, carla.Location(ahead.location.x, ahead.location.y, sz), syaw,
                                           'crossview_drone')
        actors.append(drone)
        for _ in range(10):
            ctx.world.tick()
        for v in (ego, car):
            v.apply_control(carla.VehicleControl(hand_brake=True))
        runner.take_off(air, 'crossview_drone')
        c = car.get_location()
        target = runner.ned(spawn, c, altitude)
        # Up over the car: until within 0.3 m of the station above it and nearly at rest.
        for _ in range(int(60 / DT)):
            air.trackTargetAsync(target, (0.0, 0.0, 0.0), 8.0, 1.0, vehicle_name='crossview_drone')
            ctx.world.tick()
            d = drone.get_location()
            if math.hypot(d.x - c.x, d.y - c.y) < 0.3 and abs(d.z - c.z - altitude) < 0.3 and \
                    drone.get_velocity().length() < 0.1:
                break
        else:
            raise RuntimeError('crossview: the drone did not reach its station %.0f m above the car' % altitude)
        # The ground camera just ahead of the ego's bumper (its own bonnet out of view).
        front = ego.bounding_box.extent.x + 0.2
        mounts = {'ground': (ego, carla.Transform(carla.Location(x=front, z=1.4), carla.Rotation(pitch=-5.0)), ground_fov),
                  'aerial': (drone, carla.Transform(carla.Location(z=-0.2), carla.Rotation(pitch=-90.0)), fov)}
        for view, (parent, tf, f) in mounts.items():
            for kind in ('rgb', 'semantic_segmentation'):
                b = ctx.lib.find('sensor.camera.' + kind)
                for k, v in (('image_size_x', width), ('image_size_y', height), ('fov', f)):
                    b.set_attribute(k, str(v))
                cam = ctx.world.spawn_actor(b, tf, attach_to=parent)
                q = queue.Queue()
                cam.listen(q.put)
                cams[(view, kind)] = (cam, q)
                actors.append(cam)
        records = []
        for preset in presets:
            ctx.world.set_weather(getattr(carla.WeatherParameters, preset))
            for _ in range(settle):
                air.trackTargetAsync(target, (0.0, 0.0, 0.0), 8.0, 1.0, vehicle_name='crossview_drone')
                frame = ctx.world.tick()
            got = {}
            for key, (_, q) in cams.items():
                last = None
                while not q.empty():
                    last = q.get_nowait()
                got[key] = last
            rec = {'preset': preset, 'frame': frame}
            for view in ('ground', 'aerial'):
                rgb, sem = got[(view, 'rgb')], got[(view, 'semantic_segmentation')]
                rec[view + '_frame'] = rgb.frame if rgb is not None else None
                rec[view + '_semantic_frame'] = sem.frame if sem is not None else None
                if rgb is None or sem is None:
                    continue
                a = rgb.to_numpy()
                rec[view + '_luminance'] = round(luminance(a), 2)
                tags = np.asarray(sem.to_numpy())[..., 2]
                rec[view + '_car_pixels'] = int(np.isin(tags, VEHICLE_TAGS).sum())
                name = '%s_%s.png' % (preset, view)
                write_png(os.path.join(out, name), np.ascontiguousarray(a[..., [2, 1, 0]]))
                rec[view + '_image'] = name
            records.append(rec)
        return records
    finally:
        for cam, _ in cams.values():
            try:
                cam.stop()
            except Exception:  # noqa: BLE001
                pass
        runner.release(ctx, actors, air, 'crossview_drone')


def contact_sheet(out, records, path, columns=7, dpi=80):
    """Every preset's ground image over its aerial image, in a grid (matplotlib)."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    rows = (len(records) + columns - 1) // columns
    fig, axes = plt.subplots(2 * rows, columns, figsize=(2.2 * columns, 3.4 * rows), squeeze=False)
    for ax in axes.flat:
        ax.axis('off')
    for i, rec in enumerate(records):
        r, c = divmod(i, columns)
        for k, view in enumerate(('ground', 'aerial')):
            if rec.get(view + '_image'):
                axes[2 * r + k][c].imshow(plt.imread(os.path.join(out, rec[view + '_image'])))
        axes[2 * r][c].set_title(rec['preset'], fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--presets', default='', help='comma-separated carla.WeatherParameters presets (default: the 14)')
    ap.add_argument('--width', type=int, default=320)
    ap.add_argument('--height', type=int, default=240)
    ap.add_argument('--altitude', type=float, default=15.0)
    runner.workload_args(ap, connect=False)
    args = ap.parse_args(argv)
    presets = args.presets.split(',') if args.presets else [runner.WEATHERS[k] for k in sorted(runner.WEATHERS)]
    out = runner.out_dir(args.out, 'crossview')
    sim = runner.own_simulation('Town01', args.domain, out, dt=DT, air=True, cameras=True)
    try:
        import airsim
        ctx = runner.Context(dt=DT)
        for p in presets:
            if not hasattr(ctx.carla.WeatherParameters, p):
                raise SystemExit('crossview: no weather preset %s' % p)
        started = time.time()
        records = sweep(ctx, airsim.MultirotorClient(), out, presets, args.width, args.height,
                        altitude=args.altitude)
        aligned = all(r['ground_frame'] == r['aerial_frame'] == r['frame'] == r['ground_semantic_frame'] ==
                      r['aerial_semantic_frame'] for r in records)
        summary = {'workload': 'cross_view_sweep', 'presets': len(records), 'aligned': aligned,
                   'car_in_both_views': all(r.get('ground_car_pixels', 0) > 0 and r.get('aerial_car_pixels', 0) > 0
                                            for r in records),
                   'wall_s': round(time.time() - started, 1), 'image_size': [args.width, args.height]}
        with open(os.path.join(out, 'crossview.json'), 'w') as f:
            json.dump({'summary': summary, 'presets': records}, f, indent=1)
        contact_sheet(out, records, os.path.join(out, 'sweep.png'))
        for r in records:
            print(json.dumps(r))
        print(json.dumps(summary))
        return 0 if aligned else 1
    finally:
        sim.stop()


if __name__ == '__main__':
    sys.exit(main())
