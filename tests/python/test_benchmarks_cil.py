"""Imitation-learning data collection (lockstep.benchmarks.collect) at reduced size: the
steering noise of CIL (fraction, triangular impulses), and a recorded episode where the
noisy steering drives the car while the expert's control and the route's command are
stored, one camera image per frame."""
import csv
import os
import random

import pytest

from conftest import DOMAIN, has_service

from lockstep.benchmarks import collect


def test_noise_covers_the_fraction_with_triangular_impulses():
    n = collect.SteeringNoise(random.Random(1), 0.1, fraction=0.2)
    values = [n() for _ in range(20000)]
    noisy = sum(1 for v in values if v != 0.0) / len(values)
    assert 0.15 < noisy < 0.25
    assert max(abs(v) for v in values) <= 0.35
    # One impulse: up, then down, one sign.
    start = next(i for i, v in enumerate(values) if v != 0.0)
    end = next(i for i in range(start, len(values)) if values[i] == 0.0)
    imp = [abs(v) for v in values[start:end]]
    top = imp.index(max(imp))
    assert all(a <= b + 1e-12 for a, b in zip(imp[:top], imp[1:top + 1]))
    assert all(a >= b - 1e-12 for a, b in zip(imp[top:], imp[top + 1:]))
    assert len({v > 0 for v in values[start:end]}) == 1
    assert collect.SteeringNoise(random.Random(1), 0.1, fraction=0.0)() == 0.0


needs = pytest.mark.skipif(not (has_service('ground_sim') and has_service('render') and has_service('sensors')),
                           reason='needs lockstep_ground_sim, lockstep_render and lockstep_sensors')


@needs
def test_collect_records_expert_control_under_noise(tmp_path):
    from lockstep.benchmarks import episodes, runner
    out = str(tmp_path / 'cil')
    sim = runner.Simulation('Town01', DOMAIN, str(tmp_path), dt=0.1, cameras=True)
    try:
        ctx = runner.Context(dt=0.1)
        _, tasks = episodes.load('Town01')
        total = collect.collect(ctx, out, tasks['Navigation'][:1], seed=3, max_frames=80, noise_fraction=0.5)
    finally:
        sim.stop()
    rows = list(csv.DictReader(open(os.path.join(out, 'measurements.csv'))))
    assert len(rows) == total['frames'] == 80
    assert [int(r['frame']) for r in rows] == list(range(int(rows[0]['frame']), int(rows[0]['frame']) + 80))
    for r in rows:
        assert os.path.getsize(os.path.join(out, 'images', r['image'])) > 0
        assert int(r['command']) in (2, 3, 4, 5)
        steer, applied = float(r['steer']), float(r['applied_steer'])
        if r['noise'] == '1':
            assert applied != steer
        else:
            assert applied == pytest.approx(max(-1.0, min(1.0, steer)), abs=1e-5)
    noisy = sum(r['noise'] == '1' for r in rows)
    assert noisy == total['noisy'] and 10 < noisy < 70
    assert float(rows[-1]['speed_kmh']) > 5.0                      # the expert drove
    with open(os.path.join(out, 'images', rows[0]['image']), 'rb') as f:
        head = f.read(24)
    assert head[:8] == b'\x89PNG\r\n\x1a\n'
    assert int.from_bytes(head[16:20], 'big') == 200 and int.from_bytes(head[20:24], 'big') == 88
