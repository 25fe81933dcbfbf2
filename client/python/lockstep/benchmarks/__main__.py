"""lockstep python -m lockstep.benchmarks SUITE [options]   (or: lockstep bench SUITE ...)

Suites:
  corl2017     CARLA's CoRL 2017 benchmark: 4 tasks x Town01/Town02 x weathers 1,3,6,8 / 4,14
  nocrash      NoCrash: empty / regular / dense traffic, any collision fails the episode
  leaderboard  Leaderboard-style routes with the driving score (1.0/2.0 product, 2.1 additive)
  generate     rewrite the episode files (data/corl2017_<town>.json) from the towns' maps

CARLA-Air's workloads and the learning data (each takes its own options, `--help`):
  landing      precision landing of a drone on a moving car (touchdown error over seeded runs)
  dataset      the synchronized multi-modal dataset (KITTI-like) and its alignment check
  joint        the joint workload (100 vehicles, 50 walkers, a drone, 8 sensors) in ticks/s
  crossview    one scene from the ground and the air through the 14 weather presets
  vln          vision-language navigation pairs (instructions, ground and aerial images)
  follow       drone follow with RL (cross-entropy method on DroneFollowEnv)
  collect      imitation-learning data as CIL (noise injection, high-level commands)

Each run starts its own simulation per town (ground_sim + sensors, 10 frames per simulated
second) on --domain, or uses the one running with --connect, and writes to --out:
summary.csv (one line per episode), episodes/*.csv (per-frame measurements), tables.md,
success.csv, km_between_infractions.csv, success.png, results.json.
"""
import argparse
import json
import os
import sys
import time

from . import episodes as episodes_mod
from . import metrics, report, runner

NOCRASH_TRAFFIC = {'Town01': {'Empty': (0, 0), 'Regular': (20, 50), 'Dense': (100, 250)},
                   'Town02': {'Empty': (0, 0), 'Regular': (15, 50), 'Dense': (70, 150)}}
CORL_TRAFFIC = {'Town01': (20, 50), 'Town02': (15, 50)}   # Nav. dynamic: vehicles, pedestrians


def _weathers(text, default):
    if not text:
        return default
    if text == 'train':
        return list(runner.TRAIN_WEATHERS)
    if text == 'test':
        return list(runner.TEST_WEATHERS)
    out = []
    for w in text.split(','):
        w = int(w)
        if w not in runner.WEATHERS:
            raise SystemExit('weather %d: CARLA 0.8 numbers are 1..14' % w)
        out.append(w)
    return out


class Towns:
    """One simulation for the whole run (started with the first town unless --connect);
    each further town is loaded into it with client.load_world, as on a CARLA server."""

    def __init__(self, args):
        self.args = args
        self.cameras = args.agent in runner.CAMERA_AGENTS   # the agent sees through cameras: render runs too
        self.sim = None
        self.ctx = None

    def open(self, town):
        a = self.args
        if self.sim is None and not a.connect:
            os.environ['LOCKSTEP_DOMAIN'] = str(a.domain)
            self.sim = runner.Simulation(town, a.domain, a.out, dt=0.1, seed=a.seed, cameras=self.cameras)
        else:
            import carla
            c = carla.Client('localhost', 2000)
            c.set_timeout(120)
            if c.get_world().get_map().name != os.path.basename(town).replace('.xodr', ''):
                c.load_world(episodes_mod.find_map(town))
        self.ctx = runner.Context(dt=0.1, grid_m=a.grid)
        return self.ctx

    def close(self):
        self.ctx = None
        if self.sim is not None:
            self.sim.stop()
            self.sim = None


def _log(msg):
    print(msg, flush=True)


def _write_summary(out, results):
    report.write_csv(os.path.join(out, 'summary.csv'), results)


def _train_and_all_weathers(args, default_test):
    """The training and test weathers, and every weather to run: training first, then the test ones not in it."""
    train_w = _weathers(args.train_weathers, runner.TRAIN_WEATHERS)
    test_w = _weathers(args.test_weathers, default_test)
    return train_w, test_w, train_w + [w for w in test_w if w not in train_w]


def _value(text):
    for cast in (int, float):
        try:
            return cast(text)
        except ValueError:
            pass
    return {'True': True, 'False': False}.get(text, text)


def _done_episodes(args):
    """--resume: the episodes summary.csv of --out already holds, {(town, task, weather, id): row}."""
    path = os.path.join(args.out, 'summary.csv')
    if not (args.resume and os.path.exists(path)):
        return {}
    import csv
    with open(path, newline='') as f:
        rows = [{k: _value(v) for k, v in r.items()} for r in csv.DictReader(f)]
    return {(r['town'], r['exp_id'], r['weather'], r['episode']): r for r in rows}


def run_corl2017(args):
    agent = runner.make_agent(args.agent, args.ignore_lights)
    train_w, _, weathers = _train_and_all_weathers(args, runner.TEST_WEATHERS)
    tasks = [t for t in report.TASKS if not args.tasks or t in args.tasks.split(',')]
    towns = Towns(args)
    results = []
    done = _done_episodes(args)
    resumed = 0
    started = time.time()
    os.makedirs(os.path.join(args.out, 'episodes'), exist_ok=True)
    try:
        for town in args.towns.split(','):
            doc, eps = episodes_mod.load(town)
            if all((town, t, w, ep['id']) in done for t in tasks for w in weathers for ep in eps[t][:args.episodes]):
                results += [done[(town, t, w, ep['id'])] for t in tasks for w in weathers for ep in eps[t][:args.episodes]]
                resumed += len(tasks) * len(weathers) * len(eps[tasks[0]][:args.episodes])
                continue
            ctx = towns.open(town)
            for task in tasks:
                veh, ped = CORL_TRAFFIC.get(town, (20, 50)) if task == 'Nav. dynamic' else (0, 0)
                for w in weathers:
                    for ep in eps[task][:args.episodes]:
                        if (town, task, w, ep['id']) in done:
                            results.append(done[(town, task, w, ep['id'])])
                            resumed += 1
                            continue
                        log = os.path.join(args.out, 'episodes', '%s_%s_w%d_%02d.csv' % (
                            town, task.replace(' ', '').replace('.', ''), w, ep['id']))
                        r, _ = runner.run_episode(ctx, agent, ep, task=task, weather=w, vehicles=veh, walkers=ped,
                                                  seed=args.seed, log_path=log)
                        r['town'] = town
                        r['agent'] = agent.name
                        results.append(r)
                        _log('%s %-12s w%-2d ep%02d %-8s %6.1f s sim, %5.1f s wall, %.3f km, infractions %s' % (
                            town, task, w, ep['id'], r['end'], r['final_time'], r['wall_s'], r['km'],
                            ','.join('%s=%d' % (metrics.INFRACTION_NAMES[k], r[k]) for k in metrics.INFRACTIONS
                                     if r[k])))
                        _write_summary(args.out, results)
    finally:
        towns.close()
    wall = time.time() - started
    ran = len(results) - resumed
    header = ('%d episodes (%d run now in %.0f s of wall time, %.0f episodes/hour, %d kept from before) on this '
              'machine; towns %s, weathers %s (train %s), %s episode(s) per task and weather; time-out at 10 km/h + '
              '10 s; success within 2 m.'
              % (len(results), ran, wall, 3600.0 * ran / max(wall, 1e-9), resumed, args.towns,
                 ','.join(map(str, weathers)), ','.join(map(str, train_w)), args.episodes))
    success, kms, _ = report.write_corl2017(args.out, results, train_w, agent.name, header)
    print()
    print(header)
    print(report.markdown(success))
    print(report.markdown(kms, ['infraction', 'condition', 'km_driven', 'count', 'ours_km', 'paper_MP_km',
                                'paper_CIL_km', 'paper_RL_km']))
    print('written: %s' % os.path.join(args.out, 'tables.md'))
    print(json.dumps({'suite': 'corl2017', 'agent': agent.name, 'episodes': len(results),
                      'episodes_per_hour': round(3600.0 * ran / max(wall, 1e-9), 1),
                      'success_%': {'%s/%s' % (r['task'], r['condition']): r['ours_%'] for r in success}}))
    return results


def run_nocrash(args):
    agent = runner.make_agent(args.agent, args.ignore_lights)
    train_w, test_w, weathers = _train_and_all_weathers(args, [10, 14])
    levels = [t for t in ('Empty', 'Regular', 'Dense') if not args.tasks or t in args.tasks.split(',')]
    towns = Towns(args)
    results = []
    started = time.time()
    os.makedirs(os.path.join(args.out, 'episodes'), exist_ok=True)
    try:
        for town in args.towns.split(','):
            _, eps = episodes_mod.load(town)
            ctx = towns.open(town)
            for level in levels:
                veh, ped = NOCRASH_TRAFFIC.get(town, NOCRASH_TRAFFIC['Town01'])[level]
                for w in weathers:
                    for ep in eps['Navigation'][:args.episodes]:
                        log = os.path.join(args.out, 'episodes', '%s_%s_w%d_%02d.csv' % (town, level, w, ep['id']))
                        r, _ = runner.run_episode(ctx, agent, ep, task=level, weather=w, vehicles=veh, walkers=ped,
                                                  collision_as_failure=True, seed=args.seed, log_path=log,
                                                  time_out=metrics.time_out_s(ep['route_m'], 5.0, 20.0))
                        r['town'] = town
                        r['agent'] = agent.name
                        results.append(r)
                        _log('%s %-8s w%-2d ep%02d %-9s %6.1f s sim, %5.1f s wall' % (
                            town, level, w, ep['id'], r['end'], r['final_time'], r['wall_s']))
                        _write_summary(args.out, results)
    finally:
        towns.close()
    wall = time.time() - started
    rows = []
    for town in args.towns.split(','):
        for level in levels:
            for split, ws in (('train weathers', train_w), ('new weathers', test_w)):
                rs = [r for r in results if r['town'] == town and r['exp_id'] == level and r['weather'] in ws]
                if not rs:
                    continue
                per_w = {}
                for r in rs:
                    per_w.setdefault(r['weather'], []).append(r['result'])
                paper = report.PAPER_NOCRASH_AUTOPILOT.get(town)
                idx = ('Empty', 'Regular', 'Dense').index(level) * 2 + (0 if split == 'train weathers' else 1)
                rows.append({'town': town, 'traffic': level, 'weathers': split, 'episodes': len(rs),
                             'ours_%': round(100.0 * metrics.success_rate(per_w), 1),
                             'collisions': sum(1 for r in rs if r['end'] == 'collision'),
                             'time_outs': sum(1 for r in rs if r['end'] == 'time-out'),
                             'LBC_autopilot_0.9.6_%': paper[idx] if paper else ''})
    report.write_csv(os.path.join(args.out, 'nocrash.csv'), rows)
    header = '%d episodes in %.0f s (%.0f episodes/hour); agent %s' % (len(results), wall,
                                                                        3600.0 * len(results) / max(wall, 1e-9), agent.name)
    with open(os.path.join(args.out, 'tables.md'), 'w') as f:
        f.write('# NoCrash with agent `%s`\n\n%s\n\n%s' % (agent.name, header, report.markdown(rows)))
    print()
    print(header)
    print(report.markdown(rows))
    print(json.dumps({'suite': 'nocrash', 'agent': agent.name, 'episodes': len(results),
                      'episodes_per_hour': round(3600.0 * len(results) / max(wall, 1e-9), 1)}))
    return results


def run_leaderboard(args):
    from . import leaderboard
    return leaderboard.run(args, Towns(args))


WORKLOADS = ('landing', 'dataset', 'joint', 'crossview', 'vln', 'follow', 'collect')


def main(argv=None):
    argv = sys.argv[1:] if argv is None else list(argv)
    if argv and argv[0] in WORKLOADS:
        import importlib
        return importlib.import_module('lockstep.benchmarks.' + argv[0]).main(argv[1:])
    ap = argparse.ArgumentParser(prog='lockstep bench', description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('suite', choices=['corl2017', 'nocrash', 'leaderboard', 'generate'] + list(WORKLOADS))
    ap.add_argument('--agent', default='autopilot', help='autopilot (Traffic Manager), basic, behavior (CARLA\'s agents), modular (the paper\'s MP baseline)')
    ap.add_argument('--episodes', type=int, default=25, help='episodes per task and weather (at most 25)')
    ap.add_argument('--towns', default='Town01,Town02')
    ap.add_argument('--tasks', default='', help="comma-separated task names (default: all)")
    ap.add_argument('--train-weathers', default='', help="CARLA 0.8 numbers, 'train' or 'test'")
    ap.add_argument('--test-weathers', default='')
    ap.add_argument('--out', default='')
    ap.add_argument('--domain', type=int, default=int(os.environ.get('LOCKSTEP_DOMAIN', '0') or 0))
    ap.add_argument('--connect', action='store_true', help='use the simulation already running (load_world per town)')
    ap.add_argument('--ignore-lights', action='store_true',
                    help='the agent ignores traffic lights (CoRL 2017 allows it; the other cars obey them)')
    ap.add_argument('--resume', action='store_true',
                    help="corl2017: keep the episodes --out's summary.csv already has and run the others")
    ap.add_argument('--grid', type=float, default=0.2, help='footprint sampling step in m (CARLA 0.8: 0.1)')
    ap.add_argument('--seed', type=int, default=0)
    ap.add_argument('--routes', default='', help='leaderboard: a JSON file of routes (default: the Navigation episodes)')
    ap.add_argument('--traffic', default='Regular', help='leaderboard: Empty, Regular or Dense')
    args = ap.parse_args(argv)
    if args.suite == 'generate':
        for town in args.towns.split(','):
            print(episodes_mod.generate(town))
        return 0
    if not 1 <= args.episodes <= 25:
        ap.error('--episodes: 1 to 25')
    if not args.out:
        root = os.path.dirname(runner.build_dir())
        args.out = os.path.join(root, 'out', 'benchmarks', '%s-%s' % (args.suite, args.agent))
    os.makedirs(args.out, exist_ok=True)
    {'corl2017': run_corl2017, 'nocrash': run_nocrash, 'leaderboard': run_leaderboard}[args.suite](args)
    return 0


if __name__ == '__main__':
    sys.exit(main())
