"""Imitation-learning data collection as in CIL (Codevilla et al. 2018, "End-to-end
driving via conditional imitation learning"): an expert drives the CoRL 2017 routes, a
camera records, every frame is stored with the expert's control and the route's
high-level command (follow lane, left, right, straight), and noise is injected into the
steering so that the data shows recoveries: the car is driven by the noisy control while
the expert's own control is what is recorded.

Noise (CIL §5): now and then (about a fifth of the time) a triangular impulse on the
steering, rising to a random peak (±0.1..0.35) and back over 0.5 to 2 s; the expert
(CARLA's BasicAgent, unmodified) keeps computing its control from where the car really is.

    build/bin/lockstep python -m lockstep.benchmarks.collect --episodes 4 --out out/cil

Writes `images/<episode>_<frame>.png` (the camera, 200x88 as CIL's network input,
fov 100 at (2.0, 0, 1.4) pitched -15° as CoRL 2017's camera) and `measurements.csv`: episode,
frame, image, command (CIL's codes 2 follow lane, 3 left, 4 right, 5 straight), the
expert's steer / throttle / brake, the applied steer, noise (0/1), speed (km/h), x, y, yaw."""
import argparse
import csv
import json
import math
import os
import queue
import random
import sys

import numpy as np

from . import episodes as episodes_mod
from . import runner
from .route import RouteProgress, command

CIL_CODES = {0: 2, 1: 3, 2: 4, 3: 5}   # our command -> CIL's (follow, left, right, straight)


class SteeringNoise:
    """Triangular steering impulses at random times (seeded)."""

    def __init__(self, rng, dt, fraction=0.2, peak=(0.1, 0.35), duration_s=(0.5, 2.0)):
        self.rng, self.dt = rng, dt
        self.peak, self.duration = peak, duration_s
        mean_len = sum(duration_s) / 2.0
        # Start probability per frame so that impulses cover about `fraction` of the frames.
        self.p_start = fraction * dt / (mean_len * (1.0 - fraction))
        self.t = self.length = self.amp = 0.0

    def __call__(self):
        if self.length <= 0.0 and self.rng.random() < self.p_start:
            self.length = self.rng.uniform(*self.duration)
            self.amp = self.rng.uniform(*self.peak) * self.rng.choice((-1.0, 1.0))
            self.t = 0.0
        if self.length <= 0.0:
            return 0.0
        x = self.t / self.length
        value = self.amp * (2 * x if x < 0.5 else 2 * (1 - x))
        self.t += self.dt
        if self.t >= self.length:
            self.length = 0.0
        return value


def collect_episode(ctx, ep, out, rng, writer, max_frames=None, noise_fraction=0.2, width=200, height=88):
    carla = ctx.carla
    agent = runner.CarlaAgent('basic')
    sx, sy, sz, syaw = ep['start']
    ego = ctx.world.spawn_actor(ctx.ego_blueprint(), carla.Transform(carla.Location(sx, sy, sz + 0.3),
                                                                     carla.Rotation(yaw=syaw)))
    b = ctx.lib.find('sensor.camera.rgb')
    for k, v in (('image_size_x', width), ('image_size_y', height), ('fov', 100)):
        b.set_attribute(k, str(v))
    cam = ctx.world.spawn_actor(b, carla.Transform(carla.Location(x=2.0, z=1.4), carla.Rotation(pitch=-15.0)),
                                attach_to=ego)
    images = queue.Queue()
    stats = {'frames': 0, 'noisy': 0, 'commands': {}}
    try:
        for _ in range(10):
            ctx.world.tick()
        agent.setup(ctx, ego, ep)
        cam.listen(images.put)
        progress = RouteProgress(ep)
        noise = SteeringNoise(rng, ctx.dt, noise_fraction)
        limit = runner.metrics.time_out_s(ep['route_m'])
        frames = 0
        while frames * ctx.dt < limit and (max_frames is None or frames < max_frames):
            expert = agent.agent.run_step()
            n = noise()
            applied = carla.VehicleControl(throttle=expert.throttle, brake=expert.brake,
                                           steer=float(np.clip(expert.steer + n, -1.0, 1.0)))
            ego.apply_control(applied)
            frame = ctx.world.tick()
            img = None
            while not images.empty():
                img = images.get_nowait()
            if img is None or img.frame != frame:
                raise RuntimeError('camera sample of frame %s missing at frame %d' % (img and img.frame, frame))
            tr = ego.get_transform()
            progress.update(tr.location.x, tr.location.y)
            cmd = CIL_CODES[command(progress, ctx.map, tr.location.x, tr.location.y, carla.Location)]
            name = '%03d_%06d.png' % (ep['id'], frame)
            from lockstep.carla.sensor_data import write_png
            write_png(os.path.join(out, 'images', name), np.ascontiguousarray(img.to_numpy()[..., [2, 1, 0]]))
            writer.writerow({'episode': ep['id'], 'frame': frame, 'image': name, 'command': cmd,
                             'steer': round(expert.steer, 5), 'throttle': round(expert.throttle, 5),
                             'brake': round(expert.brake, 5), 'applied_steer': round(applied.steer, 5),
                             'noise': int(n != 0.0), 'speed_kmh': round(ego.get_velocity().length() * 3.6, 3),
                             'x': round(tr.location.x, 3), 'y': round(tr.location.y, 3),
                             'yaw': round(tr.rotation.yaw, 3)})
            frames += 1
            stats['noisy'] += int(n != 0.0)
            stats['commands'][cmd] = stats['commands'].get(cmd, 0) + 1
            if math.hypot(tr.location.x - ep['goal'][0], tr.location.y - ep['goal'][1]) < 2.0:
                break
        stats['frames'] = frames
        return stats
    finally:
        try:
            cam.stop()
        except Exception:  # noqa: BLE001
            pass
        runner.destroy(ctx, [cam, ego])
        ctx.world.tick()


FIELDS = ['episode', 'frame', 'image', 'command', 'steer', 'throttle', 'brake', 'applied_steer', 'noise',
          'speed_kmh', 'x', 'y', 'yaw']


def collect(ctx, out, episodes, seed=0, max_frames=None, noise_fraction=0.2):
    os.makedirs(os.path.join(out, 'images'), exist_ok=True)
    rng = random.Random(seed)
    total = {'frames': 0, 'noisy': 0, 'commands': {}}
    with open(os.path.join(out, 'measurements.csv'), 'w', newline='') as f:
        w = csv.DictWriter(f, fieldnames=FIELDS)
        w.writeheader()
        for ep in episodes:
            s = collect_episode(ctx, ep, out, rng, w, max_frames, noise_fraction)
            total['frames'] += s['frames']
            total['noisy'] += s['noisy']
            for k, v in s['commands'].items():
                total['commands'][k] = total['commands'].get(k, 0) + v
    return total


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--episodes', type=int, default=4, help='CoRL 2017 Navigation episodes of Town01')
    ap.add_argument('--seed', type=int, default=0)
    ap.add_argument('--noise', type=float, default=0.2, help='fraction of frames with steering noise')
    runner.workload_args(ap, connect=False)
    args = ap.parse_args(argv)
    out = runner.out_dir(args.out, 'cil')
    sim = runner.own_simulation('Town01', args.domain, out, dt=0.1, cameras=True)
    try:
        ctx = runner.Context(dt=0.1)
        _, tasks = episodes_mod.load('Town01')
        total = collect(ctx, out, tasks['Navigation'][:args.episodes], args.seed, noise_fraction=args.noise)
        print(json.dumps(total))
        return 0
    finally:
        sim.stop()


if __name__ == '__main__':
    sys.exit(main())
