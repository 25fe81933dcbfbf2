"""CARLA-Air's drone-follow RL workload: a Gymnasium-style environment where a drone (the
`airsim` API) keeps an offset above a car the Traffic Manager drives (the `carla` API), in
one synchronous world (ground_sim and air_sim at 20 ticks per simulated second), and a
policy-search trainer (the cross-entropy method) for it.

    env = DroneFollowEnv(domain=85)                      # its own simulation
    obs, info = env.reset(seed=0)
    obs, reward, terminated, truncated, info = env.step(env.action_space.sample())

- *Observation* (Box(9,), the car's heading frame: x forward, y right, z up): the error
  drone - (car + offset) (m), the car's velocity (m/s), the drone's velocity relative to
  the car (m/s).
- *Action* (Box(3,) in [-1, 1]): the drone's velocity command in the car's heading frame,
  times `max_speed` (m/s), sent as AirSim's moveByVelocityAsync each tick.
- *Reward*: `-|error| / 10` per tick (`distance`); when the drone is lost (error over 20 m,
  or a collision) the episode ends (terminated) and `lost` charges the error limit's cost,
  `-2`, for every tick left, so that ending early never pays better than following badly;
  `truncated` after `max_steps`. `info['reward_terms']` has each term.
- *Episode*: one of Town01's CoRL Straight or One-turn routes (seeded), the car at 15-25
  km/h along it (lights ignored), the drone taking off 6 m beside the car's start, so it
  starts some 8 m from its station and has to catch up.

Training (`python -m lockstep.benchmarks.follow --iterations 6`): the cross-entropy method
over a linear policy with three gains, `v = k_v v_car - k_e e` horizontally and
`v_z = -k_z e_z`, every candidate scored on the same seeded episodes (common random
numbers); writes the learning curve (`follow.json`, `follow.png`)."""
import argparse
import json
import math
import os
import random
import sys
import time

import numpy as np

from . import episodes as episodes_mod
from . import runner
from .spaces import Box

DT = 0.05
LOST_M = 20.0


def follow_reward(error_m, lost, ticks_left=0):
    """-error/10 per tick; a lost drone pays the error limit's cost for every tick left (so
    that ending an episode early never pays better than following badly)."""
    terms = {'distance': -error_m / 10.0, 'lost': -(LOST_M / 10.0) * ticks_left if lost else 0.0}
    return sum(terms.values()), terms


class DroneFollowEnv(runner.SimulationEnv):
    metadata = {'render_modes': []}

    def __init__(self, town='Town01', domain=None, connect=False, offset=(0.0, 0.0, 8.0), max_steps=200,
                 max_speed=10.0, out_dir=None, seed=None):
        if domain is not None:
            os.environ['LOCKSTEP_DOMAIN'] = str(int(domain))
        self.domain = int(os.environ.get('LOCKSTEP_DOMAIN', '0') or 0)
        self.sim = None
        if not connect:
            import tempfile
            self.sim = runner.Simulation(town, self.domain, out_dir or tempfile.mkdtemp(prefix='lockstep-follow-'),
                                         dt=DT, air=True)
        import airsim
        self.ctx = runner.Context(dt=DT)
        self.air = airsim.MultirotorClient()
        _, tasks = episodes_mod.load(town)
        self.routes = tasks['Straight'] + tasks['One turn']
        self.offset = np.asarray(offset, dtype=np.float64)
        self.max_steps, self.max_speed = int(max_steps), float(max_speed)
        self.action_space = Box(-1.0, 1.0, shape=(3,), dtype=np.float32, seed=seed)
        self.observation_space = Box(-np.inf, np.inf, shape=(9,), dtype=np.float32, seed=seed)
        self._rng = random.Random(seed)
        self._actors = []
        self._count = 0
        self.car = self.drone = None

    def _clear(self):
        if self._actors:
            runner.release(self.ctx, self._actors, self.air, self.name)
        self._actors, self.car, self.drone = [], None, None

    def reset(self, seed=None, options=None):
        carla = self.ctx.carla
        self._reseed(seed)
        self._clear()
        options = options or {}
        ep = self.routes[options.get('route', self._rng.randrange(len(self.routes)))]
        speed = options.get('car_kmh', self._rng.uniform(15.0, 25.0))
        sx, sy, sz, syaw = ep['start']
        self.car = self.ctx.world.spawn_actor(self.ctx.ego_blueprint(), carla.Transform(
            carla.Location(sx, sy, sz + 0.3), carla.Rotation(yaw=syaw)))
        self._actors.append(self.car)
        self._count += 1
        self.name = 'follower%d' % self._count
        self.drone, _ = runner.drone_beside(self.ctx, carla.Location(sx, sy, sz), syaw, self.name)
        self._actors.append(self.drone)
        for _ in range(10):
            self.ctx.world.tick()
        runner.take_off(self.air, self.name)
        tm = self.ctx.client.get_trafficmanager()
        self.car.set_autopilot(True, tm.get_port())
        tm.auto_lane_change(self.car, False)
        tm.ignore_lights_percentage(self.car, 100.0)
        tm.set_desired_speed(self.car, speed)
        self.ctx.world.tick()
        tm.set_path(self.car, [carla.Location(*p) for p in ep['path']
                               if math.hypot(p[0] - sx, p[1] - sy) > 10.0][:256] or [carla.Location(*ep['goal'][:3])])
        self.air.simGetCollisionInfo(vehicle_name=self.name)
        self._stamp0 = self._collision_stamp()
        self.steps = 0
        self.route = ep['id']
        obs, err = self._observe()
        return obs, {'route': ep['id'], 'car_kmh': speed, 'error_m': err, 'reward_terms': None}

    def _collision_stamp(self):
        info = self.air.simGetCollisionInfo(vehicle_name=self.name)
        return info.time_stamp if info.has_collided else 0

    def _frame(self):
        """The car's heading frame: (forward, right, up) unit vectors in CARLA's axes."""
        yaw = math.radians(self.car.get_transform().rotation.yaw)
        return np.array([[math.cos(yaw), math.sin(yaw), 0.0], [-math.sin(yaw), math.cos(yaw), 0.0], [0.0, 0.0, 1.0]])

    def _observe(self):
        c, d = self.car.get_location(), self.drone.get_location()
        cv, dv = self.car.get_velocity(), self.drone.get_velocity()
        R = self._frame()
        e = R @ np.array([d.x - c.x, d.y - c.y, d.z - c.z]) - self.offset
        vc = R @ np.array([cv.x, cv.y, cv.z])
        vr = R @ np.array([dv.x - cv.x, dv.y - cv.y, dv.z - cv.z])
        self._error = float(np.linalg.norm(e))
        return np.concatenate([e, vc, vr]).astype(np.float32), self._error

    def step(self, action):
        a = np.asarray(action, dtype=np.float64).reshape(-1)
        if a.shape != (3,) or not np.all(np.isfinite(a)):
            raise ValueError('action: 3 finite velocities in [-1, 1] (forward, right, up), got %r' % (action,))
        a = np.clip(a, -1.0, 1.0) * self.max_speed
        v = self._frame().T @ a                            # CARLA's axes
        # AirSim's NED from CARLA's axes: north = -y, east = x, down = -z.
        self.air.moveByVelocityAsync(-v[1], v[0], -v[2], 2 * DT, vehicle_name=self.name)
        self.ctx.world.tick()
        self.steps += 1
        obs, err = self._observe()
        lost = err > LOST_M or self._collision_stamp() > self._stamp0
        reward, terms = follow_reward(err, lost, max(0, self.max_steps - self.steps))
        truncated = not lost and self.steps >= self.max_steps
        return obs, float(reward), bool(lost), bool(truncated), {'error_m': err, 'reward_terms': terms,
                                                                 'steps': self.steps}



# ---------------------------------------------------------------- training

def gains_policy(theta, max_speed=10.0):
    """The linear policy of the three gains theta = (k_e, k_v, k_z) as an action function."""
    k_e, k_v, k_z = (float(t) for t in theta)

    def act(obs):
        e, vc = obs[:3], obs[3:6]
        v = np.array([k_v * vc[0] - k_e * e[0], k_v * vc[1] - k_e * e[1], -k_z * e[2]])
        return np.clip(v / max_speed, -1.0, 1.0)
    return act


def episode_return(env, policy, seed, options=None):
    obs, _ = env.reset(seed=seed, options=options)
    total, errors = 0.0, []
    while True:
        obs, r, term, trunc, info = env.step(policy(obs))
        total += r
        errors.append(info['error_m'])
        if term or trunc:
            return total, errors


def cem(score, mean, std, iterations, population, elite, rng, log=None):
    """The cross-entropy method: sample `population` parameter vectors from N(mean, std),
    keep the `elite` best by `score`, refit mean and std; returns (mean, history)."""
    mean, std = np.asarray(mean, dtype=np.float64), np.asarray(std, dtype=np.float64)
    history = []
    for it in range(iterations):
        cands = mean + std * rng.standard_normal((population, len(mean)))
        scores = np.array([score(c) for c in cands])
        order = np.argsort(-scores)
        best = cands[order[:elite]]
        mean, std = best.mean(axis=0), best.std(axis=0) + 0.05
        rec = {'iteration': it, 'mean_return': float(scores.mean()), 'best_return': float(scores[order[0]]),
               'theta': [round(float(x), 4) for x in mean]}
        history.append(rec)
        if log:
            log(rec)
    return mean, history


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--iterations', type=int, default=6)
    ap.add_argument('--population', type=int, default=8)
    ap.add_argument('--elite', type=int, default=2)
    ap.add_argument('--episodes', type=int, default=1, help='seeded episodes per candidate')
    ap.add_argument('--steps', type=int, default=200, help='ticks per episode (20 per simulated second)')
    ap.add_argument('--seed', type=int, default=0)
    runner.workload_args(ap, connect=False)
    args = ap.parse_args(argv)
    out = runner.out_dir(args.out, 'follow')
    env = DroneFollowEnv(domain=args.domain, max_steps=args.steps, out_dir=out, seed=args.seed)
    started = time.time()
    try:
        seeds = [args.seed + k for k in range(args.episodes)]

        def score(theta):
            return float(np.mean([episode_return(env, gains_policy(theta, env.max_speed), s)[0] for s in seeds]))

        def report_line(rec):
            print(json.dumps(rec), flush=True)

        hover = score([0.0, 0.0, 0.0])
        theta, history = cem(score, [0.0, 0.0, 0.0], [1.0, 1.0, 1.0], args.iterations, args.population,
                             args.elite, np.random.default_rng(args.seed), report_line)
        # The learnt policy on unseen seeds, against hovering in place.
        test_seeds = [1000 + args.seed + k for k in range(3)]
        learnt = [episode_return(env, gains_policy(theta, env.max_speed), s) for s in test_seeds]
        still = [episode_return(env, gains_policy([0, 0, 0], env.max_speed), s) for s in test_seeds]
        summary = {'workload': 'drone_follow_rl', 'theta_k_e_k_v_k_z': [round(float(x), 3) for x in theta],
                   'episodes_trained': args.iterations * args.population * len(seeds),
                   'hover_return_train': round(hover, 2),
                   'test_return_learnt': round(float(np.mean([r for r, _ in learnt])), 2),
                   'test_return_hover': round(float(np.mean([r for r, _ in still])), 2),
                   'test_mean_error_last_5s_m': round(float(np.mean([np.mean(e[-100:]) for _, e in learnt])), 3),
                   'ticks_per_episode': args.steps, 'wall_s': round(time.time() - started, 1)}
        with open(os.path.join(out, 'follow.json'), 'w') as f:
            json.dump({'summary': summary, 'history': history}, f, indent=1)
        _plot(os.path.join(out, 'follow.png'), history, summary)
        print(json.dumps(summary))
        return 0
    finally:
        env.close()


def _plot(path, history, summary):
    try:
        import matplotlib
        matplotlib.use('Agg')
        import matplotlib.pyplot as plt
    except ImportError:
        return
    fig, ax = plt.subplots(figsize=(6, 3.2))
    its = [h['iteration'] for h in history]
    ax.plot(its, [h['mean_return'] for h in history], 'o-', label='population mean')
    ax.plot(its, [h['best_return'] for h in history], 's-', label='best candidate')
    ax.axhline(summary['hover_return_train'], color='grey', ls='--', label='hovering in place')
    ax.set_xlabel('CEM iteration')
    ax.set_ylabel('episode return')
    ax.set_title('Drone follow: cross-entropy method, %d episodes' % summary['episodes_trained'])
    ax.legend(loc='lower right', fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


if __name__ == '__main__':
    sys.exit(main())
