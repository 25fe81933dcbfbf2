"""The CARLA paper's modular-pipeline baseline (MP, Dosovitskiy et al. 2017, §3.1), on
Lockstep's own cameras: perception -> local planner (a state machine) -> PID control.

- *Perception*: a semantic-segmentation camera and a depth camera at CoRL 2017's camera
  pose ((2.0, 0, 1.4), pitched -15 deg, fov 100). Every pixel is lifted to the car's frame
  with its depth (`Perception.lift`); the paper's road and lane-marking classes give the
  free space, the lane (the right lane's centre between the centre marking and the road's
  right edge, on a slice 5-9 m ahead) and the junctions ahead (the road opens wider than a
  two-lane street); vehicle and pedestrian pixels inside the corridor ahead give the
  obstacle distance. The paper trained a segmentation network; the camera's ground-truth
  labels stand in for it here (so perception is a ceiling, as is the privileged autopilot's).
- *Global planner*: the paper's MP had a topological route planner giving the turns; here the
  lane-graph route of planner.py from start to goal (the one the episode's length comes
  from), with the car's pose as in 0.8's measurements.
- *Local planner* (states as the paper's: road following, left / right turn, intersection
  forward, hazard stop): road following steers to the perceived lane centre; near a
  junction or a turn of the route it follows the route's lane through the junction at a
  lower speed; an obstacle within the braking distance stops the car. Traffic lights are
  ignored, as the CoRL 2017 protocol lets agents.
- *Control*: a PID on speed (throttle / brake) and a PD on the pure-pursuit steering angle.

    build/bin/lockstep python -m lockstep.benchmarks corl2017 --agent modular --episodes 2

The run starts the render service with the simulation (the agent's `needs_cameras`)."""
import math

import numpy as np

from .planner import Planner

# CARLA semantic tags (0.9.14+ ids, as the segmentation camera writes them in R).
ROADS, ROADLINES, SIDEWALKS = 1, 24, 2
DYNAMIC = (12, 13, 14, 15, 16, 18, 19)   # pedestrian, rider, car, truck, bus, motorcycle, bicycle

LANE_FOLLOW, TURN_LEFT, TURN_RIGHT, JUNCTION_FORWARD, HAZARD_STOP = \
    'road following', 'left turn', 'right turn', 'intersection forward', 'hazard stop'
STATES = (LANE_FOLLOW, TURN_LEFT, TURN_RIGHT, JUNCTION_FORWARD, HAZARD_STOP)


def depth_metres(image):
    """(H, W) float metres of a depth camera sample (depth_f32, or CARLA's 24-bit BGRA)."""
    a = image.to_numpy()
    if a.ndim == 2:
        return np.asarray(a, dtype=np.float32)
    a = a.astype(np.float32)
    return (a[..., 2] + a[..., 1] * 256.0 + a[..., 0] * 65536.0) / (256.0 ** 3 - 1) * 1000.0


def semantic_tags(image):
    a = image.to_numpy()
    return np.asarray(a[..., 2] if a.ndim == 3 else a, dtype=np.uint8)


class Perception:
    """Free space, lane and obstacles from a semantic and a depth image of one camera."""

    def __init__(self, width, height, fov_deg, mount=(2.0, 0.0, 1.4), pitch_deg=-15.0, slice_m=(5.0, 9.0),
                 bin_m=0.25, half_width_m=12.0, corridor_m=1.6):
        f = width / (2.0 * math.tan(math.radians(fov_deg) / 2.0))
        u = (np.arange(width) + 0.5 - width / 2.0) / f
        v = (np.arange(height) + 0.5 - height / 2.0) / f
        uu, vv = np.meshgrid(u, v)
        p = math.radians(pitch_deg)
        fwd = np.array([math.cos(p), 0.0, math.sin(p)])
        up = np.array([-math.sin(p), 0.0, math.cos(p)])
        right = np.array([0.0, 1.0, 0.0])
        # A pixel at planar depth d lies at mount + d * ray (CARLA's depth is along the optical axis).
        self.ray = fwd[None, None, :] + uu[..., None] * right[None, None, :] - vv[..., None] * up[None, None, :]
        self.mount = np.asarray(mount, dtype=np.float64)
        self.shape = (height, width)
        self.slice = slice_m
        self.bin = bin_m
        self.half = half_width_m
        self.corridor = corridor_m

    def lift(self, depth):
        """(H, W, 3) points in the car's frame (x forward, y right, z up; CARLA's axes)."""
        return self.mount[None, None, :] + depth[..., None] * self.ray

    def analyse(self, tags, depth):
        """{'road_left', 'road_right' (m, y of the road's edges on the slice, None if open),
        'marking' (y of the centre marking or None), 'lane_centre' (y or None), 'junction'
        (bool), 'obstacle_m' (x of the nearest vehicle or pedestrian in the corridor, inf),
        'free_space' (fraction of the slice's cells that are road)}."""
        if tags.shape != self.shape or depth.shape != self.shape:
            raise ValueError('perception: images of %s expected, got %s and %s' % (self.shape, tags.shape, depth.shape))
        pts = self.lift(depth.astype(np.float64))
        x, y, z = pts[..., 0], pts[..., 1], pts[..., 2]
        near = depth < 60.0
        road_px = near & ((tags == ROADS) | (tags == ROADLINES))
        # The ground plane's height in the car's frame, from the road seen within 12 m (the
        # mount's height is not trusted: a camera set lower or higher moves every point).
        close = road_px & (x < 12.0)
        z0 = float(np.median(z[close])) if close.any() else 0.0
        road = road_px & (np.abs(z - z0) < 0.3)
        a, b = self.slice
        in_slice = (x >= a) & (x <= b)
        nb = int(round(2 * self.half / self.bin))
        occ = np.zeros(nb, dtype=bool)
        seen = np.zeros(nb, dtype=bool)
        sel = in_slice & road
        idx = np.floor((y[sel] + self.half) / self.bin).astype(int)
        occ[idx[(idx >= 0) & (idx < nb)]] = True
        # Cells the camera sees on the slice at all (any ground class): a gap there is no road.
        ground = in_slice & near & (np.abs(z - z0) < 0.3)
        gi = np.floor((y[ground] + self.half) / self.bin).astype(int)
        seen[gi[(gi >= 0) & (gi < nb)]] = True
        centre = nb // 2
        right = self._edge(occ, seen, centre, +1)
        left = self._edge(occ, seen, centre, -1)
        out = {'road_left': left, 'road_right': right, 'marking': None, 'lane_centre': None, 'junction': False,
               'free_space': float(occ.mean()), 'ground_z': z0}
        if left is not None and right is not None:
            width = right - left
            out['junction'] = width > 12.0
            lines = in_slice & near & (tags == ROADLINES)
            ly = y[lines]
            ly = ly[(ly > left + 0.8) & (ly < right - 0.8)]
            if ly.size:
                mid = 0.5 * (left + right)
                out['marking'] = float(ly[np.argmin(np.abs(ly - mid))])
            if 4.5 <= width <= 12.0:
                m = out['marking']
                out['lane_centre'] = 0.5 * (m + right) if m is not None else right - width / 4.0
        else:
            out['junction'] = True   # the road opens to a side within the camera's view
        dyn = near & np.isin(tags, DYNAMIC) & (x > 0.0) & (np.abs(y) < self.corridor)
        out['obstacle_m'] = float(x[dyn].min()) if dyn.any() else math.inf
        return out

    def _edge(self, occ, seen, start, step):
        """y of the road's edge from `start` towards `step`: the first run of 0.5 m the camera
        sees that is not road; None when the road runs on out of view (a side street)."""
        i, gap = start, 0
        nb = len(occ)
        while 0 <= i < nb:
            if occ[i]:
                gap = 0
            elif seen[i]:
                gap += 1
                if gap * self.bin >= 0.5:
                    first = i - step * (gap - 1)            # the first cell off the road
                    return (first + (1 if step < 0 else 0)) * self.bin - self.half
            i += step
        return None


class PID:
    def __init__(self, kp, ki, kd, dt, i_limit=1.0):
        self.kp, self.ki, self.kd, self.dt, self.i_limit = kp, ki, kd, dt, i_limit
        self.i = 0.0
        self.prev = None

    def __call__(self, e):
        self.i = max(-self.i_limit, min(self.i_limit, self.i + e * self.dt))
        d = 0.0 if self.prev is None else (e - self.prev) / self.dt
        self.prev = e
        return self.kp * e + self.ki * self.i + self.kd * d


def dense_route(carla_map, episode, step=2.0):
    """The lane route from the episode's start to its goal (planner.py, the one that gave its
    length) as [(x, y)] in CARLA's coordinates every `step` metres."""
    native = carla_map._native
    planner = Planner(native, step=step)
    sx, sy, sz = episode['start'][:3]
    gx, gy, gz = episode['goal'][:3]
    start = planner.waypoint(sx, -sy, sz)
    goal = planner.waypoint(gx, -gy, gz)
    if start is None or goal is None:
        raise RuntimeError('modular agent: no driving lane at the start or goal of episode %s' % episode.get('id'))
    found = planner.search(start, {'goal': goal}, max_m=max(3000.0, 3 * episode.get('route_m', 0.0)))
    if 'goal' not in found:
        raise RuntimeError('modular agent: no lane route to the goal of episode %s' % episode.get('id'))
    pts = [(w.pose[0], -w.pose[1]) for w in found['goal'][1]]
    pts.append((gx, gy))
    return pts


class ModularAgent:
    """The modular pipeline: cameras -> Perception -> state machine -> PID (see the module)."""
    needs_cameras = True

    def __init__(self, width=256, height=128, fov=100.0, cruise_kmh=25.0, turn_kmh=13.0, junction_kmh=18.0):
        self.name = 'modular'
        self.width, self.height, self.fov = width, height, fov
        self.cruise, self.turn_speed, self.junction_speed = cruise_kmh, turn_kmh, junction_kmh
        self.sensors = []
        self.stats = {}

    # -- episode
    def setup(self, ctx, ego, episode):
        carla = ctx.carla
        self.ctx = ctx
        self.route = dense_route(ctx.map, episode)
        self.cum = [0.0]
        for (ax, ay), (bx, by) in zip(self.route, self.route[1:]):
            self.cum.append(self.cum[-1] + math.hypot(bx - ax, by - ay))
        self.k = 0
        self.latest = {}
        tf = carla.Transform(carla.Location(x=2.0, z=1.4), carla.Rotation(pitch=-15.0))
        for kind in ('semantic_segmentation', 'depth'):
            bp = ctx.lib.find('sensor.camera.' + kind)
            for k, v in (('image_size_x', self.width), ('image_size_y', self.height), ('fov', self.fov)):
                bp.set_attribute(k, str(v))
            cam = ctx.world.spawn_actor(bp, tf, attach_to=ego)
            cam.listen(lambda img, kind=kind: self.latest.__setitem__(kind, img))
            self.sensors.append(cam)
        self.perception = Perception(self.width, self.height, self.fov)
        try:
            self.max_steer = math.radians(ego.get_physics_control().wheels[0].max_steer_angle)
        except Exception:  # noqa: BLE001 - a vehicle without wheel data: CARLA's default
            self.max_steer = math.radians(70.0)
        self.wheelbase = 2.9
        self.speed_pid = PID(0.25, 0.05, 0.0, ctx.dt, i_limit=10.0)
        self.steer_pid = PID(1.0, 0.0, 0.05, ctx.dt)
        self.state = LANE_FOLLOW
        self.stats = {s: 0 for s in STATES}
        self.stats['lane_from_perception'] = 0
        self.stats['frames'] = 0

    def teardown(self, ctx):
        for s in self.sensors:
            try:
                s.stop()
            except Exception:  # noqa: BLE001
                pass
        if self.sensors:
            ctx.client.apply_batch_sync([ctx.carla.command.DestroyActor(s.id) for s in self.sensors], True)
        self.sensors = []

    # -- the route
    def _progress(self, x, y):
        best, bk = None, self.k
        for k in range(self.k, min(self.k + 15, len(self.route))):
            d = math.hypot(self.route[k][0] - x, self.route[k][1] - y)
            if best is None or d < best:
                best, bk = d, k
        self.k = bk
        return self.cum[bk]

    def _route_point(self, s):
        k = self.k
        while k < len(self.route) - 1 and self.cum[k] < s:
            k += 1
        return self.route[k]

    def _route_turn(self, s, ahead):
        """The route's heading change (deg, + right as CARLA's yaw) from s to s + ahead."""
        def heading(at):
            k = self.k
            while k < len(self.route) - 2 and self.cum[k + 1] < at:
                k += 1
            (ax, ay), (bx, by) = self.route[k], self.route[min(k + 2, len(self.route) - 1)]
            return math.degrees(math.atan2(by - ay, bx - ax))
        d = heading(s + ahead) - heading(s)
        return (d + 180.0) % 360.0 - 180.0

    @staticmethod
    def _to_car(tr, px, py):
        yaw = math.radians(tr.rotation.yaw)
        dx, dy = px - tr.location.x, py - tr.location.y
        return math.cos(yaw) * dx + math.sin(yaw) * dy, -math.sin(yaw) * dx + math.cos(yaw) * dy

    # -- one frame
    def step(self, ego):
        carla = self.ctx.carla
        seg, dep = self.latest.get('semantic_segmentation'), self.latest.get('depth')
        if seg is None or dep is None or seg.frame != dep.frame:
            control = carla.VehicleControl(throttle=0.0, brake=1.0)   # no perception yet
            ego.apply_control(control)
            return control
        p = self.perception.analyse(semantic_tags(seg), depth_metres(dep))
        tr = ego.get_transform()
        v = ego.get_velocity().length() * 3.6
        s = self._progress(tr.location.x, tr.location.y)
        turn = self._route_turn(s, 15.0)
        stop_m = 4.0 + v / 3.6 * 1.2 + (v / 3.6) ** 2 / (2 * 4.0)
        in_junction = p['junction'] or abs(turn) > 30.0
        if p['obstacle_m'] < stop_m:
            self.state = HAZARD_STOP
        elif abs(turn) > 30.0:
            self.state = TURN_RIGHT if turn > 0 else TURN_LEFT
        elif in_junction:
            self.state = JUNCTION_FORWARD
        else:
            self.state = LANE_FOLLOW
        self.stats[self.state] += 1
        self.stats['frames'] += 1
        # Lateral: a target point ahead, on the perceived lane when following the road.
        look = max(6.0, 0.35 * v)
        rx, ry = self._to_car(tr, *self._route_point(s + look))
        tx, ty = rx, ry
        if self.state in (LANE_FOLLOW, HAZARD_STOP) and p['lane_centre'] is not None and \
                abs(p['lane_centre'] - ry) < 1.5:
            tx, ty = 0.5 * sum(self.perception.slice) + 2.0, p['lane_centre']
            self.stats['lane_from_perception'] += 1
        alpha = math.atan2(ty, max(tx, 0.5))
        delta = math.atan2(2.0 * self.wheelbase * math.sin(alpha), math.hypot(tx, ty))
        steer = max(-1.0, min(1.0, self.steer_pid(delta / self.max_steer)))
        # Longitudinal: the state's speed, a PID on it.
        target = {LANE_FOLLOW: self.cruise, TURN_LEFT: self.turn_speed, TURN_RIGHT: self.turn_speed,
                  JUNCTION_FORWARD: self.junction_speed, HAZARD_STOP: 0.0}[self.state]
        if self.state != HAZARD_STOP and math.isfinite(p['obstacle_m']):
            target = min(target, max(0.0, (p['obstacle_m'] - 4.0) * 2.0))   # close in slowly behind a car
        u = self.speed_pid(target - v)
        if self.state == HAZARD_STOP or target - v < -3.0:
            control = carla.VehicleControl(throttle=0.0, brake=1.0 if self.state == HAZARD_STOP else 0.4, steer=steer)
            self.speed_pid.i = 0.0
        else:
            control = carla.VehicleControl(throttle=max(0.0, min(0.75, u)), brake=0.0, steer=steer)
        ego.apply_control(control)
        return control
