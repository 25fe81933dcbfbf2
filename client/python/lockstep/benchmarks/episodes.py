"""The benchmark episodes: start and goal poses with their route, stored as data files
(`data/<suite>_<town>.json`), generated once by `generate()` (deterministic: the map, the
spawn points of Lockstep's map library and a fixed seed decide everything).

CARLA 0.8's CoRL 2017 pairs index the 0.8 levels' `player_start_spots`, which the 0.9
OpenDRIVE towns do not have (../shared/reference/corl2017.md §4). So the episodes are
defined on the town's own spawn points (`carla.Map.get_spawn_points()`) with the paper's
mean route lengths and the tasks' shapes:

| task | route | Town01 | Town02 |
|---|---|---|---|
| Straight | no turn at any junction | 200 m | 100 m |
| One turn | exactly one turn | 400 m | 170 m |
| Navigation | any route with at least one turn | 770 m | 360 m |
| Nav. dynamic | Navigation's episodes, with traffic | 770 m | 360 m |

Candidates are every (start, goal) pair of spawn points whose shortest lane route (the
planner of planner.py) has the task's shape and a length within ±25% of the mean; 25 are
drawn with a seeded random generator, preferring distinct start points, then the draw is
swapped pair by pair towards the paper's mean (the stored mean is printed and kept in
the file).

    build/bin/lockstep python -m lockstep.benchmarks generate   # rewrites data/*.json
"""
import json
import math
import os
import random

from .planner import Planner, junctions_crossed, path_points, to_carla, turns

DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), 'data')

TASKS = ['Straight', 'One turn', 'Navigation', 'Nav. dynamic']
ROUTE_M = {'Town01': {'Straight': 200.0, 'One turn': 400.0, 'Navigation': 770.0},
           'Town02': {'Straight': 100.0, 'One turn': 170.0, 'Navigation': 360.0}}
EPISODES_PER_TASK = 25
SEED = 2017


def maps_dirs():
    here = os.path.dirname(os.path.abspath(__file__))
    dirs = [d for d in os.environ.get('LOCKSTEP_MAPS_PATH', '').split(':') if d]
    # build/python/lockstep/benchmarks -> build/maps/generated, <root>/../shared/maps/carla
    build = os.path.dirname(os.path.dirname(os.path.dirname(here)))
    root = os.path.dirname(build)
    src_root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(here))))
    dirs += [os.path.join(build, 'maps', 'generated'), os.path.join(root, '..', 'shared', 'maps', 'carla'),
             os.path.join(src_root, '..', 'shared', 'maps', 'carla'), os.path.join(src_root, 'build', 'maps', 'generated')]
    return dirs


def find_map(town):
    if town.endswith('.xodr') and os.path.exists(town):
        return os.path.abspath(town)
    for d in maps_dirs():
        p = os.path.join(d, town + '.xodr')
        if os.path.exists(p):
            return os.path.abspath(p)
    raise FileNotFoundError('map %s.xodr not found in %s (set LOCKSTEP_MAPS_PATH)' % (town, ':'.join(maps_dirs())))


def _shape_ok(task, path):
    t = turns(path)
    if task == 'Straight':
        return len(t) == 0
    if task == 'One turn':
        return len(t) == 1
    return len(t) >= 1


def _candidates(planner, spawns, targets):
    """Every (start, goal, length, path) pair whose length is within ±25% of some target."""
    lo = min(targets.values()) * 0.75
    hi = max(targets.values()) * 1.25
    wps = [planner.waypoint(p[0], p[1], p[2]) for p in spawns]
    out = []
    for i, w in enumerate(wps):
        goals = {j: g for j, g in enumerate(wps) if j != i and g is not None}
        found = planner.search(w, goals, max_m=hi)
        for j, (d, path) in sorted(found.items()):
            if lo <= d <= hi:
                out.append((i, j, d, path))
    return out


def _pick(rng, cands, target, n):
    """n candidates, distinct starts first, then swapped towards the target mean."""
    cands = list(cands)
    rng.shuffle(cands)
    chosen, used = [], set()
    for c in cands:
        if len(chosen) < n and c[0] not in used:
            chosen.append(c)
            used.add(c[0])
    for c in cands:
        if len(chosen) < n and c not in chosen:
            chosen.append(c)
    rest = [c for c in cands if c not in chosen]
    # Greedy swaps that bring the mean nearer the target, in a fixed order.
    for _ in range(200):
        mean = sum(c[2] for c in chosen) / max(len(chosen), 1)
        err = mean - target
        if abs(err) < 1.0 or not rest:
            break
        best = None
        for a, ca in enumerate(chosen):
            for b, cb in enumerate(rest):
                new_err = err + (cb[2] - ca[2]) / len(chosen)
                if abs(new_err) < abs(err) - 1e-9 and (best is None or abs(new_err) < best[0]):
                    best = (abs(new_err), a, b)
        if best is None:
            break
        _, a, b = best
        chosen[a], rest[b] = rest[b], chosen[a]
    return chosen


def generate(town, out_dir=DATA, seed=SEED, verbose=True):
    from lockstep._lockstep import Map as NativeMap
    path = find_map(town)
    native = NativeMap.load(path)
    spawns = native.spawn_points(25.0)   # carla.Map.get_spawn_points() of this town, in ENU
    planner = Planner(native)
    targets = ROUTE_M[town]
    cands = _candidates(planner, spawns, targets)
    rng = random.Random('%s-%d' % (town, seed))
    tasks = {}
    for task in ('Straight', 'One turn', 'Navigation'):
        t = targets[task]
        ok = [c for c in cands if 0.75 * t <= c[2] <= 1.25 * t and _shape_ok(task, c[3])]
        if len(ok) < EPISODES_PER_TASK:
            raise RuntimeError('%s %s: only %d candidate routes' % (town, task, len(ok)))
        picked = _pick(rng, ok, t, EPISODES_PER_TASK)
        eps = []
        for k, (i, j, d, p) in enumerate(picked):
            eps.append({'id': k, 'start_index': i, 'goal_index': j,
                        'start': to_carla(spawns[i]), 'goal': to_carla(p[-1].pose),
                        'route_m': round(d, 2), 'turns': turns(p), 'junctions': junctions_crossed(p),
                        'path': path_points(p)})
        tasks[task] = eps
        if verbose:
            print('%s %-10s %3d candidates, 25 picked, mean route %.1f m (paper %.0f m)'
                  % (town, task, len(ok), sum(e['route_m'] for e in eps) / len(eps), t))
    tasks['Nav. dynamic'] = tasks['Navigation']
    doc = {'suite': 'corl2017', 'town': town, 'map': os.path.basename(path), 'seed': seed,
           'spawn_points': len(spawns), 'generator': 'lockstep.benchmarks.episodes.generate',
           'paper_mean_route_m': targets,
           'mean_route_m': {k: round(sum(e['route_m'] for e in v) / len(v), 1) for k, v in tasks.items()},
           'tasks': {k: v for k, v in tasks.items() if k != 'Nav. dynamic'}}
    os.makedirs(out_dir, exist_ok=True)
    out = os.path.join(out_dir, 'corl2017_%s.json' % town)
    with open(out, 'w') as f:
        json.dump(doc, f, indent=1)
        f.write('\n')
    return out


def load(town, suite='corl2017'):
    """The episodes of a town: {task: [episode dict]} (Nav. dynamic = Navigation's)."""
    p = os.path.join(DATA, 'corl2017_%s.json' % town)
    if not os.path.exists(p):
        raise FileNotFoundError('no episodes for %s (%s): run `lockstep python -m lockstep.benchmarks generate`' % (town, p))
    doc = json.load(open(p))
    tasks = dict(doc['tasks'])
    tasks['Nav. dynamic'] = tasks['Navigation']
    return doc, tasks


def euclid(a, b):
    return math.hypot(a[0] - b[0], a[1] - b[1])
