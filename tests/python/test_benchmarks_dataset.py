"""CARLA-Air's synchronized multi-modal dataset (lockstep.benchmarks.dataset) at reduced
size: ground and aerial cameras, LiDAR, IMU and GNSS, one sample each per tick in a
KITTI-like layout; the alignment check finds no misaligned index, and finds a shifted
sensor and a missing file. (Its own file: a process keeps one simulation per domain.)"""
import pytest

from conftest import DOMAIN, has_service

needs_render = pytest.mark.skipif(not (has_service('ground_sim') and has_service('air_sim') and has_service('sensors')
                                       and has_service('render')),
                                  reason='needs lockstep_ground_sim, lockstep_air_sim, lockstep_sensors and lockstep_render')


@needs_render
def test_synchronized_dataset_is_aligned_and_the_check_finds_a_shift(tmp_path):
    import os
    from lockstep.benchmarks import dataset, runner
    out = str(tmp_path / 'dataset')
    sim = runner.Simulation('Town01', DOMAIN, str(tmp_path), dt=0.05, air=True, cameras=True)
    try:
        import airsim
        ctx = runner.Context(dt=0.05)
        summary = dataset.record(ctx, airsim.MultirotorClient(), out, ticks=12, width=160, height=120)
    finally:
        sim.stop()
    assert summary['indices'] == 12
    ok = dataset.check_alignment(out)
    assert ok == {'indices': 12, 'misaligned': 0, 'per_sensor': {n: 0 for n in ok['per_sensor']}}
    assert set(ok['per_sensor']) == {'image_front', 'image_rear', 'image_aerial', 'velodyne', 'oxts_imu', 'oxts_gnss'}
    for folder, ext in (('image_front', '.png'), ('image_aerial', '.png'), ('velodyne', '.bin'), ('oxts', '.txt')):
        assert len([f for f in os.listdir(os.path.join(out, folder)) if f.endswith(ext) and f[0].isdigit()]) == 12
    calib = open(os.path.join(out, 'calib.txt')).read()
    assert 'P_front:' in calib and 'P_aerial:' in calib and 'Tr_velo_to_front:' in calib
    assert os.path.getsize(os.path.join(out, 'velodyne', '000005.bin')) % 16 == 0
    # The rear camera one frame late from index 4 on: the check names those indices.
    path = os.path.join(out, 'image_rear', 'timestamps.txt')
    lines = open(path).read().splitlines()
    shifted = lines[:4] + ['%d %s' % (int(line.split()[0]) - 1, line.split()[1]) for line in lines[4:]]
    open(path, 'w').write('\n'.join(shifted) + '\n')
    bad = dataset.check_alignment(out)
    assert bad['misaligned'] == 8 and bad['per_sensor']['image_rear'] == 8 and bad['per_sensor']['velodyne'] == 0
    # A missing file is a misaligned index too.
    open(path, 'w').write('\n'.join(lines) + '\n')
    os.remove(os.path.join(out, 'velodyne', '000007.bin'))
    assert dataset.check_alignment(out)['misaligned'] == 1
