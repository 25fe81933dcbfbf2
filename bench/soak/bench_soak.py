#!/usr/bin/python3
"""bench/run soak [--cycles N] [--ticks T] [--no-reset] [--max-drift MIB] [--max-slope MIB]:
the full stack (every service built: air_sim, ground_sim, sensors, render, recorder) on a
simulation of its own, through N cycles; each cycle spawns 20 cars under the Traffic
Manager, 10 walkers with their AI controllers, 2 drones (armed, take off, fly), 2 cameras
and a LiDAR, runs T ticks, destroys them all and resets the world (CARLA's reload_world,
as CARLA-Air's reset cycles). Every process's RSS (/proc, VmRSS) is sampled after each
cycle. One JSON line per cycle, then the summary: per process its RSS after the first
counted cycle and the last, the drift (MiB, last - first), the least-squares slope (MiB
per cycle) and the errors (exceptions, rejected commands, sensors that delivered nothing,
members that failed or diverged, error lines in the simulation's log). Exits 1 on any
error, or when a drift or slope exceeds --max-drift / --max-slope (the suite's short
soak, tests/fault: a leak fails it)."""
import argparse
import fcntl
import json
import os
import random
import re
import signal
import subprocess
import sys
import tempfile
import threading
import time

BIN = os.path.dirname(os.path.abspath(__file__))
BUILD = os.path.dirname(BIN)
ROOT = os.path.dirname(BUILD)
sys.path[:0] = [os.path.join(BUILD, 'python'), os.path.join(BUILD, 'python', 'dropin')]
_lock = None


def free_domain():
    """A DDS domain of this process's own (the lock files of the tests and benchmarks)."""
    global _lock
    start = os.getpid() % 200
    for i in range(200):
        d = 1 + (start + i) % 200
        f = open(os.path.join(tempfile.gettempdir(), 'lockstep-test-domain-%d.lock' % d), 'w')
        try:
            fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
            _lock = f
            return d
        except OSError:
            f.close()
    sys.exit('bench soak: no free DDS domain')


def rss_mib(pid):
    try:
        with open('/proc/%d/status' % pid) as f:
            for line in f:
                if line.startswith('VmRSS:'):
                    return int(line.split()[1]) / 1024.0
    except OSError:
        return None
    return None


def children(pid):
    """Direct children of pid (from /proc/*/stat)."""
    out = []
    for entry in os.listdir('/proc'):
        if not entry.isdigit():
            continue
        try:
            with open('/proc/%s/stat' % entry) as f:
                stat = f.read()
        except OSError:
            continue
        fields = stat[stat.rfind(')') + 2:].split()
        if int(fields[1]) == pid:
            out.append(int(entry))
    return out


def process_name(pid):
    """'coordinator' or the service's --name, from its command line."""
    try:
        with open('/proc/%d/cmdline' % pid, 'rb') as f:
            argv = f.read().split(b'\0')
    except OSError:
        return None
    argv = [a.decode(errors='replace') for a in argv if a]
    if '--name' in argv:
        return argv[argv.index('--name') + 1]
    return os.path.basename(argv[0]).replace('lockstep_', '') if argv else None


def slope(ys):
    n = len(ys)
    if n < 2:
        return 0.0
    mx = (n - 1) / 2.0
    my = sum(ys) / n
    den = sum((i - mx) ** 2 for i in range(n))
    return sum((i - mx) * (y - my) for i, y in enumerate(ys)) / den


def write_config(path, domain, services, seed):
    town = os.path.join(BUILD, 'maps', 'generated', 'LockstepTown1.xodr')
    lines = ['name: soak', 'domain_id: %d' % domain, 'seed: %d' % seed, 'map: %s' % town, 'world:',
             '  synchronous_mode: true', '  fixed_delta_seconds: 0.05', '  service_timeout: 60', 'services:']
    for kind, perception in services:
        lines.append('  - {name: %s, kind: %s, perception: %s}' % (kind, kind, 'true' if perception else 'false'))
    with open(path, 'w') as f:
        f.write('\n'.join(lines) + '\n')


class Soak:
    def __init__(self, args):
        import airsim
        import carla
        self.carla, self.airsim, self.args = carla, airsim, args
        self.client = carla.Client('localhost', 2000)
        self.client.set_timeout(60)
        self.world = self.client.get_world()
        self.air = airsim.MultirotorClient()
        self.rng = random.Random(args.seed)
        self.errors = []

    def error(self, cycle, what):
        self.errors.append('cycle %d: %s' % (cycle, what))

    def settle(self, n):
        for _ in range(n):
            self.world.tick()

    def cycle(self, c):
        carla, a = self.carla, self.args
        world = self.world
        library = world.get_blueprint_library()
        points = world.get_map().get_spawn_points()
        cars, walkers, controllers, drones, sensors = [], [], [], [], []
        heard = {}
        try:
            vehicle_bps = [bp for bp in library.filter('vehicle.*') if not bp.id.startswith('vehicle.lockstep.drone')]
            order = list(range(len(points)))
            self.rng.shuffle(order)
            for i in order:
                if len(cars) == a.cars:
                    break
                car = world.try_spawn_actor(self.rng.choice(vehicle_bps), points[i])
                if car is not None:
                    car.set_autopilot(True)
                    cars.append(car)
            if len(cars) < a.cars:
                self.error(c, 'spawned %d of %d cars' % (len(cars), a.cars))
            walker_bps = library.filter('walker.pedestrian.*')
            controller_bp = library.find('controller.ai.walker')
            for _ in range(a.walkers * 3):
                if len(walkers) == a.walkers:
                    break
                loc = world.get_random_location_from_navigation()
                if loc is None:
                    continue
                w = world.try_spawn_actor(self.rng.choice(walker_bps), carla.Transform(loc + carla.Location(z=1.0)))
                if w is not None:
                    walkers.append(w)
            if len(walkers) < a.walkers:
                self.error(c, 'spawned %d of %d walkers' % (len(walkers), a.walkers))
            for w in walkers:
                controllers.append(world.spawn_actor(controller_bp, carla.Transform(), w))
            for i in range(a.drones):
                bp = library.find('drone.generic_quad')
                bp.set_attribute('role_name', 'soak%d' % i)
                p = points[order[-1 - i]]
                drones.append(world.spawn_actor(bp, carla.Transform(p.location + carla.Location(z=0.2), p.rotation)))
            # Sensors on the cars (on drones when there are no cars).
            hosts = cars or drones
            for i in range(a.cameras + a.lidars):
                camera = i < a.cameras
                bp = library.find('sensor.camera.rgb' if camera else 'sensor.lidar.ray_cast')
                if camera:
                    bp.set_attribute('image_size_x', '320')
                    bp.set_attribute('image_size_y', '240')
                else:
                    bp.set_attribute('range', '50')
                    bp.set_attribute('rotation_frequency', '20')
                    bp.set_attribute('points_per_second', '20000')
                s = world.spawn_actor(bp, carla.Transform(carla.Location(x=1.5, z=2.4)), hosts[i % len(hosts)])
                key = '%s %d' % (bp.id, s.id)
                heard[key] = 0

                def on_data(data, key=key):
                    heard[key] += 1
                s.listen(on_data)
                sensors.append((key, s))
            world.tick()
            for ctl in controllers:
                ctl.start()
                ctl.go_to_location(world.get_random_location_from_navigation())
                ctl.set_max_speed(1.0 + self.rng.random())
            # Drones come to rest on the ground first (AirSim refuses a takeoff while moving).
            self.settle(20)
            names = ['soak%d' % i for i in range(len(drones))]
            for n in names:
                self.air.enableApiControl(True, n)
                self.air.armDisarm(True, n)
            for f in [self.air.takeoffAsync(vehicle_name=n) for n in names]:
                f.join()
            for i, n in enumerate(names):
                self.air.moveByVelocityAsync(2.0 * (1 - 2 * (i % 2)), 1.0, -0.5, a.ticks * 0.05, vehicle_name=n)
            self.settle(a.ticks)
            for key, n in heard.items():
                if n == 0:
                    self.error(c, '%s delivered no data in %d ticks' % (key, a.ticks))
            status = world._client.run_status() or {}
            if status.get('state') not in ('running', 'ready'):
                self.error(c, 'run state %s: %s' % (status.get('state'), status.get('reason')))
            for service, kind, alive, required in status.get('members', []):
                if not alive:
                    self.error(c, 'member %s (%s) is not alive' % (service, kind))
        except Exception as e:  # counted, then the cycle cleans up and the soak goes on
            self.error(c, '%s: %s' % (type(e).__name__, e))
        finally:
            for _, s in sensors:
                try:
                    s.stop()
                except Exception as e:
                    self.error(c, 'stop: %s' % e)
            for ctl in controllers:
                try:
                    ctl.stop()
                except Exception as e:
                    self.error(c, 'controller stop: %s' % e)
            try:
                batch = [carla.command.DestroyActor(x) for x in
                         [s for _, s in sensors] + controllers + walkers + cars + drones]
                for r in self.client.apply_batch_sync(batch, True):
                    if r.error:
                        self.error(c, 'destroy: %s' % r.error)
                if a.reset:
                    self.client.reload_world(False)
                    self.world = self.client.get_world()
                self.settle(2)
                left = [x.type_id for x in self.world.get_actors()
                        if x.type_id.split('.')[0] in ('vehicle', 'walker', 'sensor', 'drone', 'controller')]
                if left:
                    self.error(c, 'actors left after the cycle: %s' % ', '.join(sorted(set(left))))
            except Exception as e:
                self.error(c, 'cleanup: %s: %s' % (type(e).__name__, e))


def summarize(args, cycle_lines, series, log_path, started, aborted=None):
    errors = [e for line in cycle_lines for e in line['errors']]
    # Error lines of the simulation's log ([error] / [critical] from spdlog).
    for line in open(log_path, errors='replace'):
        if re.search(r'\[(error|critical)\]', line):
            errors.append('log: ' + line.strip()[:300])
    summary = {'bench': 'soak', 'cycles': len(cycle_lines), 'counted_cycles': max(0, len(cycle_lines) - args.warmup),
               'per_cycle': {'cars': args.cars, 'walkers': args.walkers, 'drones': args.drones,
                             'cameras': args.cameras, 'lidars': args.lidars, 'ticks': args.ticks + 21,
                             'reset': args.reset},
               'wall_s': round(time.time() - started, 1), 'rss_first_mib': {}, 'rss_last_mib': {}, 'drift_mib': {},
               'slope_mib_per_cycle': {}, 'max_mib': {}, 'errors': len(errors), 'error_list': errors[:20],
               'log': os.path.relpath(log_path, ROOT)}
    if aborted:
        summary['aborted'] = aborted
    failed = bool(errors) or len(cycle_lines) < args.cycles
    for name, ys in sorted(series.items()):
        summary['rss_first_mib'][name] = round(ys[0], 2)
        summary['rss_last_mib'][name] = round(ys[-1], 2)
        summary['drift_mib'][name] = round(ys[-1] - ys[0], 2)
        summary['slope_mib_per_cycle'][name] = round(slope(ys), 4)
        summary['max_mib'][name] = round(max(ys), 2)
        if args.max_drift is not None and ys[-1] - ys[0] > args.max_drift:
            failed = True
            summary.setdefault('over_limit', []).append('%s drift %.2f MiB > %.2f' % (name, ys[-1] - ys[0], args.max_drift))
        if args.max_slope is not None and slope(ys) > args.max_slope:
            failed = True
            summary.setdefault('over_limit', []).append('%s slope %.3f MiB/cycle > %.3f' % (name, slope(ys), args.max_slope))
    print(json.dumps(summary), flush=True)
    return 1 if failed or aborted else 0


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--cycles', type=int, default=20)
    ap.add_argument('--ticks', type=int, default=40, help='ticks each cycle drives and flies (after 21 to settle)')
    ap.add_argument('--cars', type=int, default=20)
    ap.add_argument('--walkers', type=int, default=10)
    ap.add_argument('--drones', type=int, default=2)
    ap.add_argument('--cameras', type=int, default=2)
    ap.add_argument('--lidars', type=int, default=1)
    ap.add_argument('--no-reset', dest='reset', action='store_false', help='no reload_world at the end of a cycle')
    ap.add_argument('--warmup', type=int, default=2, help='cycles before the first counted RSS sample')
    ap.add_argument('--max-drift', type=float, default=None, help='MiB: fail when a process drifts more')
    ap.add_argument('--max-slope', type=float, default=None, help='MiB per cycle: fail when a slope is steeper')
    ap.add_argument('--domain', type=int, default=None)
    ap.add_argument('--seed', type=int, default=21)
    ap.add_argument('--out', default=os.path.join(ROOT, 'out', 'soak'))
    args = ap.parse_args()
    domain = args.domain if args.domain is not None else free_domain()
    os.environ['LOCKSTEP_DOMAIN'] = str(domain)
    os.makedirs(args.out, exist_ok=True)
    services = [('air_sim', False)]
    for kind, perception in (('ground_sim', False), ('sensors', True), ('render', True)):
        if os.path.exists(os.path.join(BIN, 'lockstep_' + kind)):
            services.append((kind, perception))
    config = os.path.join(args.out, 'soak.yaml')
    write_config(config, domain, services, args.seed)
    log_path = os.path.join(args.out, 'soak.log')
    log = open(log_path, 'w')
    up = subprocess.Popen([os.path.join(BIN, 'lockstep'), 'up', config], stdout=log, stderr=subprocess.STDOUT)
    series = {}
    cycle_lines = []
    started = time.time()
    soak = None
    def watchdog():
        # A simulation that stopped (a failed service) can leave the client waiting for ever
        # (a drone command's join): the figures so far, then exit.
        up.wait()
        time.sleep(60)
        summarize(args, list(cycle_lines), dict(series), log_path, started,
                  aborted='lockstep up exited with %s during cycle %d' % (up.returncode, len(cycle_lines) + 1))
        os._exit(1)
    threading.Thread(target=watchdog, daemon=True).start()
    try:
        import lockstep
        native = lockstep.Client(domain=domain, timeout=60)
        if not native.wait_ready(120):
            sys.exit('bench soak: simulation not ready: %s' % open(log_path).read()[-2000:])
        soak = Soak(args)
        settings = soak.world.get_settings()
        settings.synchronous_mode = True
        settings.fixed_delta_seconds = 0.05
        soak.world.apply_settings(settings)
        for c in range(1, args.cycles + 1):
            t0 = time.time()
            before = len(soak.errors)
            soak.cycle(c)
            if up.poll() is not None:
                soak.error(c, 'lockstep up exited with %s' % up.returncode)
            pids = {'lockstep_up': up.pid, 'client': os.getpid()}
            for pid in children(up.pid):
                name = process_name(pid)
                if name:
                    pids[name] = pid
            rss = {}
            for name, pid in sorted(pids.items()):
                v = rss_mib(pid)
                if v is not None:
                    rss[name] = round(v, 2)
                    if c > args.warmup:
                        series.setdefault(name, []).append(v)
            line = {'cycle': c, 'wall_s': round(time.time() - t0, 2), 'at': time.strftime('%H:%M:%S'), 'rss_mib': rss,
                    'errors': soak.errors[before:]}
            print(json.dumps(line), flush=True)
            cycle_lines.append(line)
            if up.poll() is not None:
                break
    finally:
        del soak
        if up.poll() is None:
            up.send_signal(signal.SIGINT)
            try:
                up.wait(30)
            except subprocess.TimeoutExpired:
                up.kill()
                up.wait()
        log.close()
    return summarize(args, cycle_lines, series, log_path, started)


if __name__ == '__main__':
    sys.exit(main())
