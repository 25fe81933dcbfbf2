"""DDS Security (deploy/security): a simulation whose QoS file turns security on (PKI-DH,
governance and permissions signed by a test CA, AES-GCM on the lockstep topics) is seen
only by participants with a certificate of its CA. A participant without security, or with
a certificate of another CA, neither reads its topics nor joins its barrier."""
import fcntl
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time

import pytest

BIN = os.path.abspath(os.environ.get('LOCKSTEP_BIN', ''))
SOURCE = os.path.abspath(os.environ.get('LOCKSTEP_SOURCE', os.path.join(os.path.dirname(__file__), '..', '..')))
SECURITY = os.path.join(SOURCE, 'deploy', 'security')
MAKE_QOS = os.path.join(SOURCE, 'deploy', 'containers', 'make_qos.py')

if shutil.which('openssl') is None:
    pytest.skip('openssl is not installed', allow_module_level=True)
if not all(os.path.exists(os.path.join(BIN, p)) for p in ('lockstep', 'lockstep_coordinator', 'lockstep_noop')):
    pytest.skip('lockstep, lockstep_coordinator or lockstep_noop is not built', allow_module_level=True)


def _domain():
    """A DDS domain of this process's own (the lock files the other tests use)."""
    for d in list(range(76, 80)) + list(range(1, 200)):
        f = open(os.path.join(tempfile.gettempdir(), 'lockstep-test-domain-%d.lock' % d), 'w')
        try:
            fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
            _domain.lock = f
            return d
        except OSError:
            f.close()
    raise RuntimeError('no free DDS domain')


DOMAIN = _domain()


def make_site(directory, names):
    """A QoS file with security on and its pki/ (a CA of its own) in `directory`."""
    os.makedirs(directory, exist_ok=True)
    subprocess.run([os.path.join(SECURITY, 'make_pki.sh'), '--out', os.path.join(directory, 'pki')] + names, check=True,
                   stdout=subprocess.PIPE)
    # Loopback only: nothing leaves the machine.
    qos = subprocess.run([sys.executable, MAKE_QOS, '--security'], check=True, stdout=subprocess.PIPE, text=True).stdout
    start = qos.index('<participant profile_name="lockstep.participant">')
    end = qos.index('</participant>', start)
    qos = qos[:start] + qos[start:end].replace('<transport_id>lockstep_udp</transport_id>',
                                               '<transport_id>lockstep_udp_loopback</transport_id>') + qos[end:]
    with open(os.path.join(directory, 'fastdds.xml'), 'w') as f:
        f.write(qos)
    return os.path.join(directory, 'fastdds.xml')


def write_config(directory, services):
    path = os.path.join(directory, 'sim.yaml')
    with open(path, 'w') as f:
        f.write('name: secure\ndomain_id: %d\nseed: 1\nqos_file: fastdds.xml\nworld:\n  synchronous_mode: false\n'
                '  fixed_delta_seconds: 0.05\n  real_time_factor: 1\nservices:\n' % DOMAIN)
        for s in services:
            f.write('  - {name: %s, kind: noop}\n' % s)
    return path


def status(qos_file, wait_s, identity=None):
    env = dict(os.environ, LOCKSTEP_QOS_FILE=qos_file)
    env.pop('LOCKSTEP_SECURITY_IDENTITY', None)
    if identity:
        env['LOCKSTEP_SECURITY_IDENTITY'] = identity
    return subprocess.run([os.path.join(BIN, 'lockstep'), 'status', '--domain', str(DOMAIN), '--wait', str(wait_s), '--json'],
                          stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env, timeout=wait_s + 30)


@pytest.fixture(scope='module')
def sites():
    root = tempfile.mkdtemp(prefix='lockstep-security-')
    good = make_site(os.path.join(root, 'good'), ['coordinator', 'steady', 'late', 'client'])
    rogue = make_site(os.path.join(root, 'rogue'), ['late', 'client'])   # the same names, another CA
    plain = os.path.join(root, 'plain.xml')
    shutil.copy(os.path.join(SOURCE, 'deploy', 'qos', 'fastdds.xml'), plain)
    yield root, good, rogue, plain
    shutil.rmtree(root, ignore_errors=True)


def run_status(r):
    """The JSON line of `lockstep status --json` (None when it answered nothing)."""
    import json
    for line in r.stdout.splitlines():
        if line.startswith('{'):
            return json.loads(line)
    return None


def alive(st):
    return {m['service'] for m in st['members'] if m['alive']}


def wait_status(qos_file, predicate, what, clog):
    """Polls `lockstep status` (each call waits for the next RunStatus, sent twice a second)."""
    st = None
    for _ in range(60):
        r = status(qos_file, 30)
        st = run_status(r)
        if st is not None and predicate(st):
            return st
    raise AssertionError('%s: last status %s\n%s' % (what, st, open(clog.name).read()[-3000:]))


def start(argv, log_path):
    log = open(log_path, 'w')
    return subprocess.Popen(argv, stdout=log, stderr=subprocess.STDOUT, env=dict(os.environ, LOCKSTEP_LOG='info')), log


def stop(proc, log):
    proc.send_signal(signal.SIGINT)
    try:
        proc.wait(20)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()
    log.close()


def test_only_participants_of_the_ca_read_the_run_and_join_the_barrier(sites):
    root, good, rogue, plain = sites
    good_dir = os.path.dirname(good)
    config = write_config(good_dir, ['steady', 'late'])   # both required: the run waits for 'late'
    coordinator, clog = start([os.path.join(BIN, 'lockstep_coordinator'), config], os.path.join(root, 'coordinator.log'))
    steady, slog = start([os.path.join(BIN, 'lockstep_noop'), '--name', 'steady', '--config', config],
                         os.path.join(root, 'steady.log'))
    intruder = late = None
    try:
        # A client with a certificate of the CA reads the run: 'steady' joined, waiting for 'late'.
        st = wait_status(good, lambda st: 'steady' in alive(st), "'steady' joining the secure run", clog)
        assert st['frame'] == 0 and 'late' not in alive(st), st
        assert "authenticates as 'coordinator'" in open(clog.name).read()
        # No security, or a certificate of another CA: nothing to read (the same 5 s a valid
        # client needed well under).
        r = status(plain, 5)
        assert r.returncode == 1 and 'no simulation answered' in r.stderr, r.stdout + r.stderr
        r = status(rogue, 5)
        assert r.returncode == 1 and 'no simulation answered' in r.stderr, r.stdout + r.stderr
        # The missing required service with a foreign certificate does not join the barrier:
        # it never hears the coordinator, and the run stays at frame 0 without it.
        rogue_config = write_config(os.path.dirname(rogue), ['steady', 'late'])
        intruder, ilog = start([os.path.join(BIN, 'lockstep_noop'), '--name', 'late', '--config', rogue_config],
                               os.path.join(root, 'intruder.log'))
        # It hears no coordinator: after 10 s it says so and tries again with a new participant.
        for _ in range(600):
            if 'joining again with a new participant' in open(ilog.name).read() or intruder.poll() is not None:
                break
            time.sleep(0.1)
        assert 'joining again with a new participant' in open(ilog.name).read(), open(ilog.name).read()[-2000:]
        st = run_status(status(good, 30))
        assert st is not None and st['frame'] == 0 and 'late' not in alive(st), st
        # The same service with its own certificate joins, and the clock runs.
        late, llog = start([os.path.join(BIN, 'lockstep_noop'), '--name', 'late', '--config', config],
                           os.path.join(root, 'late.log'))
        st = wait_status(good, lambda st: 'late' in alive(st) and st['frame'] > 0, "'late' joining with its certificate", clog)
        assert "authenticates as 'late'" in open(llog.name).read()
    finally:
        if intruder is not None:
            if intruder.poll() is None:
                intruder.kill()
                intruder.wait()
            ilog.close()
        if late is not None:
            stop(late, llog)
        stop(steady, slog)
        stop(coordinator, clog)


def test_a_missing_certificate_is_an_error_naming_it(sites):
    root, good, _, _ = sites
    r = status(good, 1, identity='nobody')
    assert r.returncode != 0 and 'nobody.cert.pem' in r.stderr and 'make_pki.sh' in r.stderr, r.stderr
