"""A script's process as a CARLA or AirSim user sees it: it exits cleanly whatever client
threads, sensor callbacks and waiting daemon threads are alive at its end, and Ctrl-C
(SIGINT) ends a call blocked in wait_for_tick() or a drone command's join() with
KeyboardInterrupt, as in CARLA and AirSim, where those calls wait in native code.

Each case runs a real script in its own Python process against the module's simulation."""
import os
import select
import signal
import subprocess
import sys
import textwrap
import time

import pytest

from conftest import DOMAIN

PRELUDE = textwrap.dedent('''
    import sys, threading
    import carla
    client = carla.Client('localhost', 2000)
    client.set_timeout(30)
    world = client.get_world()
    ''')


def _start(body):
    env = dict(os.environ, LOCKSTEP_DOMAIN=str(DOMAIN), PYTHONUNBUFFERED='1')
    return subprocess.Popen([sys.executable, '-c', PRELUDE + textwrap.dedent(body)], stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, env=env, text=True)


def _read_until(proc, marker, timeout):
    """The script's output up to the line `marker` (it prints it when it is about to block)."""
    seen = []
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        ready, _, _ = select.select([proc.stdout], [], [], max(0.0, deadline - time.monotonic()))
        if not ready:
            break
        line = proc.stdout.readline()
        if not line:
            break
        seen.append(line)
        if line.strip() == marker:
            return ''.join(seen)
    proc.kill()
    pytest.fail('the script did not print %r within %s s:\n%s%s' % (marker, timeout, ''.join(seen), proc.stdout.read()))


def _finish(proc, timeout):
    try:
        out, _ = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        proc.kill()
        out, _ = proc.communicate()
        pytest.fail('the script still ran %s s later:\n%s' % (timeout, out))
    return out


CRASH = ('FATAL', 'terminate called', 'Segmentation fault', 'Aborted', 'core dumped', 'Exception in thread',
         'Exception ignored')


@pytest.mark.parametrize('attempt', [1, 2, 3])
def test_a_script_that_ends_with_live_callbacks_and_waiting_daemon_threads_exits_cleanly(sim, attempt):
    proc = _start('''
        lib = world.get_blueprint_library()
        sensors = [bp for bp in lib.filter('sensor.*') if bp.id in ('sensor.other.imu', 'sensor.other.gnss')]
        sensors = sensors or list(lib.filter('sensor.*'))
        sensor = world.spawn_actor(sensors[0], carla.Transform(carla.Location(0, 0, 2)))
        got = []
        sensor.listen(lambda data: got.append(data.frame))       # a callback on the client's thread
        world.on_tick(lambda snapshot: got.append(snapshot.frame))  # a thread of the carla module

        def waiter():                                              # a user's daemon thread, blocked
            while True:
                world.wait_for_tick(600)

        def ticker():                  # the world goes on ticking, so data arrives while Python exits
            while True:
                world.tick()
        threading.Thread(target=waiter, daemon=True).start()
        for _ in range(10):
            world.tick()
        assert got, 'no callback ran'
        threading.Thread(target=ticker, daemon=True).start()
        while len(got) < 40:
            pass
        print('last line', flush=True)
        ''')
    out = _finish(proc, 60)
    assert proc.returncode == 0, out
    assert 'last line' in out
    crash = [word for word in CRASH if word in out]
    assert not crash, out


def test_ctrl_c_ends_a_blocked_wait_for_tick_with_keyboard_interrupt(sim):
    # The simulation is synchronous and nobody ticks: wait_for_tick() waits its 600 s.
    proc = _start('''
        print('blocking', flush=True)
        world.wait_for_tick(600)
        print('returned', flush=True)
        ''')
    _read_until(proc, 'blocking', 60)
    time.sleep(0.3)  # into the native wait (the signal is what is tested, not the timing)
    proc.send_signal(signal.SIGINT)
    out = _finish(proc, 10)
    assert 'KeyboardInterrupt' in out, out
    assert 'returned' not in out
    assert proc.returncode == -signal.SIGINT, out  # Python re-raises an uncaught KeyboardInterrupt as SIGINT


def test_a_sigint_handler_that_does_not_raise_runs_and_the_wait_goes_on(sim):
    proc = _start('''
        import signal
        signal.signal(signal.SIGINT, lambda *a: print('handler ran', flush=True))
        print('blocking', flush=True)
        try:
            world.wait_for_tick(4)
        except RuntimeError as e:
            print('timed out:', type(e).__name__, flush=True)
        ''')
    _read_until(proc, 'blocking', 60)
    time.sleep(0.3)
    proc.send_signal(signal.SIGINT)
    out = _finish(proc, 30)
    assert proc.returncode == 0, out
    # The handler runs while the call still waits (not when it returns), and the call then
    # ends as it would have: by its own time-out.
    assert out.index('handler ran') < out.index('timed out: ClientError'), out


def test_ctrl_c_ends_a_drone_join_that_drives_a_synchronous_world(sim):
    proc = _start('''
        import airsim
        bp = world.get_blueprint_library().find('drone.generic_quad')
        bp.set_attribute('role_name', 'sigint')
        drone = world.spawn_actor(bp, carla.Transform(carla.Location(43.25, 1.75, 0.2)))
        for _ in range(40):
            world.tick()
        c = airsim.MultirotorClient()
        c.enableApiControl(True, 'sigint')
        c.armDisarm(True, 'sigint')
        c.takeoffAsync(vehicle_name='sigint').join()
        future = c.moveToPositionAsync(5000, 0, -5, 1, vehicle_name='sigint')   # hours away
        print('blocking', flush=True)
        future.join()   # ticks the synchronous world itself while it waits
        print('returned', flush=True)
        ''')
    _read_until(proc, 'blocking', 120)
    time.sleep(0.5)
    proc.send_signal(signal.SIGINT)
    out = _finish(proc, 15)
    assert 'KeyboardInterrupt' in out, out
    assert 'returned' not in out
    assert proc.returncode == -signal.SIGINT, out  # Python re-raises an uncaught KeyboardInterrupt as SIGINT
