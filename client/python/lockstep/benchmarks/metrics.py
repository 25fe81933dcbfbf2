"""The metrics of CARLA 0.8's driving benchmark (`driving_benchmark/metrics.py`,
`experiment_suite.metrics_parameters`), of NoCrash (`_has_agent_collided`) and of the
Leaderboard's driving score. Pure functions over per-frame measurement rows: no
simulation needed, so the tests can feed them exact sequences.

A measurement row (one per frame, 10 frames per simulated second) has the keys of 0.8's
measurements.csv that the counting reads: `pos_x`, `pos_y` (m), `intersection_offroad`,
`intersection_otherlane` (fractions of the car's footprint, 0..1), `collision_vehicles`,
`collision_pedestrians`, `collision_other` (accumulated |normal impulse| in kg m/s since
the episode began, as 0.8.2 reports them)."""
import math

# experiment_suite.metrics_parameters (CARLA 0.8.4), unchanged.
METRICS_PARAMETERS = {
    'intersection_offroad': {'frames_skip': 10, 'frames_recount': 20, 'threshold': 0.3},
    'intersection_otherlane': {'frames_skip': 10, 'frames_recount': 20, 'threshold': 0.4},
    'collision_other': {'frames_skip': 10, 'frames_recount': 20, 'threshold': 400},
    'collision_vehicles': {'frames_skip': 10, 'frames_recount': 30, 'threshold': 400},
    'collision_pedestrians': {'frames_skip': 5, 'frames_recount': 100, 'threshold': 300},
}

INFRACTIONS = ['intersection_otherlane', 'intersection_offroad', 'collision_other', 'collision_vehicles',
               'collision_pedestrians']
INFRACTION_NAMES = {'intersection_otherlane': 'Opposite lane', 'intersection_offroad': 'Sidewalk',
                    'collision_other': 'Collision-static', 'collision_vehicles': 'Collision-car',
                    'collision_pedestrians': 'Collision-pedestrian'}


def _rise(rows, i, key, skip):
    # rows[i - skip] with Python's wrap-around for i < skip, as 0.8's numpy indexing.
    return rows[i][key] - rows[(i - skip) % len(rows)][key]


def count_out_of_road_lane(rows, p=METRICS_PARAMETERS):
    """(otherlane, offroad) counts: 0.8's `_get_out_of_road_lane`, one shared scan from
    frame 0 that jumps `frames_recount` after each event (an offroad event also skips
    the otherlane test of the frames it jumps over)."""
    lane = side = 0
    i = 0
    n = len(rows)
    off, other = p['intersection_offroad'], p['intersection_otherlane']
    while i < n:
        if _rise(rows, i, 'intersection_offroad', off['frames_skip']) > off['threshold']:
            side += 1
            i += off['frames_recount']
        if i >= n:
            break
        if _rise(rows, i, 'intersection_otherlane', other['frames_skip']) > other['threshold']:
            lane += 1
            i += other['frames_recount']
        i += 1
    return lane, side


def count_collisions(rows, p=METRICS_PARAMETERS):
    """(other, vehicles, pedestrians) counts: 0.8's `_get_collisions`, a scan per kind
    from frame 1."""
    out = []
    for key in ('collision_other', 'collision_vehicles', 'collision_pedestrians'):
        q = p[key]
        count, i = 0, 1
        while i < len(rows):
            if _rise(rows, i, key, q['frames_skip']) > q['threshold']:
                count += 1
                i += q['frames_recount']
            i += 1
        out.append(count)
    return tuple(out)


def distance_km(rows):
    """0.8's `_get_distance_traveled`: the sum of frame-to-frame 2-D displacements."""
    return sum(math.hypot(b['pos_x'] - a['pos_x'], b['pos_y'] - a['pos_y']) for a, b in zip(rows, rows[1:])) / 1000.0


def episode_infractions(rows, dynamic):
    """{infraction key: count} of one episode. Collisions count only in dynamic tasks
    (with vehicles or pedestrians), as 0.8's `dynamic_tasks`; other tasks record 0."""
    lane, side = count_out_of_road_lane(rows)
    if dynamic:
        other, veh, ped = count_collisions(rows)
    else:
        other = veh = ped = 0
    return {'intersection_otherlane': lane, 'intersection_offroad': side, 'collision_other': other,
            'collision_vehicles': veh, 'collision_pedestrians': ped}


# NoCrash's collision-as-failure test (`_has_agent_collided`): the frame-to-frame increase
# of an accumulated impulse above half the counting threshold.
def has_collided(prev, now, p=METRICS_PARAMETERS):
    for key in ('collision_vehicles', 'collision_pedestrians', 'collision_other'):
        if now[key] - prev[key] > p[key]['threshold'] / 2:
            return key
    return None


def time_out_s(route_m, speed_kmh=10.0, margin_s=10.0):
    """`calculate_time_out`: the time at 10 km/h plus 10 s (CoRL 2017); NoCrash: 5 km/h + 20 s."""
    return (route_m / 1000.0) / speed_kmh * 3600.0 + margin_s


def success_rate(results_by_weather):
    """{weather: [0/1 results]} -> the mean per weather averaged equally over the weathers
    (0.8's results_printer)."""
    means = [sum(v) / len(v) for v in results_by_weather.values() if v]
    return sum(means) / len(means) if means else float('nan')


def km_between(km, count):
    """(value, text): Σkm / Σcount; with no infraction, 'more than Σkm' (0.8's printer)."""
    if count == 0:
        return km, '> %.2f' % km
    return km / count, '%.2f' % (km / count)


# ---- Leaderboard driving score ----
# Leaderboard 1.0 / 2.0 penalty coefficients (per infraction, multiplied).
PENALTY = {'collisions_pedestrian': 0.5, 'collisions_vehicle': 0.6, 'collisions_layout': 0.65, 'red_light': 0.7,
           'stop_infraction': 0.8}


def penalty_product(counts, coefficients=PENALTY):
    """Leaderboard 1.0/2.0: the product of p_j ** n_j."""
    out = 1.0
    for k, n in counts.items():
        if k in coefficients:
            out *= coefficients[k] ** n
    return out


def penalty_additive(counts, coefficients=PENALTY):
    """Leaderboard 2.1's form 1 / (1 + Σ_j w_j n_j), with w_j = 1 / p_j - 1, so that one
    infraction costs exactly what it costs in 2.0 and several add up instead of
    multiplying (docs/benchmarks.md)."""
    total = 0.0
    for k, n in counts.items():
        if k in coefficients:
            total += (1.0 / coefficients[k] - 1.0) * n
    return 1.0 / (1.0 + total)


def driving_score(route_completion, counts):
    """{'route_completion', 'penalty_2_0', 'driving_score_2_0', 'penalty_2_1', 'driving_score_2_1'};
    route_completion in 0..1 (percent in the leaderboard's files: x 100)."""
    p0 = penalty_product(counts)
    p1 = penalty_additive(counts)
    return {'route_completion': route_completion, 'penalty_2_0': p0, 'driving_score_2_0': route_completion * p0,
            'penalty_2_1': p1, 'driving_score_2_1': route_completion * p1}
