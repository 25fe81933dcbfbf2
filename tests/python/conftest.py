"""A simulation for the Python tests: `lockstep up` on a DDS domain of this process's own
(the same lock files as the C++ tests), synchronous, in the generated training town, with
air_sim, the stand-in sensors service, and whichever of ground_sim, sensors and render are
built. Scripts and clients find it through LOCKSTEP_DOMAIN."""
import fcntl
import os
import signal
import subprocess
import tempfile

import pytest

BIN = os.path.abspath(os.environ.get('LOCKSTEP_BIN', ''))
SOURCE = os.path.abspath(os.environ.get('LOCKSTEP_SOURCE', ''))
_lock_file = None


def _domain():
    global _lock_file
    start = os.getpid() % 200
    for i in range(200):
        d = 1 + (start + i) % 200
        f = open(os.path.join(tempfile.gettempdir(), 'lockstep-test-domain-%d.lock' % d), 'w')
        try:
            fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
            _lock_file = f  # held until the process exits
            return d
        except OSError:
            f.close()
    raise RuntimeError('no free DDS domain')


DOMAIN = _domain()
os.environ['LOCKSTEP_DOMAIN'] = str(DOMAIN)


def _end_with_parent():
    """In the child: SIGINT when this test process dies, so a pytest that ctest kills at its
    time-out leaves no simulation behind (one left running eats the 2 cores of the next tests)."""
    import ctypes
    ctypes.CDLL('libc.so.6', use_errno=True).prctl(1, signal.SIGINT)  # PR_SET_PDEATHSIG


def has_service(kind):
    return os.path.exists(os.path.join(BIN, 'lockstep_' + kind))


class Simulation:
    def __init__(self, services, synchronous=True):
        self.dir = tempfile.mkdtemp(prefix='lockstep-pytest-')
        town = os.path.join(os.path.dirname(BIN), 'maps', 'generated', 'LockstepTown1.xodr')
        lines = ['name: pytest', 'domain_id: %d' % DOMAIN, 'seed: 3', 'map: %s' % town, 'world:',
                 '  synchronous_mode: %s' % ('true' if synchronous else 'false'), '  fixed_delta_seconds: 0.05',
                 '  service_timeout: 30', 'services:']
        for name, kind, perception in services:
            lines.append('  - {name: %s, kind: %s, perception: %s}' % (name, kind, 'true' if perception else 'false'))
        self.config = os.path.join(self.dir, 'sim.yaml')
        with open(self.config, 'w') as f:
            f.write('\n'.join(lines) + '\n')
        self.log = open(os.path.join(self.dir, 'sim.log'), 'w')
        self.proc = subprocess.Popen([os.path.join(BIN, 'lockstep'), 'up', self.config], stdout=self.log,
                                     stderr=subprocess.STDOUT, preexec_fn=_end_with_parent)
        import lockstep
        try:
            self.client = lockstep.Client(domain=DOMAIN, timeout=30)
            if not self.client.wait_ready(60):
                raise RuntimeError('simulation not ready: %s' % open(self.log.name).read()[-2000:])
        except BaseException:
            self.stop()  # a simulation that did not start must not keep running for the next tests
            raise

    def output(self):
        return open(self.log.name).read()

    def stop(self):
        self.client = None
        self.proc.send_signal(signal.SIGINT)
        try:
            self.proc.wait(20)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        self.log.close()


def default_services():
    services = [('air_sim', 'air_sim', False)]
    for kind, perception in (('ground_sim', False), ('sensors', True), ('render', True)):
        if has_service(kind):
            services.append((kind, kind, perception))
    if not (has_service('sensors') or has_service('render')):
        services.append(('sensors_stand_in', 'fake_sensors', True))  # tests/client/fake_sensors.h
    return services


@pytest.fixture(scope='module')
def sim():
    s = Simulation(default_services())
    yield s
    s.stop()


@pytest.fixture(scope='module')
def world(sim):
    """The world of the module's simulation through the drop-in carla client (a module may
    override it, as test_world.py does to switch synchronous mode on)."""
    import carla
    client = carla.Client('localhost', 2000)
    client.set_timeout(30)
    return client.get_world()
