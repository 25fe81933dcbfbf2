"""A Gymnasium-style driving environment on the public `carla` API, with the reward of the
CARLA paper's reinforcement-learning agent (Dosovitskiy et al. 2017, §4):

    r = 1000 (d_{t-1} - d_t) + 0.05 (v_t - v_{t-1}) - 0.00002 (c_t - c_{t-1})
        - 2 (s_t - s_{t-1}) - 2 (o_t - o_{t-1})

d: distance to the goal along the route (km), v: speed (km/h), c: collision damage (the
accumulated |normal impulse| of the collision sensor, kg m/s), s / o: the fraction of the
car's footprint on the sidewalk (off-road) / on the opposite lane (runner.Footprint).

    env = DrivingEnv('Town01', domain=83)             # starts its own simulation
    obs, info = env.reset(seed=0)
    obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
    env.close()

Episodes are the CoRL 2017 episodes of the town (`task`, default Navigation). terminated:
the goal within 2 m, or a collision (terminate_on_collision); truncated: the CoRL time-out
(10 km/h + 10 s of route) or max_steps. `info['reward_terms']` holds each term.

One process talks to one DDS domain (the carla module's session follows
$LOCKSTEP_DOMAIN), so N environments run in N processes, each with its own simulation on
its own domain: `VectorEnv(n, base_domain=...)`."""
import math
import multiprocessing
import os
import random

import numpy as np

from . import episodes as episodes_mod
from . import runner
from .route import RouteProgress, command
from .spaces import Box, Dict, Discrete

REWARD_WEIGHTS = {'distance': 1000.0, 'speed': 0.05, 'collision': -0.00002, 'sidewalk': -2.0, 'opposite_lane': -2.0}
COMMANDS = ['follow_lane', 'left', 'right', 'straight']   # CIL's high-level commands


def driving_reward(prev, now, weights=REWARD_WEIGHTS):
    """(reward, terms) from two measurement dicts with distance_km, speed_kmh,
    collision_damage, offroad, otherlane."""
    terms = {'distance': weights['distance'] * (prev['distance_km'] - now['distance_km']),
             'speed': weights['speed'] * (now['speed_kmh'] - prev['speed_kmh']),
             'collision': weights['collision'] * (now['collision_damage'] - prev['collision_damage']),
             'sidewalk': weights['sidewalk'] * (now['offroad'] - prev['offroad']),
             'opposite_lane': weights['opposite_lane'] * (now['otherlane'] - prev['otherlane'])}
    return sum(terms.values()), terms


def _wrap_deg(a):
    return (a + 180.0) % 360.0 - 180.0


class DrivingEnv(runner.SimulationEnv):
    metadata = {'render_modes': []}

    def __init__(self, town='Town01', domain=None, connect=False, task='Navigation', vehicles=0, walkers=0,
                 weather=1, max_steps=None, terminate_on_collision=True, grid_m=0.4, out_dir=None, seed=None):
        if domain is not None:
            os.environ['LOCKSTEP_DOMAIN'] = str(int(domain))
        self.domain = int(os.environ.get('LOCKSTEP_DOMAIN', '0') or 0)
        self.sim = None
        if not connect:
            import tempfile
            self.sim = runner.Simulation(town, self.domain, out_dir or tempfile.mkdtemp(prefix='lockstep-env-'), dt=0.1)
        self.ctx = runner.Context(dt=0.1, grid_m=grid_m)
        _, tasks = episodes_mod.load(town)
        if task not in tasks:
            raise ValueError("task '%s': one of %s" % (task, ', '.join(tasks)))
        self.episodes = tasks[task]
        self.vehicles, self.walkers, self.weather = vehicles, walkers, weather
        self.max_steps = max_steps
        self.terminate_on_collision = terminate_on_collision
        self.action_space = Box(np.array([-1.0, 0.0, 0.0]), np.array([1.0, 1.0, 1.0]), dtype=np.float32, seed=seed)
        inf = np.float32(np.inf)
        # speed m/s, distance to goal m, heading error to the route deg, offroad, otherlane,
        # collision damage kg m/s, route completion 0..1
        self.observation_space = Dict({
            'measurements': Box(np.array([-inf, 0, -180, 0, 0, 0, 0], dtype=np.float32),
                                np.array([inf, inf, 180, 1, 1, inf, 1], dtype=np.float32), dtype=np.float32),
            'command': Discrete(len(COMMANDS))}, seed=seed)
        self._actors = []
        self.ego = None
        self._rng = random.Random(seed)

    # -- the episode's actors
    def _clear(self):
        if self._actors:
            for a in self._actors:
                if a.type_id.startswith('sensor.'):
                    try:
                        a.stop()
                    except Exception:  # noqa: BLE001
                        pass
            runner.destroy(self.ctx, self._actors)
            self.ctx.world.tick()
        self._actors, self.ego = [], None

    def reset(self, seed=None, options=None):
        carla = self.ctx.carla
        self._reseed(seed)
        self._clear()
        options = options or {}
        idx = options.get('episode', self._rng.randrange(len(self.episodes)))
        self.episode = self.episodes[idx]
        sx, sy, sz, syaw = self.episode['start']
        self.ctx.world.set_weather(getattr(carla.WeatherParameters, runner.WEATHERS[self.weather]))
        self.ego = self.ctx.world.spawn_actor(self.ctx.ego_blueprint(),
                                              carla.Transform(carla.Location(sx, sy, sz + 0.3), carla.Rotation(yaw=syaw)))
        sensor = self.ctx.world.spawn_actor(self.ctx.lib.find('sensor.other.collision'), carla.Transform(),
                                            attach_to=self.ego)
        self._events = []
        sensor.listen(lambda e: self._events.append(e.normal_impulse.length()))
        self._actors = [sensor, self.ego]
        self.ctx.world.tick()
        self._actors += runner.spawn_traffic(self.ctx, self._rng, self.vehicles, self.walkers, (sx, sy))
        for _ in range(10):
            self.ctx.world.tick()
        self.foot = runner.Footprint(self.ctx.map, self.ego.bounding_box.extent, self.ctx.grid_m)
        self.progress = RouteProgress(self.episode)
        self.damage = 0.0
        self.steps = 0
        self.time_out = runner.metrics.time_out_s(self.episode['route_m'])
        self.t0 = self.ctx.world.get_snapshot().timestamp.elapsed_seconds
        del self._events[:]
        self.m = self._measure()
        return self._obs(), self._info(None)

    def _measure(self):
        tr = self.ego.get_transform()
        v = self.ego.get_velocity().length()
        pending, self._events[:] = list(self._events), []
        if v * 3.6 > 1.0:
            self.damage += sum(pending)
        off, other = self.foot.measure(tr)
        remaining = self.progress.update(tr.location.x, tr.location.y)
        gx, gy = self.episode['goal'][0], self.episode['goal'][1]
        return {'x': tr.location.x, 'y': tr.location.y, 'yaw': tr.rotation.yaw, 'speed_kmh': v * 3.6,
                'distance_km': remaining / 1000.0, 'goal_m': math.hypot(tr.location.x - gx, tr.location.y - gy),
                'collision_damage': self.damage, 'offroad': off, 'otherlane': other}

    def _command(self):
        return command(self.progress, self.ctx.map, self.m['x'], self.m['y'], self.ctx.carla.Location)

    def _obs(self):
        m = self.m
        err = _wrap_deg(self.progress.heading_ahead(5.0) - m['yaw'])
        meas = np.array([m['speed_kmh'] / 3.6, m['distance_km'] * 1000.0, err, m['offroad'], m['otherlane'],
                         m['collision_damage'], self.progress.along / max(self.progress.total, 1e-9)],
                        dtype=np.float32)
        return {'command': self._command(), 'measurements': meas}

    def _info(self, terms):
        return {'episode': self.episode['id'], 'goal_m': self.m['goal_m'], 'reward_terms': terms,
                'measurements': dict(self.m), 'steps': self.steps}

    def step(self, action):
        carla = self.ctx.carla
        a = np.asarray(action, dtype=np.float64).reshape(-1)
        if a.shape != (3,) or not np.all(np.isfinite(a)):
            raise ValueError('action: [steer, throttle, brake], finite, got %r' % (action,))
        a = np.clip(a, self.action_space.low, self.action_space.high)
        self.ego.apply_control(carla.VehicleControl(steer=float(a[0]), throttle=float(a[1]), brake=float(a[2])))
        self.ctx.world.tick()
        self.steps += 1
        prev, self.m = self.m, self._measure()
        reward, terms = driving_reward(prev, self.m)
        now = self.ctx.world.get_snapshot().timestamp.elapsed_seconds - self.t0
        collided = self.m['collision_damage'] - prev['collision_damage'] > 0
        terminated = self.m['goal_m'] < 2.0 or (self.terminate_on_collision and collided)
        truncated = not terminated and (now > self.time_out or (self.max_steps is not None and self.steps >= self.max_steps))
        info = self._info(terms)
        info['success'] = self.m['goal_m'] < 2.0
        info['collision'] = collided
        return self._obs(), float(reward), bool(terminated), bool(truncated), info



from .follow import DroneFollowEnv  # noqa: E402 - the drone's environment, beside the car's

ENVS = {'driving': DrivingEnv, 'drone_follow': DroneFollowEnv}


def _worker(conn, domain, kwargs, kind='driving'):
    os.environ['LOCKSTEP_DOMAIN'] = str(domain)
    env = None
    try:
        env = ENVS[kind](domain=domain, **kwargs)
        conn.send(('ok', (env.observation_space, env.action_space)))
        while True:
            cmd, arg = conn.recv()
            if cmd == 'reset':
                conn.send(('ok', env.reset(**arg)))
            elif cmd == 'step':
                conn.send(('ok', env.step(arg)))
            elif cmd == 'close':
                break
    except Exception as e:  # noqa: BLE001 - reported to the parent
        conn.send(('error', '%s: %s' % (type(e).__name__, e)))
    finally:
        if env is not None:
            env.close()
        conn.close()


class VectorEnv:
    """N environments (`env`: 'driving', DrivingEnv, or 'drone_follow', follow.DroneFollowEnv),
    each in its own process with its own simulation on its own DDS domain (base_domain + i,
    or the list `domains`). reset/step take and return lists."""

    def __init__(self, n, base_domain=None, domains=None, env='driving', **kwargs):
        if env not in ENVS:
            raise ValueError("VectorEnv: env '%s' is one of %s" % (env, ', '.join(ENVS)))
        if domains is None:
            if base_domain is None:
                raise ValueError('VectorEnv: base_domain or domains')
            domains = [base_domain + i for i in range(n)]
        if len(domains) != n or len(set(domains)) != n:
            raise ValueError('VectorEnv: %d distinct domains needed, got %r' % (n, domains))
        ctx = multiprocessing.get_context('spawn')
        self.domains = list(domains)
        self.conns, self.procs = [], []
        spaces = []
        for d in self.domains:
            # One at a time: N simulations starting at once on a small machine time out.
            parent, child = ctx.Pipe()
            p = ctx.Process(target=_worker, args=(child, d, kwargs, env), daemon=True)
            p.start()
            child.close()
            self.conns.append(parent)
            self.procs.append(p)
            spaces.append(self._recv(parent))
        self.observation_space, self.action_space = spaces[0]
        self.num_envs = n

    def _recv(self, conn):
        status, value = conn.recv()
        if status != 'ok':
            self.close()
            raise RuntimeError('environment process failed: %s' % value)
        return value

    def reset(self, seed=None):
        for i, c in enumerate(self.conns):
            c.send(('reset', {'seed': None if seed is None else seed + i}))
        return [self._recv(c) for c in self.conns]

    def step(self, actions):
        for c, a in zip(self.conns, actions):
            c.send(('step', a))
        return [self._recv(c) for c in self.conns]

    def close(self):
        for c in self.conns:
            try:
                c.send(('close', None))
            except (OSError, BrokenPipeError):
                pass
        for p in self.procs:
            p.join(60)
            if p.is_alive():
                p.terminate()
        self.conns, self.procs = [], []
