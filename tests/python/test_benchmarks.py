"""lockstep.benchmarks at reduced size: CARLA 0.8's infraction counting on exact frame
sequences, the footprint measurement on CARLA's Town01, and real episodes on a
simulation of our own (ground_sim + sensors on Town01, 10 frames per second) that end by
success, by time-out and by collision, each counted as CARLA's benchmark counts it."""

import contextlib

import pytest

from conftest import DOMAIN, has_service

from lockstep.benchmarks import episodes, metrics, report, runner


def rows_of(**series):
    n = len(next(iter(series.values())))
    keys = ['pos_x', 'pos_y', 'intersection_offroad', 'intersection_otherlane', 'collision_vehicles',
            'collision_pedestrians', 'collision_other']
    return [{k: (series[k][i] if k in series else 0.0) for k in keys} for i in range(n)]


# ---- counting (no simulation) ----

def test_sidewalk_counts_each_rise():
    # 0.8's code counts an event when the footprint rose by > 0.3 within 10 frames, then
    # skips 20 frames: a long stay on the sidewalk is one event (the paper's text speaks of
    # one per 2 s; the code, which the published figures came from, counts rises).
    off = [0.0] * 10 + [1.0] * 100
    assert metrics.count_out_of_road_lane(rows_of(intersection_offroad=off)) == (0, 1)
    # On and off every 3 s (30 frames): each climb counts.
    weave = ([0.0] * 15 + [1.0] * 15) * 4
    assert metrics.count_out_of_road_lane(rows_of(intersection_offroad=weave)) == (0, 4)
    # Below the threshold nothing counts.
    assert metrics.count_out_of_road_lane(rows_of(intersection_offroad=[0.0] * 10 + [0.3] * 100)) == (0, 0)


def test_opposite_lane_threshold_is_0_4():
    assert metrics.count_out_of_road_lane(rows_of(intersection_otherlane=[0.0] * 10 + [0.41] * 15)) == (1, 0)
    assert metrics.count_out_of_road_lane(rows_of(intersection_otherlane=[0.0] * 10 + [0.39] * 15)) == (0, 0)


def test_shared_scan_skips_the_other_test():
    # 0.8 scans offroad and otherlane in one loop: an offroad event jumps 20 frames for both.
    off = [0.0] * 10 + [1.0] * 30
    other = [0.0] * 10 + [0.0, 0.0, 0.0] + [1.0] * 27
    assert metrics.count_out_of_road_lane(rows_of(intersection_offroad=off, intersection_otherlane=other)) == (0, 1)


def test_collision_thresholds_and_recount():
    # Accumulated impulse (kg m/s): +450 at frame 20 is one car collision (> 400 within 10
    # frames), +350 is not; pedestrians count from > 300 within 5 frames.
    veh = [0.0] * 20 + [450.0] * 40
    assert metrics.count_collisions(rows_of(collision_vehicles=veh)) == (0, 1, 0)
    assert metrics.count_collisions(rows_of(collision_vehicles=[0.0] * 20 + [350.0] * 40)) == (0, 0, 0)
    ped = [0.0] * 20 + [310.0] * 10
    assert metrics.count_collisions(rows_of(collision_pedestrians=ped)) == (0, 0, 1)
    # Two hits 40 frames apart: two events (car recount is 30 frames); 25 apart: one.
    assert metrics.count_collisions(rows_of(collision_other=[0.0] * 5 + [500.0] * 40 + [1000.0] * 40)) == (2, 0, 0)
    assert metrics.count_collisions(rows_of(collision_vehicles=[0.0] * 5 + [500.0] * 25 + [1000.0] * 40)) == (0, 1, 0)
    # Collisions count only in dynamic tasks.
    assert metrics.episode_infractions(rows_of(collision_vehicles=veh), dynamic=False)['collision_vehicles'] == 0
    assert metrics.episode_infractions(rows_of(collision_vehicles=veh), dynamic=True)['collision_vehicles'] == 1


def test_collision_as_failure_is_half_the_threshold_in_one_frame():
    a = rows_of(collision_vehicles=[0.0, 201.0, 399.0])
    assert metrics.has_collided(a[0], a[1]) == 'collision_vehicles'
    assert metrics.has_collided(a[1], a[2]) is None
    b = rows_of(collision_pedestrians=[0.0, 151.0])
    assert metrics.has_collided(b[0], b[1]) == 'collision_pedestrians'


def test_km_time_out_success_rate_and_km_between():
    assert metrics.distance_km(rows_of(pos_x=[0.0, 3.0, 3.0], pos_y=[0.0, 4.0, 10.0])) == pytest.approx(0.011)
    assert metrics.time_out_s(770.0) == pytest.approx(770 / 1000 / 10 * 3600 + 10)
    assert metrics.time_out_s(360.0, 5.0, 20.0) == pytest.approx(360 / 1000 / 5 * 3600 + 20)
    # Mean per weather, then the mean of the weathers (not of all episodes).
    assert metrics.success_rate({1: [1, 1, 1, 0], 3: [0, 0]}) == pytest.approx((0.75 + 0.0) / 2)
    assert metrics.km_between(3.0, 4) == (0.75, '0.75')
    assert metrics.km_between(3.0, 0) == (3.0, '> 3.00')


def test_driving_score_both_forms():
    counts = {'collisions_vehicle': 2, 'collisions_pedestrian': 1, 'red_light': 0}
    s = metrics.driving_score(0.8, counts)
    assert s['penalty_2_0'] == pytest.approx(0.6 * 0.6 * 0.5)
    assert s['driving_score_2_0'] == pytest.approx(0.8 * 0.18)
    w = 2 * (1 / 0.6 - 1) + (1 / 0.5 - 1)
    assert s['penalty_2_1'] == pytest.approx(1 / (1 + w))
    assert s['driving_score_2_1'] == pytest.approx(0.8 / (1 + w))
    # One infraction costs the same in both.
    one = metrics.driving_score(1.0, {'collisions_layout': 1})
    assert one['penalty_2_0'] == pytest.approx(one['penalty_2_1']) == pytest.approx(0.65)


def test_tables_per_condition():
    rs = []
    for town, w, result in (('Town01', 1, 1), ('Town01', 3, 0), ('Town01', 3, 1), ('Town01', 4, 0), ('Town02', 1, 1)):
        rs.append({'town': town, 'exp_id': 'Nav. dynamic', 'weather': w, 'result': result, 'km': 0.5,
                   'intersection_otherlane': 1, 'intersection_offroad': 0, 'collision_other': 0,
                   'collision_vehicles': 0, 'collision_pedestrians': 0})
    success, kms, _ = report.corl2017_tables(rs, [1, 3, 6, 8], 'x')
    got = {r['condition']: r['ours_%'] for r in success}
    assert got == {'Training': 75.0, 'New weather': 0.0, 'New town': 100.0}
    lane = [r for r in kms if r['infraction'] == 'Opposite lane' and r['condition'] == 'Training'][0]
    assert (lane['km_driven'], lane['count'], lane['ours_km']) == (1.5, 3, '0.50')
    assert lane['paper_MP_km'] == 10.2


def test_episode_files():
    for town, means in episodes.ROUTE_M.items():
        doc, tasks = episodes.load(town)
        assert set(tasks) == set(report.TASKS)
        for task, mean in means.items():
            eps = tasks[task]
            assert len(eps) == 25
            got = sum(e['route_m'] for e in eps) / 25
            assert abs(got - mean) < 0.02 * mean, (town, task, got)
            for e in eps:
                n = len(e['turns'])
                assert n == 0 if task == 'Straight' else (n == 1 if task == 'One turn' else n >= 1)
                assert e['path'][-1][:2] == pytest.approx(e['goal'][:2], abs=0.01)


# ---- the footprint on CARLA's Town01 (no simulation) ----

@pytest.fixture(scope='module')
def town01():
    import carla
    from lockstep import Map
    return carla.Map(Map.load(episodes.find_map('Town01')), 'Town01')


def test_footprint_on_road_other_lane_and_sidewalk(town01):
    import carla
    wp = town01.get_waypoint(carla.Location(249.0, 2.0, 0.0))   # Town01's long straight by y = 2
    assert not wp.is_junction
    foot = runner.Footprint(town01, carla.Vector3D(2.0, 0.9, 0.8), 0.1)
    assert len(foot.samples) == 40 * 18
    t = wp.transform
    assert foot.measure(t) == (0.0, 0.0)
    # Same place, heading the other way: the whole car is on a lane that opposes it.
    backwards = carla.Transform(t.location, carla.Rotation(yaw=t.rotation.yaw + 180.0))
    off, other = foot.measure(backwards)
    assert off == 0.0 and other == 1.0
    # On the other lane in its own direction: all fine again.
    left = wp.get_left_lane()
    assert left is not None and left.lane_id * wp.lane_id < 0
    lt = left.transform
    assert foot.measure(lt) == (0.0, 0.0)
    assert foot.measure(carla.Transform(lt.location, t.rotation))[1] == 1.0
    # Moved sideways off the road (past the shoulder, onto the sidewalk): off-road.
    right = wp.transform.get_right_vector()
    side = carla.Transform(t.location + right * (wp.lane_width / 2 + 4.0), t.rotation)
    off, other = foot.measure(side)
    assert off == 1.0 and other == 0.0


# ---- episodes on a simulation ----

needs_ground = pytest.mark.skipif(not (has_service('ground_sim') and has_service('sensors')),
                                  reason='needs lockstep_ground_sim and lockstep_sensors')


@pytest.fixture(scope='module')
def ctx(tmp_path_factory):
    sim = runner.Simulation('Town01', DOMAIN, str(tmp_path_factory.mktemp('bench')), dt=0.1)
    try:
        yield runner.Context(dt=0.1, grid_m=0.2)
    finally:
        sim.stop()


def straight_episode(ctx, length=60.0, index=5):
    m = ctx.map
    wp = m.get_waypoint(m.get_spawn_points()[index].location)
    goal = wp.next(length)[0]
    assert abs(goal.transform.location.y - wp.transform.location.y) < 0.1, 'pick a spawn point on a long straight'
    t, g = wp.transform, goal.transform
    return {'id': 0, 'start': [t.location.x, t.location.y, t.location.z, t.rotation.yaw],
            'goal': [g.location.x, g.location.y, g.location.z, g.rotation.yaw], 'route_m': length,
            'path': [[g.location.x, g.location.y, g.location.z]]}, wp


@contextlib.contextmanager
def parked_ahead(ctx, wp, metres=25.0):
    """A car parked in the lane of waypoint `wp`, `metres` ahead of it, for the block."""
    import carla
    ahead = wp.next(metres)[0].transform
    parked = ctx.world.spawn_actor(ctx.lib.find('vehicle.audi.a2'),
                                   carla.Transform(ahead.location + carla.Location(z=0.3), ahead.rotation))
    try:
        ctx.world.tick()
        yield parked
    finally:
        parked.destroy()
        ctx.world.tick()


class Throttle:
    """Full speed ahead: no brakes for what is in front."""
    name = 'throttle'

    def __init__(self, steer=0.0):
        self.steer = steer

    def setup(self, ctx, ego, episode):
        pass

    def step(self, ego):
        import carla
        c = carla.VehicleControl(throttle=0.8, steer=self.steer)
        ego.apply_control(c)
        return c


@needs_ground
def test_episode_ends_by_success(ctx):
    ep, _ = straight_episode(ctx)
    r, rows = runner.run_episode(ctx, runner.make_agent('autopilot'), ep, task='Straight', weather=1)
    assert r['end'] == 'success' and r['result'] == 1
    assert r['final_distance'] < 2.0 and rows[-1]['distance_to_goal'] < 2.0
    assert all(x['distance_to_goal'] >= 2.0 for x in rows[:-1])     # it ended at the first frame within 2 m
    assert r['final_time'] < r['time_out'] == pytest.approx(metrics.time_out_s(60.0))
    assert r['km'] == pytest.approx(0.058, abs=0.004)                 # about the 60 m less the last 2
    assert all(r[k] == 0 for k in metrics.INFRACTIONS)


@needs_ground
def test_episode_ends_by_time_out(ctx):
    ep, _ = straight_episode(ctx)
    r, rows = runner.run_episode(ctx, runner.make_agent('autopilot'), ep, task='Straight', weather=3, time_out=3.0)
    assert r['end'] == 'time-out' and r['result'] == 0
    assert r['final_time'] == 3.0
    # Frames at 0.1 s: the episode ends at the first frame past 3 s (frame 31).
    assert len(rows) == 31 and rows[-1]['time_s'] == pytest.approx(3.1, abs=1e-6)
    assert r['final_distance'] > 2.0


@needs_ground
def test_episode_ends_by_collision_and_counts_it(ctx):
    ep, wp = straight_episode(ctx)
    with parked_ahead(ctx, wp):
        # NoCrash: the collision ends the episode.
        r, rows = runner.run_episode(ctx, Throttle(), ep, task='Regular', weather=1, collision_as_failure=True,
                                     dynamic=True)
        assert r['end'] == 'collision' and r['result'] == 0 and r['collided_as_failure']
        assert rows[-1]['collision_vehicles'] - rows[-2]['collision_vehicles'] > 200.0
        assert rows[-1]['collision_other'] == 0.0 and rows[-1]['collision_pedestrians'] == 0.0
        assert r['collision_vehicles'] == 1 and r['collision_other'] == 0


class HitAndBrake(Throttle):
    """Full throttle into the car ahead, full brake from the moment they touch."""

    def __init__(self, other):
        super().__init__()
        self.other = other
        self.hit = False

    def step(self, ego):
        import carla
        touch = ego.bounding_box.extent.x + self.other.bounding_box.extent.x + 0.8
        self.hit = self.hit or ego.get_location().distance(self.other.get_location()) < touch
        if self.hit:
            c = carla.VehicleControl(throttle=0.0, brake=1.0)
        else:
            c = carla.VehicleControl(throttle=0.8)
        ego.apply_control(c)
        return c


@needs_ground
def test_collision_counted_in_a_dynamic_task(ctx):
    ep, wp = straight_episode(ctx)
    with parked_ahead(ctx, wp) as parked:
        # CoRL 2017: infractions never end an episode. One hit, then the brake: one car collision.
        r, rows = runner.run_episode(ctx, HitAndBrake(parked), ep, task='Nav. dynamic', weather=1, dynamic=True,
                                     time_out=8.0)
        assert r['end'] == 'time-out'
        assert max(x['collision_vehicles'] for x in rows) > 400.0
        assert r['collision_vehicles'] == 1
        assert r['collision_other'] == 0 and r['collision_pedestrians'] == 0
        # The same frames in a task without traffic record no collision (0.8's dynamic_tasks).
        assert metrics.episode_infractions(rows, dynamic=False)['collision_vehicles'] == 0
    # Pushing a car along for seconds is contact all the time: 0.8 counts it again after
    # each 30-frame recount while the impulse keeps rising by > 400 per 10 frames.
    with parked_ahead(ctx, wp):
        r, rows = runner.run_episode(ctx, Throttle(), ep, task='Nav. dynamic', weather=1, dynamic=True, time_out=8.0)
        hits = [i for i in range(1, len(rows)) if rows[i]['collision_vehicles'] > rows[i - 1]['collision_vehicles']]
        assert len(hits) > 15 and hits[-1] - hits[0] > 30
        assert r['collision_vehicles'] >= 2


@needs_ground
def test_driving_onto_the_sidewalk_is_counted(ctx):
    ep, _ = straight_episode(ctx)
    r, rows = runner.run_episode(ctx, Throttle(steer=0.25), ep, task='Straight', weather=1, time_out=6.0)
    assert r['end'] == 'time-out'
    assert max(x['intersection_offroad'] for x in rows) > 0.9
    assert r['intersection_offroad'] >= 1


# ---- the command (no simulation) ----

def test_lockstep_bench_runs_the_benchmarks_package():
    # `lockstep bench SUITE ...` is `lockstep python -m lockstep.benchmarks SUITE ...`; the
    # workloads' names run their own modules.
    import os
    import subprocess
    from conftest import BIN
    exe = os.path.join(BIN, 'lockstep')
    r = subprocess.run([exe, 'bench', 'corl2017', '--episodes', '0'], capture_output=True, text=True, timeout=60)
    assert r.returncode == 2 and 'lockstep bench: error: --episodes: 1 to 25' in r.stderr, r
    r = subprocess.run([exe, 'bench', '--help'], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0 and r.stdout.startswith('usage: lockstep bench') and 'corl2017' in r.stdout, r
    r = subprocess.run([exe, 'bench', 'vln', '--help'], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0 and '--routes' in r.stdout and 'vision-language' in r.stdout, r


# ---- Leaderboard-style routes (no simulation) ----

def test_route_completion_and_score():
    from lockstep.benchmarks import leaderboard
    ep = {'start': [0.0, 0.0, 0.0, 0.0], 'goal': [100.0, 0.0, 0.0, 0.0], 'route_m': 100.0,
          'path': [[50.0, 0.0, 0.0], [100.0, 0.0, 0.0]]}
    drive = [{'pos_x': float(x), 'pos_y': 0.5} for x in range(0, 41)]
    assert leaderboard.route_completion(ep, drive) == pytest.approx(0.40)
    # Off the route (20 m aside) nothing counts; going back does not undo progress.
    aside = drive + [{'pos_x': 90.0, 'pos_y': 20.0}] + [{'pos_x': 10.0, 'pos_y': 0.0}]
    assert leaderboard.route_completion(ep, aside) == pytest.approx(0.40)
    assert leaderboard.route_completion(ep, drive, success=True) == 1.0
    # A car collision (> 400 within 10 frames) on 40% of the route: 0.4 x 0.6 (2.0) = 0.4 x 1/(1+2/3) (2.1).
    rows = [dict(r, intersection_offroad=0.0, intersection_otherlane=0.0, collision_vehicles=0.0 if i < 20 else 500.0,
                 collision_pedestrians=0.0, collision_other=0.0) for i, r in enumerate(drive)]
    s = leaderboard.score_route(ep, {'result': 0}, rows)
    assert s['collisions_vehicle'] == 1
    assert s['driving_score_2_0'] == pytest.approx(0.4 * 0.6)
    assert s['driving_score_2_1'] == pytest.approx(0.4 * 0.6)


def test_route_progress_follows_collinear_segments():
    # A car past the end of the first segment is on the next one: the progress follows it
    # (it stuck at segment ends once, giving 0 progress rewards between route points).
    from lockstep.benchmarks.route import RouteProgress
    ep = {'start': [0.0, 0.0], 'path': [[20.0, 0.0], [40.0, 0.0], [60.0, 0.0]]}
    p = RouteProgress(ep)
    assert p.update(5.0, 0.3) == pytest.approx(55.0)
    assert p.update(25.0, 0.3) == pytest.approx(35.0)
    assert p.update(47.5, -0.5) == pytest.approx(12.5)
    assert p.update(10.0, 0.0) == pytest.approx(12.5)
    assert p.completion() == pytest.approx(47.5 / 60)
