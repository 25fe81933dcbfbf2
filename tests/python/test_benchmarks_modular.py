"""The modular-pipeline agent (lockstep.benchmarks.modular): its perception on synthetic
camera images of a known road (lane centre, junction, obstacle), and the agent driving a
short episode on a simulation with cameras (render): to the goal, and stopping for a car
parked in its lane."""
import math

import numpy as np
import pytest

import test_benchmarks as tb   # its episode and parked-car helpers (a module alias: pytest collects no test twice)
from conftest import DOMAIN, has_service

from lockstep.benchmarks import modular, runner

W, H, FOV = 256, 128, 100.0


def synthetic(p, left, right, marking=None, obstacle=None, side_street=False):
    """Semantic tags and planar depth a camera of Perception `p` sees over flat ground with a
    road from y = left to y = right (car frame, y to the right), a centre marking at y =
    `marking`, a flat 'vehicle' patch at x in obstacle = (x0, x1), |y| < 1."""
    r = p.ray
    m = p.mount
    down = r[..., 2] < -1e-6
    t = np.where(down, -m[2] / np.where(down, r[..., 2], -1.0), 1000.0)
    x = m[0] + t * r[..., 0]
    y = m[1] + t * r[..., 1]
    tags = np.full(t.shape, 11, dtype=np.uint8)                  # sky
    tags[down] = modular.SIDEWALKS
    on_road = down & (y >= left) & (y <= right)
    if side_street:
        on_road |= down & (x > 4.0) & (x < 11.0)                  # a street crossing from both sides
    tags[on_road] = modular.ROADS
    if marking is not None:
        tags[down & (np.abs(y - marking) < 0.08)] = modular.ROADLINES
    if obstacle is not None:
        tags[down & (x >= obstacle[0]) & (x <= obstacle[1]) & (np.abs(y) < 1.0)] = 14
    return tags, t.astype(np.float32)


def test_perception_finds_the_lane_centre():
    p = modular.Perception(W, H, FOV)
    # Two 3.5 m lanes, the car 0.5 m left of its lane's centre: the centre is 0.5 m to its right.
    out = p.analyse(*synthetic(p, -4.75, 2.25, marking=-1.25))
    assert out['road_right'] == pytest.approx(2.25, abs=0.26) and out['road_left'] == pytest.approx(-4.75, abs=0.26)
    assert out['marking'] == pytest.approx(-1.25, abs=0.1)
    assert out['lane_centre'] == pytest.approx(0.5, abs=0.15)
    assert not out['junction'] and math.isinf(out['obstacle_m'])
    # Without a marking: a quarter of the road's width in from its right edge.
    out = p.analyse(*synthetic(p, -5.25, 1.75))
    assert out['marking'] is None and out['lane_centre'] == pytest.approx(0.0, abs=0.15)


def test_perception_sees_junctions_and_obstacles():
    p = modular.Perception(W, H, FOV)
    out = p.analyse(*synthetic(p, -5.25, 1.75, marking=-1.75, side_street=True))
    assert out['junction'] and out['lane_centre'] is None
    out = p.analyse(*synthetic(p, -5.25, 1.75, marking=-1.75, obstacle=(12.0, 14.0)))
    assert out['obstacle_m'] == pytest.approx(12.0, abs=0.3)
    # A car in the other lane is no obstacle.
    tags, depth = synthetic(p, -5.25, 1.75, marking=-1.75)
    tags2, _ = synthetic(p, -5.25, 1.75, marking=-1.75, obstacle=(12.0, 14.0))
    shifted = np.where(tags2 == 14, modular.ROADS, tags)
    lifted = p.lift(depth.astype(np.float64))
    shifted[(lifted[..., 0] > 12) & (lifted[..., 0] < 14) & (lifted[..., 1] < -2.5) & (lifted[..., 1] > -4.5)] = 14
    assert math.isinf(p.analyse(shifted, depth)['obstacle_m'])
    with pytest.raises(ValueError, match='images of'):
        p.analyse(tags[:10], depth)


# ---- on a simulation with cameras ----

needs_render = pytest.mark.skipif(not all(has_service(k) for k in ('ground_sim', 'sensors', 'render')),
                                  reason='needs lockstep_ground_sim, lockstep_sensors and lockstep_render')


@pytest.fixture(scope='module')
def ctx(tmp_path_factory):
    sim = runner.Simulation('Town01', DOMAIN, str(tmp_path_factory.mktemp('mp')), dt=0.1, cameras=True)
    try:
        yield runner.Context(dt=0.1, grid_m=0.4)
    finally:
        sim.stop()


@needs_render
def test_modular_agent_drives_to_the_goal_and_stops_for_a_car(ctx):
    ep, wp = tb.straight_episode(ctx, 50.0)
    agent = runner.make_agent('modular')
    r, rows = runner.run_episode(ctx, agent, ep, task='Straight', weather=1)
    assert r['end'] == 'success', r
    assert agent.stats['lane_from_perception'] > 0.5 * agent.stats['frames'], agent.stats
    assert max(x['intersection_offroad'] for x in rows) < 0.05 and r['intersection_otherlane'] == 0
    assert max(x['speed_kmh'] for x in rows) > 15.0
    # A car parked in the lane 30 m ahead: the pipeline sees it and stops short (hazard stop).
    import carla
    with tb.parked_ahead(ctx, wp, 30.0) as parked:
        agent = runner.make_agent('modular')
        r, rows = runner.run_episode(ctx, agent, ep, task='Nav. dynamic', weather=1, dynamic=True, time_out=12.0)
        assert r['end'] == 'time-out' and r['collision_vehicles'] == 0, r
        assert max(x['collision_vehicles'] for x in rows) == 0.0
        assert agent.stats[modular.HAZARD_STOP] > 10
        gap = parked.get_location().distance(carla.Location(rows[-1]['pos_x'], rows[-1]['pos_y'], 0.0))
        assert rows[-1]['speed_kmh'] < 1.0 and 4.5 < gap < 15.0, (gap, rows[-1])
