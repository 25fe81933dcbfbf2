#!/usr/bin/env python3
"""A simulation as containers (issue 24): builds Lockstep's images from Debian alone
(deploy/containers/build.sh: debootstrap, podman import, Containerfiles with Debian's
runtime packages), then runs deploy/containers/sim.yaml with the coordinator, air_sim and
ground_sim each in its own container on a podman network of its own (own network
namespace, own /dev/shm, Fast DDS over UDP with unicast discovery), `lockstep hashes` in a
client container recording every frame's world hash, and a CARLA script in another
client container ticking 200 frames and reading the states. The same config run on this
machine (the same programs, the script and `lockstep hashes` as local processes) must give
the same world hash for every frame and the same states.

It builds images (minutes, ~1.5 GB of disk) and so runs only when asked:

  LOCKSTEP_CONTAINER_TEST=1 ctest -R deploy.containers --output-on-failure      (from build/)

and skips (exit 77, with the reason) otherwise, or where podman cannot run a container.
Needs root (debootstrap, podman networks). LOCKSTEP_CONTAINER_REBUILD_BASE=1 makes the
Debian base again even if the image exists."""
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

BIN = os.path.abspath(os.environ.get('LOCKSTEP_BIN', os.path.join(os.path.dirname(__file__), '..', '..', 'build', 'bin')))
SOURCE = os.path.abspath(os.environ.get('LOCKSTEP_SOURCE', os.path.join(os.path.dirname(__file__), '..', '..')))
BUILD = os.path.dirname(BIN)
DEPLOY = os.path.join(SOURCE, 'deploy', 'containers')
PODMAN = os.path.join(DEPLOY, 'podman')
TICKS = 200
DOMAIN = int(os.environ.get('LOCKSTEP_CONTAINER_DOMAIN', '76'))       # in the containers' network
HOST_DOMAIN = int(os.environ.get('LOCKSTEP_CONTAINER_HOST_DOMAIN', '77'))  # the one-machine run
SUBNET = '10.89.%d' % DOMAIN
NET = 'lockstep-test-%d' % DOMAIN
PREFIX = 'lockstep-test-%d-' % DOMAIN
IPS = {'coordinator': SUBNET + '.10', 'air_sim': SUBNET + '.11', 'ground_sim': SUBNET + '.12',
       'client': SUBNET + '.20', 'hashes': SUBNET + '.21'}


def skip(reason):
    print('SKIPPED: ' + reason)
    sys.exit(77)


def run(argv, timeout=600, check=True, **kw):
    p = subprocess.run(argv, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=timeout, **kw)
    if check and p.returncode != 0:
        raise AssertionError('%s failed (%d):\n%s' % (' '.join(argv), p.returncode, p.stdout[-4000:]))
    return p.stdout


def podman(*args, **kw):
    return run([PODMAN] + list(args), **kw)


def wait_for(what, predicate, timeout_s, describe):
    """Waits for an event (a log line, an exit) with a bound; names what did not happen."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if predicate():
            return
        time.sleep(0.2)
    raise AssertionError('%s did not happen within %d s:\n%s' % (what, timeout_s, describe()))


def parse_hashes(text):
    hashes = {}
    for line in text.splitlines():
        parts = line.split()
        if len(parts) >= 3 and parts[0].isdigit():
            hashes[int(parts[0])] = (parts[1], parts[2])
    return hashes


def parse_states(text):
    for line in text.splitlines():
        if line.startswith('STATES '):
            return json.loads(line[len('STATES '):])
    raise AssertionError('the CARLA script printed no states:\n' + text[-4000:])


def one_machine_run(workdir):
    """The reference: the same config, every program a local process on this machine."""
    config = os.path.join(workdir, 'host.yaml')
    shutil.copy(os.path.join(DEPLOY, 'sim.yaml'), config)
    env = dict(os.environ, LOCKSTEP_DOMAIN=str(HOST_DOMAIN), LOCKSTEP_BUILD_DIR=BUILD)
    env.pop('LOCKSTEP_QOS_FILE', None)
    up_log = open(os.path.join(workdir, 'host.log'), 'w')
    # The same programs the containers run, as local processes (what `lockstep up` starts).
    dom = ['--domain', str(HOST_DOMAIN)]
    procs = [subprocess.Popen(argv, stdout=up_log, stderr=subprocess.STDOUT, env=env) for argv in (
        [os.path.join(BIN, 'lockstep_coordinator'), config] + dom,
        [os.path.join(BIN, 'lockstep_air_sim'), '--name', 'air_sim', '--config', config] + dom,
        [os.path.join(BIN, 'lockstep_ground_sim'), '--name', 'ground_sim', '--config', config] + dom)]
    hashes = subprocess.Popen([os.path.join(BIN, 'lockstep'), 'hashes', '--domain', str(HOST_DOMAIN), '--until', str(TICKS),
                               '--timeout', '120'], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    try:
        seen = ''
        for line in hashes.stderr:  # "listening ..." once the coordinator's FrameDone writer matched
            seen += line
            if 'listening' in line:
                break
        assert 'listening' in seen, 'lockstep hashes: ' + seen + open(up_log.name).read()[-3000:]
        script = run([os.path.join(BIN, 'lockstep'), 'python', os.path.join(DEPLOY, 'scripts', 'read_states.py'),
                      '--ticks', str(TICKS)], timeout=600, env=env)
        out, err = hashes.communicate(timeout=120)
        assert hashes.returncode == 0, 'lockstep hashes failed: ' + err
        return parse_hashes(out), parse_states(script)
    finally:
        if hashes.poll() is None:
            hashes.kill()
        for p in procs:
            p.send_signal(2)
        for p in procs:
            try:
                p.wait(30)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()
        up_log.close()


def cleanup():
    names = [PREFIX + n for n in IPS]
    podman('rm', '-f', '-t', '2', *names, check=False, timeout=120)
    podman('network', 'rm', '-f', NET, check=False, timeout=60)


def container_run(workdir):
    etc = os.path.join(workdir, 'etc')
    os.makedirs(etc)
    shutil.copy(os.path.join(DEPLOY, 'sim.yaml'), os.path.join(etc, 'sim.yaml'))
    # Each container finds the others by address (no multicast, no shared memory).
    run([sys.executable, os.path.join(DEPLOY, 'make_qos.py'), '--peers', ','.join(IPS.values()), '--peer-ids', '2',
         '-o', os.path.join(etc, 'fastdds.xml')])
    cleanup()
    podman('network', 'create', '--subnet', SUBNET + '.0/24', NET)
    common = ['--network', NET, '-v', etc + ':/etc/lockstep:ro', '-e', 'LOCKSTEP_QOS_FILE=/etc/lockstep/fastdds.xml',
              '-e', 'LOCKSTEP_DOMAIN=%d' % DOMAIN]
    cfg = ['--config', '/etc/lockstep/sim.yaml', '--domain', str(DOMAIN)]

    def start(name, image, args, extra=()):
        podman('run', '-d', '--name', PREFIX + name, '--hostname', name, '--ip', IPS[name], *common, *extra,
               'localhost/lockstep/%s:latest' % image, *args)

    start('coordinator', 'coordinator', ['/etc/lockstep/sim.yaml', '--domain', str(DOMAIN)])
    start('air_sim', 'air_sim', ['--name', 'air_sim'] + cfg)
    start('ground_sim', 'ground_sim', ['--name', 'ground_sim'] + cfg)
    start('hashes', 'client', ['hashes', '--domain', str(DOMAIN), '--until', str(TICKS), '--timeout', '120'])

    def logs(name):
        return podman('logs', PREFIX + name, check=False, timeout=60)

    def all_logs():
        return '\n'.join('--- %s\n%s' % (n, logs(n)[-3000:]) for n in IPS)

    wait_for('lockstep hashes in its container matching the coordinator', lambda: 'listening' in logs('hashes'), 120,
             all_logs)
    scripts = os.path.join(DEPLOY, 'scripts')
    podman('run', '--name', PREFIX + 'client', '--hostname', 'client', '--ip', IPS['client'], *common,
           '-v', scripts + ':/scripts:ro', 'localhost/lockstep/client:latest', 'python', '/scripts/read_states.py',
           '--ticks', str(TICKS), timeout=600)
    client_out = logs('client')
    wait_for('the hashes container ending at frame %d' % TICKS,
             lambda: podman('inspect', '--format', '{{.State.Status}}', PREFIX + 'hashes', check=False).strip() == 'exited',
             120, all_logs)
    code = podman('inspect', '--format', '{{.State.ExitCode}}', PREFIX + 'hashes').strip()
    assert code == '0', 'lockstep hashes in its container exited %s:\n%s' % (code, all_logs())
    # No process shares /dev/shm with another: each container has its own (Fast DDS's
    # shared-memory transport is off in the generated profile anyway).
    shm = {n: podman('exec', PREFIX + n, 'stat', '-c', '%d:%i', '/dev/shm', check=False).strip()
           for n in ('coordinator', 'air_sim', 'ground_sim')}
    return parse_hashes(logs('hashes')), parse_states(client_out), shm, all_logs()


def main():
    if os.environ.get('LOCKSTEP_CONTAINER_TEST') != '1':
        skip('builds container images (minutes); run with LOCKSTEP_CONTAINER_TEST=1 (docs/deployment.md)')
    if shutil.which('podman') is None:
        skip('podman is not installed (apt-get install podman runc debootstrap)')
    if os.geteuid() != 0:
        skip('needs root (debootstrap, podman networks with fixed addresses)')
    for p in ('lockstep', 'lockstep_coordinator', 'lockstep_air_sim', 'lockstep_ground_sim'):
        if not os.path.exists(os.path.join(BIN, p)):
            skip('%s is not built' % p)
    t0 = time.monotonic()
    argv = [os.path.join(DEPLOY, 'build.sh'), '--build-dir', BUILD]
    if os.environ.get('LOCKSTEP_CONTAINER_REBUILD_BASE') == '1':
        argv.append('--rebuild-base')
    print(run(argv + ['coordinator', 'air_sim', 'ground_sim', 'client'], timeout=1800), flush=True)
    print('images built in %.0f s' % (time.monotonic() - t0), flush=True)
    probe = podman('run', '--rm', 'localhost/lockstep/runtime:latest', 'true', check=False, timeout=120)
    if 'Error' in probe:
        skip('podman cannot run a container here: ' + probe.strip()[-500:])

    workdir = tempfile.mkdtemp(prefix='lockstep-containers-')
    t1 = time.monotonic()
    host_hashes, host_states = one_machine_run(workdir)
    print('one machine: %d frames in %.1f s' % (len(host_hashes), time.monotonic() - t1), flush=True)
    t2 = time.monotonic()
    try:
        hashes, states, shm, logs = container_run(workdir)
    finally:
        cleanup()
    print('containers: %d frames in %.1f s' % (len(hashes), time.monotonic() - t2), flush=True)

    failures = []
    if len(set(shm.values())) != len(shm) or '' in shm.values():
        failures.append('the service containers share /dev/shm: %s' % shm)
    for name, h in (('one machine', host_hashes), ('containers', hashes)):
        missing = [f for f in range(1, TICKS + 1) if f not in h]
        if missing:
            failures.append('%s: no world hash for %d frame(s), first %s' % (name, len(missing), missing[:5]))
    differ = [f for f in range(1, TICKS + 1) if f in hashes and f in host_hashes and hashes[f] != host_hashes[f]]
    if differ:
        f = differ[0]
        failures.append('world hash differs at %d frame(s); first frame %d: containers %s, one machine %s'
                        % (len(differ), f, hashes[f], host_hashes[f]))
    if states != host_states:
        failures.append('states differ:\n containers  %s\n one machine %s' % (states, host_states))
    if states.get('ticks') != TICKS or len(states.get('actors', [])) < 2:
        failures.append('the script ticked %s frames and saw %d vehicle/drone(s): %s'
                        % (states.get('ticks'), len(states.get('actors', [])), states))
    if failures:
        print('\n'.join(failures))
        print(logs[-8000:])
        print('0 passed, 1 failed')
        return 1
    print('frames 1..%d: world hashes equal (frame %d: %s); %d actors with equal states; /dev/shm per container'
          % (TICKS, TICKS, hashes[TICKS][1], len(states['actors'])))
    shutil.rmtree(workdir, ignore_errors=True)
    return 0


if __name__ == '__main__':
    sys.exit(main())
