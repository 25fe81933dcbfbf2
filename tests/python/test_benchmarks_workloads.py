"""CARLA-Air's other workloads at reduced size: the cross-view weather sweep, the
vision-language navigation pairs and drone follow with RL (lockstep.benchmarks.crossview,
.vln, .follow), on one simulation (ground_sim, air_sim, sensors, render; 20 ticks per
simulated second); their text and learning parts on exact inputs first."""
import math

import numpy as np
import pytest

from conftest import DOMAIN, has_service

from lockstep.benchmarks import follow, vln


def synthetic_route():
    """100 m east, a left turn through junction 5 (radius 6 m), 50 m, straight through junction 7, 40 m."""
    r = []
    x = y = 0.0
    for _ in range(50):
        r.append((x, y, 0.0, -1))
        x += 2.0
    for k in range(1, 6):
        a = math.radians(k * 18.0)
        r.append((x + 6 * math.sin(a), y - 6 * (1 - math.cos(a)), -k * 18.0, 5))   # CARLA: left = yaw down
    x, y = x + 6.0, y - 6.0
    for j, n in ((-1, 25), (7, 5), (-1, 20)):
        for _ in range(n):
            y -= 2.0
            r.append((x, y, -90.0, j))
    return r


def test_instruction_from_the_routes_commands_and_landmarks():
    mans, cum = vln.maneuvers(synthetic_route())
    assert [m['kind'] for m in mans] == ['left', 'straight']
    text = vln.instruction(mans, cum, lights={5}, goal_sides={'right': 'buildings', 'left': None})
    assert text == ('Drive along the road for about 100 m. At the next intersection, with traffic lights, turn left. '
                    'Go straight through the next intersection. Stop after about 50 m, with buildings on your right.')
    # Mirrored (y -> -y, yaw -> -yaw): a right turn, and no lights named where there are none.
    mirrored = [(x, -y, -yaw, j) for x, y, yaw, j in synthetic_route()]
    mans, cum = vln.maneuvers(mirrored)
    assert [m['kind'] for m in mans] == ['right', 'straight']
    assert 'At the next intersection turn right.' in vln.instruction(mans, cum)


def test_follow_reward_and_cem():
    r, terms = follow.follow_reward(3.0, False)
    assert r == pytest.approx(-0.3) and terms == {'distance': -0.3, 'lost': 0.0}
    # Lost with 50 ticks left: the 20 m limit's cost for each of them, more than following at 19 m.
    assert follow.follow_reward(25.0, True, 50)[1]['lost'] == pytest.approx(-100.0)
    assert follow.follow_reward(25.0, True, 50)[0] < 51 * follow.follow_reward(19.0, False)[0]
    # The cross-entropy method finds the top of a quadratic.
    best, hist = follow.cem(lambda t: -float(np.sum((t - np.array([1.0, -2.0, 0.5])) ** 2)), [0, 0, 0], [2, 2, 2],
                            12, 16, 4, np.random.default_rng(0))
    assert np.allclose(best, [1.0, -2.0, 0.5], atol=0.15)
    assert hist[-1]['mean_return'] > hist[0]['mean_return']
    # The gains policy: catch up forwards, come down, match the car's speed.
    act = follow.gains_policy([0.5, 1.0, 0.4], max_speed=10.0)
    assert np.allclose(act(np.array([-4.0, 0.0, 2.0, 5.0, 0.0, 0.0, 0, 0, 0])), [0.7, 0.0, -0.08])


# ---- on a simulation ----

needs = pytest.mark.skipif(not all(has_service(k) for k in ('ground_sim', 'air_sim', 'sensors', 'render')),
                           reason='needs lockstep_ground_sim, lockstep_air_sim, lockstep_sensors and lockstep_render')


@pytest.fixture(scope='module')
def ctx(tmp_path_factory):
    from lockstep.benchmarks import runner
    sim = runner.Simulation('Town01', DOMAIN, str(tmp_path_factory.mktemp('air')), dt=0.05, air=True, cameras=True)
    try:
        yield runner.Context(dt=0.05)
    finally:
        sim.stop()


@needs
def test_cross_view_sweep(ctx, tmp_path):
    import airsim
    from lockstep.benchmarks import crossview
    recs = crossview.sweep(ctx, airsim.MultirotorClient(), str(tmp_path), ['ClearNoon', 'ClearSunset'],
                           width=160, height=120)
    for r in recs:
        # The four images of a preset come from the tick they were taken on, and the car is in both views.
        assert r['ground_frame'] == r['aerial_frame'] == r['ground_semantic_frame'] == r['frame'], r
        assert r['ground_car_pixels'] > 100 and r['aerial_car_pixels'] > 100, r
        assert (tmp_path / r['ground_image']).exists() and (tmp_path / r['aerial_image']).exists()
    noon, sunset = recs
    # The weather reaches both cameras: a sunset is darker than noon from both sides (the
    # scene stands still: the same weather gives the same images).
    assert sunset['ground_luminance'] < 0.9 * noon['ground_luminance'], recs
    assert sunset['aerial_luminance'] < 0.9 * noon['aerial_luminance'], recs


@needs
def test_vln_pair_of_a_route(ctx, tmp_path):
    from lockstep.benchmarks import episodes
    _, tasks = episodes.load('Town01')
    ep = tasks['One turn'][0]
    (pair,) = vln.generate(ctx, str(tmp_path), [ep], width=160, height=120)
    turns = [k.split('_')[-1] for k in pair['maneuvers'] if k != 'straight']
    assert turns == [t.lower() for t in ep['turns']], pair     # the route's own turns, in order
    assert ('turn ' + turns[0]) in pair['instruction'] or ('bends ' + turns[0]) in pair['instruction']
    assert pair['instruction'].startswith(('Drive', 'At', 'Go', 'Follow')) and 'Stop after about' in pair['instruction']
    assert abs(pair['route_m'] - ep['route_m']) < 5.0
    assert [k['kind'] for k in pair['keypoints']][0] == 'start' and pair['keypoints'][-1]['kind'] == 'goal'
    for k in pair['keypoints']:
        assert k['ground_frame'] == k['aerial_frame'] == k['ground_semantic_frame'] == k['frame'], k
        assert k['traffic_light_pixels'] >= 0
        assert (tmp_path / k['ground_image']).exists() and (tmp_path / k['aerial_image']).exists()


@needs
def test_drone_follow_env(ctx):
    env = follow.DroneFollowEnv(connect=True, max_steps=120, seed=0)
    try:
        obs, info = env.reset(seed=3)
        assert obs.shape == (9,) and obs in env.observation_space and info['error_m'] > 3.0
        obs, r, term, trunc, info = env.step([0.0, 0.0, 0.0])
        assert r == pytest.approx(-info['error_m'] / 10.0) and info['reward_terms']['lost'] == 0.0
        with pytest.raises(ValueError, match='action'):
            env.step([0.0, float('nan'), 0.0])
        # Chasing the station beats hovering where it took off, on the same seeded episode.
        chase, err_chase = follow.episode_return(env, follow.gains_policy([0.8, 1.0, 1.0]), 3)
        hover, err_hover = follow.episode_return(env, follow.gains_policy([0.0, 0.0, 0.0]), 3)
        assert chase > hover + 5.0, (chase, hover)
        assert np.mean(err_chase[-40:]) < 2.0 and np.mean(err_hover[-40:]) > 5.0
    finally:
        env.close()
