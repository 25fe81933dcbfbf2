"""The learning environment of lockstep.benchmarks: its spaces, the CARLA paper's reward
(each term, so that dropping one fails), a driving episode through reset/step, and
N environments each in its own process on its own DDS domain."""
import fcntl
import os
import tempfile

import numpy as np
import pytest

from conftest import DOMAIN, has_service

from lockstep.benchmarks import env as env_mod
from lockstep.benchmarks.spaces import Box, Dict, Discrete


def test_spaces():
    b = Box(np.array([-1.0, 0.0]), np.array([1.0, 2.0]), seed=3)
    x = b.sample()
    assert x.shape == (2,) and x.dtype == np.float32 and x in b
    assert b.sample().tolist() != x.tolist()
    b.seed(3)
    assert b.sample().tolist() == x.tolist()                 # seeded: the same draws again
    assert np.array([1.5, 0.0], dtype=np.float32) not in b and np.zeros(3) not in b
    with pytest.raises(ValueError):
        Box(1.0, 0.0, shape=(1,))
    d = Discrete(4, seed=1)
    assert all(d.sample() in d for _ in range(20)) and 4 not in d and -1 not in d and 2 in d
    s = Dict({'m': Box(0.0, 1.0, shape=(3,)), 'c': Discrete(4)}, seed=5)
    v = s.sample()
    assert list(v) == ['c', 'm'] and v in s
    assert {'c': 1} not in s and {'c': 7, 'm': np.zeros(3, np.float32)} not in s


def paper_reward(p, n):
    # Dosovitskiy et al. 2017: r = 1000 (d_{t-1} - d_t) + 0.05 (v_t - v_{t-1}) - 0.00002 (c_t - c_{t-1})
    #                              - 2 (s_t - s_{t-1}) - 2 (o_t - o_{t-1})
    return (1000 * (p['distance_km'] - n['distance_km']) + 0.05 * (n['speed_kmh'] - p['speed_kmh'])
            - 0.00002 * (n['collision_damage'] - p['collision_damage']) - 2 * (n['offroad'] - p['offroad'])
            - 2 * (n['otherlane'] - p['otherlane']))


def test_reward_has_every_term_of_the_paper():
    prev = {'distance_km': 0.500, 'speed_kmh': 20.0, 'collision_damage': 0.0, 'offroad': 0.0, 'otherlane': 0.1}
    # Each change alone, then all together: every term must show with its weight and sign.
    changes = {'distance_km': 0.498, 'speed_kmh': 26.0, 'collision_damage': 5000.0, 'offroad': 0.5, 'otherlane': 0.35}
    expected = {'distance_km': ('distance', 2.0), 'speed_kmh': ('speed', 0.3), 'collision_damage': ('collision', -0.1),
                'offroad': ('sidewalk', -1.0), 'otherlane': ('opposite_lane', -0.5)}
    for key, value in changes.items():
        now = dict(prev, **{key: value})
        r, terms = env_mod.driving_reward(prev, now)
        name, amount = expected[key]
        assert terms[name] == pytest.approx(amount)
        assert r == pytest.approx(amount) == pytest.approx(paper_reward(prev, now))
        assert all(v == 0 for k, v in terms.items() if k != name)
    now = dict(prev, **changes)
    r, terms = env_mod.driving_reward(prev, now)
    assert r == pytest.approx(paper_reward(prev, now)) == pytest.approx(2.0 + 0.3 - 0.1 - 1.0 - 0.5)
    assert r == pytest.approx(sum(terms.values()))


needs_ground = pytest.mark.skipif(not (has_service('ground_sim') and has_service('sensors')),
                                  reason='needs lockstep_ground_sim and lockstep_sensors')


@needs_ground
def test_driving_env_episode():
    e = env_mod.DrivingEnv('Town01', domain=DOMAIN, task='Straight', max_steps=40, seed=7)
    try:
        obs, info = e.reset(seed=7, options={'episode': 0})
        assert obs in e.observation_space
        assert obs['command'] in (0, 3)                       # a straight route: follow the lane (or straight on)
        start_m = obs['measurements'][1]
        assert start_m == pytest.approx(e.episode['route_m'], rel=0.05)
        total, steps = 0.0, 0
        while True:
            obs, reward, terminated, truncated, info = e.step(np.array([0.0, 0.7, 0.0]))
            steps += 1
            assert obs in e.observation_space
            assert reward == pytest.approx(sum(info['reward_terms'].values()))
            total += info['reward_terms']['distance']
            if terminated or truncated:
                break
        assert truncated and not terminated and steps == 40
        driven = start_m - obs['measurements'][1]
        assert driven > 10.0
        assert total == pytest.approx(driven, rel=1e-3)       # 1000 per km: one per metre towards the goal
        with pytest.raises(ValueError):
            e.step([0.0, float('nan'), 0.0])
    finally:
        e.close()


def _free_domains(n):
    held = []
    for d in list(range(201, 232)):
        f = open(os.path.join(tempfile.gettempdir(), 'lockstep-test-domain-%d.lock' % d), 'w')
        try:
            fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
            held.append((d, f))
            if len(held) == n:
                return held
        except OSError:
            f.close()
    raise RuntimeError('no free DDS domains')


@needs_ground
def test_vector_env_each_on_its_own_domain():
    held = _free_domains(2)
    v = env_mod.VectorEnv(2, domains=[d for d, _ in held], task='Straight', max_steps=5)
    try:
        first = v.reset(seed=1)
        assert len(first) == 2 and all(o in v.observation_space for o, _ in first)
        out = v.step([np.array([0.0, 1.0, 0.0])] * 2)
        assert len(out) == 2
        for obs, reward, terminated, truncated, info in out:
            assert obs in v.observation_space and np.isfinite(reward) and info['steps'] == 1
    finally:
        v.close()
        for _, f in held:
            f.close()
