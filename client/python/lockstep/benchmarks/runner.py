"""Run benchmark episodes on the public `carla` API: a simulation per town (or the one
already running), the agent, and per-frame measurements as CARLA 0.8's benchmark took them.

Per frame (10 frames per simulated second, as `-benchmark -fps=10`):
- `intersection_offroad` / `intersection_otherlane`: the car's bounding box sampled on a
  grid (`grid_m`, 0.8 used 0.1 m; default here 0.2 m) against the OpenDRIVE lanes: a sample
  off every driving/shoulder lane (on a sidewalk, a curb, outside the road) is off-road; a
  sample on a driving lane outside a junction whose direction of travel opposes the car's
  heading is on the other lane; both divided by the number of samples (0.8's
  `URoadMap::Intersect`; junctions have no direction there either).
- `collision_*`: |normal impulse| of the collision sensor's events, accumulated per kind of
  the other actor (vehicle.*, walker.*, anything else), registered only above 1 km/h as
  0.8's `OnCollisionEvent`.
"""
import csv
import math
import os
import random
import signal
import subprocess
import sys
import time

from . import metrics
from .episodes import find_map

HERE = os.path.dirname(os.path.abspath(__file__))

# CARLA 0.8's weather numbers -> today's presets: the 0.8 enum names (carla_settings.md) are
# the names of carla.WeatherParameters' presets, value for value.
WEATHERS = {1: 'ClearNoon', 2: 'CloudyNoon', 3: 'WetNoon', 4: 'WetCloudyNoon', 5: 'MidRainyNoon', 6: 'HardRainNoon',
            7: 'SoftRainNoon', 8: 'ClearSunset', 9: 'CloudySunset', 10: 'WetSunset', 11: 'WetCloudySunset',
            12: 'MidRainSunset', 13: 'HardRainSunset', 14: 'SoftRainSunset'}
TRAIN_WEATHERS = [1, 3, 6, 8]
TEST_WEATHERS = [4, 14]

ROAD_TYPES = (1 << 1) | (1 << 9) | (1 << 3)     # Driving, Bidirectional, Shoulder
DIRECTED_TYPES = (1 << 1) | (1 << 9)


def build_dir():
    env = os.environ.get('LOCKSTEP_BUILD_DIR')
    if env:
        return env
    # build/python/lockstep/benchmarks -> build
    return os.path.dirname(os.path.dirname(os.path.dirname(HERE)))


def agents_path():
    """Where CARLA's `agents` package is: $CARLA_AGENTS_PATH, else ../shared/compat beside the checkout."""
    env = os.environ.get('CARLA_AGENTS_PATH')
    cands = [env] if env else []
    root = os.path.dirname(build_dir())
    cands.append(os.path.join(root, '..', 'shared', 'compat', 'carla', 'PythonAPI', 'carla'))
    for c in cands:
        if c and os.path.isdir(os.path.join(c, 'agents')):
            return os.path.abspath(c)
    raise FileNotFoundError("CARLA's agents package not found (set CARLA_AGENTS_PATH to the folder holding agents/)")


class Simulation:
    """`lockstep up` with ground_sim and sensors (render too when `cameras`, air_sim when
    `air`), synchronous at `dt`, on a DDS domain; stopped by stop()."""

    def __init__(self, town, domain, out_dir, dt=0.1, seed=0, cameras=False, air=False, timeout=120):
        self.domain = domain
        bin_dir = os.path.join(build_dir(), 'bin')
        services = []
        kinds = (('ground_sim', False), ('sensors', True)) + ((('render', True),) if cameras else ()) + \
            ((('air_sim', False),) if air else ())
        for kind, perception in kinds:
            if not os.path.exists(os.path.join(bin_dir, 'lockstep_' + kind)):
                raise RuntimeError('lockstep_%s is not built (cmake --build build --target lockstep_%s)' % (kind, kind))
            services.append('  - {name: %s, kind: %s, perception: %s}' % (kind, kind, 'true' if perception else 'false'))
        os.makedirs(out_dir, exist_ok=True)
        self.config = os.path.join(out_dir, 'sim_%s.yaml' % os.path.basename(town).replace('.xodr', ''))
        with open(self.config, 'w') as f:
            f.write('\n'.join(['name: benchmark', 'domain_id: %d' % domain, 'seed: %d' % seed,
                               'map: %s' % find_map(town), 'world:', '  synchronous_mode: true',
                               '  fixed_delta_seconds: %g' % dt, '  service_timeout: 60', 'services:'] + services) + '\n')
        self.log_path = self.config.replace('.yaml', '.log')
        self.log = open(self.log_path, 'w')
        self.proc = subprocess.Popen([os.path.join(bin_dir, 'lockstep'), 'up', self.config, '--domain', str(domain)],
                                     stdout=self.log, stderr=subprocess.STDOUT, preexec_fn=_end_with_parent)
        import lockstep
        self.native = lockstep.Client(domain=domain, timeout=timeout)   # a loaded machine starts slowly
        if not self.native.wait_ready(timeout):
            self.stop()
            raise RuntimeError('simulation not ready: %s' % open(self.log_path).read()[-2000:])

    def stop(self):
        self.native = None
        stop_process(self.proc)
        self.log.close()


def stop_process(proc, grace_s=20.0):
    """Ctrl-C for a child (`lockstep up` stops its services and prints its summary), then
    SIGKILL if it is still there after grace_s; returns its exit status."""
    for sig, wait_s in ((signal.SIGINT, grace_s), (signal.SIGKILL, None)):
        if proc.poll() is not None:
            break
        proc.send_signal(sig)
        try:
            proc.wait(wait_s)
        except subprocess.TimeoutExpired:
            pass
    return proc.returncode


def out_dir(given, name):
    """`given`, else out/benchmarks/<name> beside the build folder; created."""
    out = given or os.path.join(os.path.dirname(build_dir()), 'out', 'benchmarks', name)
    os.makedirs(out, exist_ok=True)
    return out


def own_simulation(town, domain, out, **kwargs):
    """A Simulation on `domain`, which this process's carla and airsim clients then use."""
    os.environ['LOCKSTEP_DOMAIN'] = str(domain)
    return Simulation(town, domain, out, **kwargs)


def drone_beside(ctx, location, yaw_deg, role_name, side_m=6.0):
    """A drone.generic_quad `side_m` to the right of a pose on the road (clear of the lane,
    CARLA's y grows to the right of a car at yaw 0); returns (drone, its spawn transform)."""
    carla = ctx.carla
    yaw = math.radians(yaw_deg)
    spawn = carla.Transform(carla.Location(location.x - side_m * math.sin(yaw), location.y + side_m * math.cos(yaw),
                                           location.z + 0.2), carla.Rotation(yaw=yaw_deg))
    bp = ctx.lib.find('drone.generic_quad')
    bp.set_attribute('role_name', role_name)
    return ctx.world.spawn_actor(bp, spawn), spawn


def take_off(air, name):
    air.enableApiControl(True, name)
    air.armDisarm(True, name)
    air.takeoffAsync(vehicle_name=name).join()


def ned(spawn, loc, up=0.0):
    """AirSim's NED position (from the drone's spawn) of a CARLA location `up` m above it."""
    return (spawn.location.y - loc.y, loc.x - spawn.location.x, -(loc.z + up - spawn.location.z))


def ned_velocity(v):
    return (-v.y, v.x, -v.z)


def release(ctx, actors, air=None, drone_name=None):
    """The end of a run with a drone: API control given back (the drone may be gone), the
    actors destroyed, one tick so that they are gone."""
    if air is not None:
        try:
            air.enableApiControl(False, drone_name)
        except Exception:  # noqa: BLE001 - the drone may be gone
            pass
    destroy(ctx, actors)
    ctx.world.tick()


def workload_args(ap, connect=True):
    """The options every workload's command has: --domain, --out (and --connect)."""
    ap.add_argument('--domain', type=int, default=int(os.environ.get('LOCKSTEP_DOMAIN', '0') or 0))
    if connect:
        ap.add_argument('--connect', action='store_true', help='use the simulation already running')
    ap.add_argument('--out', default='')
    return ap


class SimulationEnv:
    """What the environments share: reseeding, and close() that clears the episode's actors
    and stops the environment's own simulation (none with connect=True)."""
    ctx = sim = None

    def _clear(self):
        pass

    def _reseed(self, seed):
        if seed is not None:
            self._rng = random.Random(seed)
            self.action_space.seed(seed)
            self.observation_space.seed(seed)

    def close(self):
        try:
            if self.ctx is not None:
                self._clear()
        finally:
            self.ctx = None
            if self.sim is not None:
                self.sim.stop()
                self.sim = None


def _end_with_parent():
    import ctypes
    ctypes.CDLL('libc.so.6', use_errno=True).prctl(1, signal.SIGINT)  # PR_SET_PDEATHSIG


class Footprint:
    """The 0.8 road-map intersection of the car's bounding box, on the OpenDRIVE lanes."""

    def __init__(self, carla_map, extent, grid_m=0.2):
        self.native = carla_map._native
        if not (extent.x > 0 and extent.y > 0 and grid_m > 0):
            raise ValueError('footprint: the bounding box extent (%g, %g) and the grid step %g must be positive'
                             % (extent.x, extent.y, grid_m))
        xs = _grid(extent.x, grid_m)
        ys = _grid(extent.y, grid_m)
        self.samples = [(x, y) for x in xs for y in ys]

    def measure(self, transform):
        """(offroad, otherlane) fractions for a carla.Transform."""
        yaw = math.radians(transform.rotation.yaw)
        c, s = math.cos(yaw), math.sin(yaw)
        lx, ly, lz = transform.location.x, transform.location.y, transform.location.z
        off = other = 0
        wp = self.native.waypoint
        for x, y in self.samples:
            px = lx + c * x - s * y
            py = ly + s * x + c * y
            w = wp(px, -py, lz, False, 0x7FFFFFFE)
            if w is None or not (w.lane_type & ROAD_TYPES):
                off += 1
            elif w.junction < 0 and (w.lane_type & DIRECTED_TYPES):
                lane_yaw = -w.pose[3]   # CARLA's yaw of the lane's direction of travel
                if math.cos(lane_yaw) * c + math.sin(lane_yaw) * s < 0.0:
                    other += 1
        n = len(self.samples)
        return off / n, other / n


def _grid(half, step):
    # -half, -half + step, ... < half: 0.8's `for (X = -Extent; X < Extent; X += Step)`.
    out = []
    v = -half
    while v < half - 1e-9:
        out.append(v)
        v += step
    return out


def collision_kind(other):
    t = getattr(other, 'type_id', '') or ''
    if t.startswith('vehicle.'):
        return 'collision_vehicles'
    if t.startswith('walker.'):
        return 'collision_pedestrians'
    return 'collision_other'


# ---------------------------------------------------------------- agents

class AutopilotAgent:
    """The privileged autopilot: CARLA's Traffic Manager drives the car along the episode's
    route (TrafficManager.set_path through the route's points). `ignore_lights`: the CoRL
    2017 protocol lets agents ignore traffic lights (TrafficManager.ignore_lights_percentage
    100); by default it stops at red lights like the other cars."""

    def __init__(self, ignore_lights=False):
        self.ignore_lights = ignore_lights
        self.name = 'autopilot-ignore-lights' if ignore_lights else 'autopilot'

    def setup(self, ctx, ego, episode):
        import carla
        tm = ctx.client.get_trafficmanager()
        ego.set_autopilot(True, tm.get_port())
        tm.auto_lane_change(ego, False)   # a lane change drops the path
        if self.ignore_lights:
            tm.ignore_lights_percentage(ego, 100.0)
        ctx.world.tick()                  # the autopilot takes the car first, then its path
        # Leading points within 10 m of the car may already lie behind it (the TM keeps a few
        # metres of its own path first): a route to them would go round the block.
        here = ego.get_location()
        pts = list(episode['path'])
        while len(pts) > 1 and math.hypot(pts[0][0] - here.x, pts[0][1] - here.y) < 10.0:
            pts.pop(0)
        tm.set_path(ego, [carla.Location(*p) for p in pts][:256])

    def step(self, ego):
        return None


class CarlaAgent:
    """CARLA's BasicAgent or BehaviorAgent (PythonAPI/carla/agents, unmodified, imported from
    CARLA_AGENTS_PATH or ../shared/compat), with the goal as its destination."""

    def __init__(self, kind, target_speed=None, behavior='normal', ignore_lights=False):
        self.name = kind + ('-ignore-lights' if ignore_lights else '')
        self.kind = kind
        self.ignore_lights = ignore_lights
        self.target_speed = target_speed
        self.behavior = behavior
        p = agents_path()
        if p not in sys.path:
            sys.path.append(p)

    def setup(self, ctx, ego, episode):
        import carla
        # The destination lies 5 m past the goal along its lane: the agents' local planner
        # stops short of its last waypoint (by its min distance), which would leave the car
        # outside the 2 m of success in front of a goal it has reached.
        goal = carla.Location(*episode['goal'][:3])
        past = ctx.map.get_waypoint(goal).next(5.0)
        if past:
            goal = past[0].transform.location
        if self.kind == 'basic':
            from agents.navigation.basic_agent import BasicAgent
            opt = {'ignore_traffic_lights': True} if self.ignore_lights else {}
            self.agent = BasicAgent(ego, target_speed=self.target_speed or 20, opt_dict=opt)
        else:
            from agents.navigation.behavior_agent import BehaviorAgent
            self.agent = BehaviorAgent(ego, behavior=self.behavior)
            if self.ignore_lights:
                self.agent.ignore_traffic_lights(True)
        self.agent.set_destination(goal)

    def step(self, ego):
        control = self.agent.run_step()
        ego.apply_control(control)
        return control


CAMERA_AGENTS = ('modular',)   # agents that drive from cameras: their simulation runs render too


def make_agent(name, ignore_lights=False):
    if name == 'autopilot':
        return AutopilotAgent(ignore_lights)
    if name in ('basic', 'behavior'):
        return CarlaAgent(name, ignore_lights=ignore_lights)
    if name == 'modular':
        from .modular import ModularAgent
        return ModularAgent()   # ignores lights always, as the CoRL 2017 protocol allows
    raise ValueError("unknown agent '%s' (autopilot, basic, behavior, modular)" % name)


# ---------------------------------------------------------------- episodes

class Context:
    """A connected carla client and world at the benchmark's frame rate."""

    def __init__(self, dt=0.1, grid_m=0.2):
        import carla
        self.carla = carla
        self.client = carla.Client('localhost', 2000)
        self.client.set_timeout(60.0)
        self.world = self.client.get_world()
        self.world._client.wait_ready(120)
        s = self.world.get_settings()
        s.synchronous_mode = True
        s.fixed_delta_seconds = dt
        self.world.apply_settings(s)
        self.map = self.world.get_map()
        self.lib = self.world.get_blueprint_library()
        self.grid_m = grid_m
        self.dt = dt

    def ego_blueprint(self):
        bps = self.lib.filter('vehicle.*')
        bp = (self.lib.filter('vehicle.lincoln.mkz*') or self.lib.filter('vehicle.audi.a2') or bps)[0]
        bp.set_attribute('role_name', 'hero')
        return bp


def spawn_traffic(ctx, rng, vehicles, walkers, avoid, radius=15.0):
    """NPC vehicles under the Traffic Manager at spawn points away from `avoid` (the ego's
    start), and pedestrians with CARLA's walker AI; returns the actors to destroy."""
    carla = ctx.carla
    actors = []
    if vehicles:
        points = [p for p in ctx.map.get_spawn_points()
                  if math.hypot(p.location.x - avoid[0], p.location.y - avoid[1]) > radius]
        rng.shuffle(points)
        bps = [b for b in ctx.lib.filter('vehicle.*') if int(b.get_attribute('number_of_wheels').as_int()
                                                              if b.has_attribute('number_of_wheels') else 4) == 4]
        port = ctx.client.get_trafficmanager().get_port()
        batch = [carla.command.SpawnActor(rng.choice(bps), t).then(carla.command.SetAutopilot(carla.command.FutureActor,
                                                                                              True, port))
                 for t in points[:vehicles]]
        for r in ctx.client.apply_batch_sync(batch, True):
            if not r.error:
                actors.append(ctx.world.get_actor(r.actor_id))
    if walkers:
        wbps = ctx.lib.filter('walker.pedestrian.*')
        cbp = ctx.lib.find('controller.ai.walker')
        ws = []
        for _ in range(walkers):
            loc = ctx.world.get_random_location_from_navigation()
            if loc is None:
                continue
            w = ctx.world.try_spawn_actor(rng.choice(wbps), carla.Transform(loc + carla.Location(z=1.0)))
            if w is not None:
                ws.append(w)
        ctx.world.tick()
        for w in ws:
            c = ctx.world.spawn_actor(cbp, carla.Transform(), w)
            actors += [c, w]
        ctx.world.tick()
        for a in actors:
            if a.type_id == 'controller.ai.walker':
                a.start()
                loc = ctx.world.get_random_location_from_navigation()
                if loc is not None:
                    a.go_to_location(loc)
                a.set_max_speed(1.0 + rng.random() * 0.5)
    return [a for a in actors if a is not None]


def destroy(ctx, actors):
    carla = ctx.carla
    controllers = [a for a in actors if a.type_id == 'controller.ai.walker']
    for c in controllers:
        try:
            c.stop()
        except Exception:  # noqa: BLE001 - a walker already gone
            pass
    ids = [a.id for a in actors]
    if ids:
        ctx.client.apply_batch_sync([carla.command.DestroyActor(i) for i in ids], True)


def run_episode(ctx, agent, episode, *, task, weather, vehicles=0, walkers=0, collision_as_failure=False,
                time_out=None, success_m=2.0, seed=0, log_path=None, settle_ticks=10, max_frames=None, dynamic=None):
    """One episode. Returns (summary, rows): the summary dict (0.8's summary.csv fields and
    ours: `end` is 'success', 'time-out', 'collision' or 'max-frames') and the per-frame
    measurement rows, also written to `log_path` (CSV) when given. Collisions count as
    infractions in dynamic tasks (`dynamic`, default: with vehicles or walkers), as in 0.8;
    `collision_as_failure` ends the episode at the first (NoCrash)."""
    carla = ctx.carla
    rng = random.Random('%s-%s-%s-%s' % (seed, task, weather, episode['id']))
    ctx.world.set_weather(getattr(carla.WeatherParameters, WEATHERS[weather]))
    sx, sy, sz, syaw = episode['start']
    gx, gy = episode['goal'][0], episode['goal'][1]
    ego = ctx.world.spawn_actor(ctx.ego_blueprint(), carla.Transform(carla.Location(sx, sy, sz + 0.3),
                                                                     carla.Rotation(yaw=syaw)))
    sensor = ctx.world.spawn_actor(ctx.lib.find('sensor.other.collision'), carla.Transform(), attach_to=ego)
    events = []
    sensor.listen(lambda e: events.append((collision_kind(e.other_actor), e.normal_impulse.length())))
    actors = []
    rows = []
    result = {'exp_id': task, 'weather': weather, 'start_point': episode.get('start_index', -1),
              'end_point': episode.get('goal_index', -1), 'episode': episode['id'],
              'initial_distance': round(math.hypot(sx - gx, sy - gy), 3), 'route_m': episode['route_m']}
    wall0 = time.time()
    try:
        ctx.world.tick()
        actors = spawn_traffic(ctx, rng, vehicles, walkers, (sx, sy))
        for _ in range(settle_ticks):
            ctx.world.tick()
        foot = Footprint(ctx.map, ego.bounding_box.extent, ctx.grid_m)
        agent.setup(ctx, ego, episode)
        limit = time_out if time_out is not None else metrics.time_out_s(episode['route_m'])
        acc = {'collision_vehicles': 0.0, 'collision_pedestrians': 0.0, 'collision_other': 0.0}
        t0 = ctx.world.get_snapshot().timestamp.elapsed_seconds
        del events[:]
        end, reason = None, None
        while True:
            control = agent.step(ego)
            frame = ctx.world.tick()
            now = ctx.world.get_snapshot().timestamp.elapsed_seconds - t0
            tr = ego.get_transform()
            speed = ego.get_velocity().length() * 3.6
            pending, events[:] = list(events), []
            if speed > 1.0:   # 0.8 registers a collision only above 1 km/h
                for kind, impulse in pending:
                    acc[kind] += impulse
            off, other = foot.measure(tr)
            d = math.hypot(tr.location.x - gx, tr.location.y - gy)
            row = {'frame': frame, 'time_s': round(now, 3), 'pos_x': tr.location.x, 'pos_y': tr.location.y,
                   'yaw': tr.rotation.yaw, 'speed_kmh': speed, 'intersection_offroad': off,
                   'intersection_otherlane': other, 'distance_to_goal': d,
                   'steer': getattr(control, 'steer', ''), 'throttle': getattr(control, 'throttle', ''),
                   'brake': getattr(control, 'brake', '')}
            row.update(acc)
            rows.append(row)
            if d < success_m:
                end, reason = 1, 'success'
            elif collision_as_failure and len(rows) > 1 and metrics.has_collided(rows[-2], row):
                end, reason = 0, 'collision'
            elif now > limit:
                end, reason = 0, 'time-out'
            elif max_frames is not None and len(rows) >= max_frames:
                end, reason = 0, 'max-frames'
            if end is not None:
                break
        result.update({'result': end, 'end': reason, 'time_out': round(limit, 3),
                       'final_time': round(now if end else limit, 3), 'final_distance': round(d, 3),
                       'frames': len(rows), 'wall_s': round(time.time() - wall0, 3)})
    finally:
        if hasattr(agent, 'teardown'):
            agent.teardown(ctx)   # the agent's own sensors
        try:
            sensor.stop()
        except Exception:  # noqa: BLE001
            pass
        destroy(ctx, actors + [sensor, ego])
        ctx.world.tick()
    if dynamic is None:
        dynamic = vehicles > 0 or walkers > 0
    inf = metrics.episode_infractions(rows, dynamic)
    result.update(inf)
    result['km'] = round(metrics.distance_km(rows), 5)
    result['collided_as_failure'] = reason == 'collision'
    if getattr(agent, 'stats', None):
        result['agent_stats'] = ' '.join('%s=%d' % (k.replace(' ', '_'), v) for k, v in agent.stats.items())
    if log_path:
        keys = list(rows[0].keys()) if rows else ['frame']
        with open(log_path, 'w', newline='') as f:
            w = csv.DictWriter(f, fieldnames=keys)
            w.writeheader()
            for r in rows:
                w.writerow({k: (round(v, 4) if isinstance(v, float) else v) for k, v in r.items()})
    return result, rows
