"""Leaderboard-style routes: drive a route among traffic, score it as CARLA's Leaderboard.

driving score = route completion x infraction penalty, with the penalty in both forms
(metrics.driving_score): Leaderboard 1.0 / 2.0's product of the per-infraction
coefficients (pedestrian 0.5, vehicle 0.6, static 0.65, red light 0.7, stop sign 0.8) and
2.1's additive 1 / (1 + sum). Route completion is the length of the route driven, in
order, up to the car's furthest point within 8 m of it (the route's polyline through its
points), over the route's length; 1 when the goal is reached within 2 m.

Collisions are counted as CARLA 0.8's benchmark counts them (metrics.count_collisions)
and mapped to the Leaderboard's kinds: vehicles -> collisions_vehicle, pedestrians ->
collisions_pedestrian, anything else -> collisions_layout. Red lights and stop signs are
not detected here (their counts stay 0: docs/benchmarks.md).

Routes: the towns' Navigation episodes (data/corl2017_<town>.json) by default, or
--routes FILE, a JSON file in the same shape ({"town": ..., "tasks": {"Routes": [episode,
...]}} with start, goal, route_m and path per episode)."""
import json
import os
import time

from . import episodes as episodes_mod
from . import metrics, report, runner
from .route import RouteProgress

TRAFFIC = {'Town01': {'Empty': (0, 0), 'Regular': (20, 50), 'Dense': (100, 250)},
           'Town02': {'Empty': (0, 0), 'Regular': (15, 50), 'Dense': (70, 150)}}
KIND = {'collision_vehicles': 'collisions_vehicle', 'collision_pedestrians': 'collisions_pedestrian',
        'collision_other': 'collisions_layout'}


def route_completion(episode, rows, max_deviation_m=8.0, success=False):
    """The fraction of the route driven in order (0..1); 1 at the goal."""
    if success:
        return 1.0
    p = RouteProgress(episode, max_deviation_m)
    for r in rows:
        p.update(r['pos_x'], r['pos_y'])
    return p.completion()


def score_route(episode, result, rows):
    other, veh, ped = metrics.count_collisions(rows)
    counts = {'collisions_vehicle': veh, 'collisions_pedestrian': ped, 'collisions_layout': other,
              'red_light': 0, 'stop_infraction': 0}
    rc = route_completion(episode, rows, success=result['result'] == 1)
    s = metrics.driving_score(rc, counts)
    s.update(counts)
    return s


def load_routes(args, town):
    if args.routes:
        doc = json.load(open(args.routes))
        if doc.get('town') not in (None, town):
            return []
        routes = doc['tasks']['Routes'] if 'tasks' in doc else doc['routes']
        for i, r in enumerate(routes):
            for key in ('start', 'goal', 'route_m', 'path'):
                if key not in r:
                    raise ValueError('%s: route %d has no %s' % (args.routes, i, key))
            r.setdefault('id', i)
        return routes
    _, tasks = episodes_mod.load(town)
    return tasks['Navigation']


def run(args, towns):
    agent = runner.make_agent(args.agent, args.ignore_lights)
    if args.traffic not in ('Empty', 'Regular', 'Dense'):
        raise SystemExit('--traffic: Empty, Regular or Dense')
    weather = int((args.train_weathers or '1').split(',')[0]) if args.train_weathers not in ('train', 'test') else 1
    out_rows = []
    started = time.time()
    os.makedirs(os.path.join(args.out, 'episodes'), exist_ok=True)
    try:
        for town in args.towns.split(','):
            routes = load_routes(args, town)[:args.episodes]
            if not routes:
                continue
            ctx = towns.open(town)
            veh, ped = TRAFFIC.get(town, TRAFFIC['Town01'])[args.traffic]
            for ep in routes:
                log = os.path.join(args.out, 'episodes', '%s_route%02d.csv' % (town, ep['id']))
                r, rows = runner.run_episode(ctx, agent, ep, task='Route', weather=weather, vehicles=veh, walkers=ped,
                                             seed=args.seed, log_path=log, dynamic=True)
                s = score_route(ep, r, rows)
                row = {'town': town, 'route': ep['id'], 'route_m': ep['route_m'], 'end': r['end'],
                       'route_completion_%': round(100 * s['route_completion'], 2),
                       'collisions_vehicle': s['collisions_vehicle'], 'collisions_pedestrian': s['collisions_pedestrian'],
                       'collisions_layout': s['collisions_layout'],
                       'penalty_2_0': round(s['penalty_2_0'], 4), 'driving_score_2_0': round(100 * s['driving_score_2_0'], 2),
                       'penalty_2_1': round(s['penalty_2_1'], 4), 'driving_score_2_1': round(100 * s['driving_score_2_1'], 2),
                       'sim_s': r['final_time'], 'wall_s': r['wall_s']}
                out_rows.append(row)
                print('%s route %02d %-8s completion %6.2f%%  DS 2.0 %6.2f  DS 2.1 %6.2f' % (
                    town, ep['id'], r['end'], row['route_completion_%'], row['driving_score_2_0'],
                    row['driving_score_2_1']), flush=True)
                report.write_csv(os.path.join(args.out, 'routes.csv'), out_rows)
    finally:
        towns.close()
    wall = time.time() - started
    n = max(len(out_rows), 1)
    summary = {'suite': 'leaderboard', 'agent': agent.name, 'traffic': args.traffic, 'routes': len(out_rows),
               'route_completion_%': round(sum(r['route_completion_%'] for r in out_rows) / n, 2),
               'driving_score_2_0': round(sum(r['driving_score_2_0'] for r in out_rows) / n, 2),
               'driving_score_2_1': round(sum(r['driving_score_2_1'] for r in out_rows) / n, 2),
               'episodes_per_hour': round(3600.0 * len(out_rows) / max(wall, 1e-9), 1)}
    with open(os.path.join(args.out, 'results.json'), 'w') as f:
        json.dump({'summary': summary, 'routes': out_rows}, f, indent=1)
    with open(os.path.join(args.out, 'tables.md'), 'w') as f:
        f.write('# Leaderboard-style routes, agent `%s`, %s traffic\n\n%s\n%s' % (
            agent.name, args.traffic, report.markdown([summary]), report.markdown(out_rows)))
    print(report.markdown(out_rows))
    print(json.dumps(summary))
    return out_rows
