"""CARLA-Air's vision-language navigation data: routes paired with instructions written
from the route's own commands and landmarks, with ground and aerial images along it.

For each route (Town01's CoRL 2017 episodes by default): the lane route of planner.py
(every 2 m, with each point's junction), cut into maneuvers: a junction crossed is a left
turn, a right turn or straight on (the heading from entry to exit, 45 deg), a bend of the
road outside junctions is a bend. Landmarks are what the world shows: a traffic light at a
turn's junction when the ground view 10 m before it sees one (a semantic camera beside the
ground camera, CARLA's TrafficLight class), and at the goal the first object a ray
sideways from the goal meets on the right and on the left (World.cast_ray's labels:
buildings, trees, a fence...). The instruction:

    "Drive along the road for about 90 m. At the second intersection, with traffic lights,
     turn left. Follow the road as it bends right. Stop after about 40 m, with buildings on
     your right."

Keypoints (the start, 10 m before each turn, the goal) get a ground image (a camera 1.6 m
above the road looking along the route) and an aerial image (a camera `--altitude` m
above, looking down, the route's heading up, the route drawn in), rendered on one tick.

    build/bin/lockstep python -m lockstep.benchmarks.vln --routes 5 --out out/benchmarks/vln

Writes `pairs.jsonl` (one route per line: instruction, maneuvers, landmarks, keypoints
with their images and frames) and `images/`."""
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
from .planner import Planner

ORDINALS = ['first', 'second', 'third', 'fourth', 'fifth', 'sixth', 'seventh', 'eighth', 'ninth', 'tenth']
LIGHT_TAG, LIGHT_FRACTION = 7, 2.5e-4   # CARLA's TrafficLight tag; the share of the view that makes a light seen
LABEL_WORDS = {'Buildings': 'buildings', 'Vegetation': 'trees', 'Fences': 'a fence', 'Walls': 'a wall',
               'Poles': 'a pole', 'TrafficSigns': 'a traffic sign', 'Terrain': 'grass', 'Static': 'a street object',
               'Water': 'water', 'Bridge': 'a bridge', 'GuardRail': 'a guard rail', 'Sidewalks': 'the sidewalk'}


def _wrap(d):
    return (d + 180.0) % 360.0 - 180.0


def lane_route(carla_map, episode, step=2.0):
    """[(x, y, yaw_deg, junction_id)] in CARLA's coordinates along the episode's lane route."""
    planner = Planner(carla_map._native, step=step)
    sx, sy, sz = episode['start'][:3]
    gx, gy, gz = episode['goal'][:3]
    start, goal = planner.waypoint(sx, -sy, sz), planner.waypoint(gx, -gy, gz)
    found = planner.search(start, {'g': goal}, max_m=max(3000.0, 3 * episode.get('route_m', 0.0)))
    if 'g' not in found:
        raise RuntimeError('vln: no lane route for episode %s' % episode.get('id'))
    return [(w.pose[0], -w.pose[1], -math.degrees(w.pose[3]), w.junction) for w in found['g'][1]]


def maneuvers(route, bend_deg=45.0):
    """The route's maneuvers in order: dicts with kind ('left', 'right', 'straight' at a
    junction; 'bend_left', 'bend_right' outside), index (first point of it), the distance
    driven before it (m), the junction id."""
    out = []
    cum = [0.0]
    for a, b in zip(route, route[1:]):
        cum.append(cum[-1] + math.hypot(b[0] - a[0], b[1] - a[1]))
    last_end = 0.0
    i = 1
    ref = route[0][2]
    while i < len(route):
        j_id = route[i][3]
        if j_id >= 0 and route[i - 1][3] < 0:
            k = i
            while k < len(route) - 1 and route[k][3] >= 0:
                k += 1
            turn = _wrap(route[min(k, len(route) - 1)][2] - route[i - 1][2])
            kind = 'straight' if abs(turn) < bend_deg else ('right' if turn > 0 else 'left')   # CARLA yaw: clockwise
            out.append({'kind': kind, 'index': i, 'before_m': round(cum[i] - last_end, 1), 'junction': j_id})
            last_end = cum[k]
            ref = route[min(k, len(route) - 1)][2]
            i = k + 1
            continue
        if j_id < 0:
            d = _wrap(route[i][2] - ref)
            if abs(d) > bend_deg:
                out.append({'kind': 'bend_right' if d > 0 else 'bend_left', 'index': i,
                            'before_m': round(cum[i] - last_end, 1), 'junction': -1})
                last_end = cum[i]
                ref += math.copysign(90.0, d)
        i += 1
    return out, cum


def _about(m):
    return max(10, int(round(m / 10.0)) * 10)


def instruction(mans, cum, lights=frozenset(), goal_sides=None):
    """The instruction text from the maneuvers (`lights`: junction ids with traffic lights;
    `goal_sides`: {'right': label or None, 'left': ...} at the goal)."""
    parts = []
    straight_run = 0
    first = True
    since_end = 0.0
    for m in mans:
        if m['kind'] == 'straight':
            straight_run += 1
            continue
        lead = ''
        if first and m['before_m'] > 15 and straight_run == 0:
            parts.append('Drive along the road for about %d m.' % _about(m['before_m']))
        first = False
        if m['kind'] in ('left', 'right'):
            n = straight_run + 1
            where = 'At the %s intersection' % ORDINALS[min(n, len(ORDINALS)) - 1] if n > 1 else \
                'At the next intersection'
            if m['junction'] in lights:
                where += ', with traffic lights,'
            lead = '%s turn %s.' % (where, m['kind'])
        else:
            if straight_run:
                parts.append('Go straight through the next %s.' % (
                    'intersection' if straight_run == 1 else '%d intersections' % straight_run))
            lead = 'Follow the road as it bends %s.' % m['kind'].split('_')[1]
        parts.append(lead)
        straight_run = 0
    if straight_run:
        parts.append('Go straight through the next %s.' % (
            'intersection' if straight_run == 1 else '%d intersections' % straight_run))
    end_idx = mans[-1]['index'] if mans else 0
    since_end = cum[-1] - cum[end_idx]
    stop = 'Stop after about %d m' % _about(since_end)
    sides = [(s, w) for s, w in (goal_sides or {}).items() if w]
    if sides:
        stop += ', with ' + ' and '.join('%s on your %s' % (w, s) for s, w in sides)
    parts.append(stop + '.')
    return ' '.join(parts)


def goal_landmarks(world, carla, route, reach=20.0):
    """{'right': words, 'left': words}: the first object a ray sideways from the goal meets."""
    x, y, yaw, _ = route[-1]
    r = math.radians(yaw)
    names = {v: k for k, v in vars(carla.CityObjectLabel).items() if isinstance(v, int) and not k.startswith('_')}
    out = {}
    for side, sgn in (('right', 1.0), ('left', -1.0)):
        dx, dy = -math.sin(r) * sgn, math.cos(r) * sgn
        a = carla.Location(x + 2.0 * dx, y + 2.0 * dy, 1.5)
        b = carla.Location(x + reach * dx, y + reach * dy, 1.5)
        words = None
        for hit in world.cast_ray(a, b):
            name = names.get(int(hit.label), str(hit.label).split('.')[-1])
            if name in LABEL_WORDS and name != 'Sidewalks':
                words = LABEL_WORDS[name]
                break
        out[side] = words
    return out


def draw_route(img, route, cam_xyz, yaw_deg, fov_deg):
    """Draws the route (red) onto a down-looking camera's RGB image, the camera's yaw up."""
    h, w = img.shape[:2]
    f = w / (2.0 * math.tan(math.radians(fov_deg) / 2.0))
    r = math.radians(yaw_deg)
    fx, fy = math.cos(r), math.sin(r)
    rx, ry = -math.sin(r), math.cos(r)
    cx, cy, cz = cam_xyz
    for x, y, _, _ in route:
        dx, dy = x - cx, y - cy
        u = int(round(w / 2.0 + f * (dx * rx + dy * ry) / cz))
        v = int(round(h / 2.0 - f * (dx * fx + dy * fy) / cz))
        if 1 <= u < w - 1 and 1 <= v < h - 1:
            img[v - 1:v + 2, u - 1:u + 2] = (255, 30, 30)
    return img


def make_pair(ctx, episode, out, cams, altitude=60.0, fov=90.0):
    """One route's pair: the instruction and its keypoint images (cams: the ground and aerial
    rgb cameras with their queues)."""
    carla = ctx.carla
    from lockstep.carla.sensor_data import write_png
    route = lane_route(ctx.map, episode)
    mans, cum = maneuvers(route)
    sides = goal_landmarks(ctx.world, carla, route)
    keys = [('start', 0, None)]
    for m in mans:
        if m['kind'] != 'straight':
            k = m['index']
            while k > 0 and cum[m['index']] - cum[k] < 10.0:
                k -= 1
            keys.append((m['kind'], k, m['junction']))
    keys.append(('goal', len(route) - 1, None))
    kps = []
    lights = set()
    for n, (kind, k, junction) in enumerate(keys):
        x, y, yaw, _ = route[k]
        z = ctx.map.get_waypoint(carla.Location(x, y, 0.0)).transform.location.z
        for view in ('ground', 'ground_semantic'):
            cams[view][0].set_transform(carla.Transform(carla.Location(x, y, z + 1.6), carla.Rotation(yaw=yaw)))
        cams['aerial'][0].set_transform(carla.Transform(carla.Location(x, y, z + altitude),
                                                        carla.Rotation(pitch=-90.0, yaw=yaw)))
        for _ in range(2):
            frame = ctx.world.tick()
        kp = {'kind': kind, 'x': round(x, 2), 'y': round(y, 2), 'yaw': round(yaw, 1), 'route_m': round(cum[k], 1),
              'frame': frame}
        for view, (_, q) in cams.items():
            img = None
            while not q.empty():
                img = q.get_nowait()
            if img is None:
                kp[view + '_frame'] = None
                continue
            if view == 'ground_semantic':
                # A landmark the ground view shows: a traffic light at the junction ahead.
                tags = np.asarray(img.to_numpy())[..., 2]
                kp['ground_semantic_frame'] = img.frame
                kp['traffic_light_pixels'] = int((tags == LIGHT_TAG).sum())
                if junction is not None and junction >= 0 and kp['traffic_light_pixels'] >= LIGHT_FRACTION * tags.size:
                    lights.add(junction)
                continue
            rgb = np.ascontiguousarray(img.to_numpy()[..., [2, 1, 0]])
            if view == 'aerial':
                rgb = draw_route(rgb.copy(), route, (x, y, altitude), yaw, fov)
            name = 'r%02d_%d_%s_%s.png' % (episode['id'], n, kind, view)
            write_png(os.path.join(out, 'images', name), rgb)
            kp[view + '_frame'] = img.frame
            kp[view + '_image'] = 'images/' + name
        kps.append(kp)
    text = instruction(mans, cum, lights, sides)
    return {'route': episode['id'], 'route_m': round(cum[-1], 1), 'instruction': text,
            'maneuvers': [m['kind'] for m in mans], 'lights_at_junctions': len(lights), 'goal_landmarks': sides,
            'start': episode['start'], 'goal': episode['goal'], 'keypoints': kps}


def spawn_cameras(ctx, width, height, fov):
    carla = ctx.carla
    cams = {}
    for view in ('ground', 'aerial', 'ground_semantic'):
        b = ctx.lib.find('sensor.camera.semantic_segmentation' if view == 'ground_semantic' else 'sensor.camera.rgb')
        for k, v in (('image_size_x', width), ('image_size_y', height), ('fov', fov)):
            b.set_attribute(k, str(v))
        cam = ctx.world.spawn_actor(b, carla.Transform(carla.Location(z=500.0)))
        q = queue.Queue()
        cam.listen(q.put)
        cams[view] = (cam, q)
    return cams


def generate(ctx, out, episodes, width=400, height=300, fov=90.0, altitude=60.0):
    os.makedirs(os.path.join(out, 'images'), exist_ok=True)
    cams = spawn_cameras(ctx, width, height, fov)
    pairs = []
    try:
        with open(os.path.join(out, 'pairs.jsonl'), 'w') as f:
            for ep in episodes:
                p = make_pair(ctx, ep, out, cams, altitude, fov)
                f.write(json.dumps(p) + '\n')
                pairs.append(p)
    finally:
        for cam, _ in cams.values():
            cam.stop()
        runner.destroy(ctx, [c for c, _ in cams.values()])
        ctx.world.tick()
    return pairs


def figure(out, pair, path, dpi=80):
    """One pair as a picture: the instruction, and each keypoint's ground view over its aerial view."""
    import textwrap
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    kps = pair['keypoints']
    fig, axes = plt.subplots(2, len(kps), figsize=(2.6 * len(kps), 4.6), squeeze=False)
    for i, k in enumerate(kps):
        for j, view in enumerate(('ground', 'aerial')):
            ax = axes[j][i]
            ax.axis('off')
            if k.get(view + '_image'):
                ax.imshow(plt.imread(os.path.join(out, k[view + '_image'])))
        axes[0][i].set_title('%s, %.0f m' % (k['kind'].replace('_', ' '), k['route_m']), fontsize=8)
    fig.suptitle('\n'.join(textwrap.wrap(pair['instruction'], 110)), fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--routes', type=int, default=5, help='routes of the task (from the first)')
    ap.add_argument('--task', default='Navigation', help="the CoRL 2017 task whose episodes are the routes")
    ap.add_argument('--town', default='Town01')
    ap.add_argument('--altitude', type=float, default=60.0)
    runner.workload_args(ap, connect=False)
    args = ap.parse_args(argv)
    out = runner.out_dir(args.out, 'vln')
    sim = runner.own_simulation(args.town, args.domain, out, dt=0.05, cameras=True)
    try:
        ctx = runner.Context(dt=0.05)
        _, tasks = episodes_mod.load(args.town)
        started = time.time()
        pairs = generate(ctx, out, tasks[args.task][:args.routes], altitude=args.altitude)
        if pairs:
            figure(out, pairs[0], os.path.join(out, 'pair_r%02d.png' % pairs[0]['route']))
        for p in pairs:
            print(json.dumps({'route': p['route'], 'instruction': p['instruction'], 'keypoints': len(p['keypoints'])}))
        aligned = all(k['ground_frame'] == k['aerial_frame'] == k['ground_semantic_frame'] == k['frame']
                      for p in pairs for k in p['keypoints'])
        print(json.dumps({'workload': 'vln_pairs', 'routes': len(pairs), 'keypoints': sum(len(p['keypoints'])
                                                                                          for p in pairs),
                          'aligned': aligned, 'wall_s': round(time.time() - started, 1)}))
        return 0 if aligned else 1
    finally:
        sim.stop()


if __name__ == '__main__':
    sys.exit(main())
