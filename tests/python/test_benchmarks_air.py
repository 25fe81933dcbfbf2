"""CARLA-Air's precision landing (lockstep.benchmarks.landing) at reduced size: a drone
lands on the roof of a Traffic-Manager car, over several seeds, each touchdown within
CARLA-Air's 0.5 m of the roof's centre."""
import pytest

from conftest import DOMAIN, has_service

needs = pytest.mark.skipif(not (has_service('ground_sim') and has_service('air_sim') and has_service('sensors')),
                           reason='needs lockstep_ground_sim, lockstep_air_sim and lockstep_sensors')


@needs
def test_precision_landing_over_seeds(tmp_path):
    from lockstep.benchmarks import episodes, landing, runner
    sim = runner.Simulation('Town01', DOMAIN, str(tmp_path), dt=landing.DT, air=True)
    try:
        import airsim
        ctx = runner.Context(dt=landing.DT)
        air = airsim.MultirotorClient()
        _, tasks = episodes.load('Town01')
        results = []
        for seed in range(3):
            log = []
            r = landing.run_once(ctx, air, seed, tasks['Straight'], log=log)
            results.append(r)
            assert r['touchdown'] and r['contact'], (r, log[-5:])   # air_sim's contact with the car
            assert -0.2 < r['above_roof_m'] < 0.3, r
            assert r['error_m'] < 0.5, r
            assert r['car_speed_at_touchdown_kmh'] > 10.0, r       # on a moving car
            # It came down from the tracking height during the run.
            assert max(h for _, _, h, _ in log) > 10.0
        assert len({r['episode'] for r in results} | {r['car_speed_kmh'] for r in results}) > 1
    finally:
        sim.stop()

