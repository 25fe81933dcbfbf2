"""Shortest lane routes on an OpenDRIVE map, for defining benchmark episodes.

A Dijkstra search over the map's lane graph, stepped at `step` metres with the map
library's own `next` (the query behind carla.Waypoint.next): it follows lanes in their
direction of travel through junctions, without lane changes (CARLA's CoRL 2017 towns have
one lane each way). The distance is the driven length along lane centres, the analogue of
CARLA 0.8's `Planner.get_shortest_path_distance` (its A* on the road graph).

Everything here works on the native map (`lockstep.Map`, ENU, radians) so that generating
the episode files needs no simulation. `to_carla` converts a pose to CARLA's convention
(left-handed: y = -ENU y, yaw in degrees clockwise)."""
import heapq
import math


def to_carla(pose):
    """(x, y, z, yaw, ...) ENU radians -> [x, y, z, yaw_deg] in CARLA's convention."""
    x, y, z, yaw = pose[0], pose[1], pose[2], pose[3]
    return [round(x, 3), round(-y, 3), round(z, 3), round(-math.degrees(yaw), 3)]


def _key(w):
    return (w.road, w.section, w.lane, int(math.floor(w.s)))


def _yaw(w):
    return w.pose[3]


def _angle(a, b):
    """Signed difference b - a wrapped to (-pi, pi]."""
    d = (b - a) % (2 * math.pi)
    return d - 2 * math.pi if d > math.pi else d


class Planner:
    """Lane-graph search on a native map. `routes_from(start)` explores everything reachable."""

    def __init__(self, native_map, step=2.0):
        self.map = native_map
        self.step = float(step)

    def waypoint(self, x, y, z=0.0):
        """The driving-lane waypoint nearest an ENU point."""
        return self.map.waypoint(x, y, z, True, 2)

    def search(self, start, goals, max_m=3000.0):
        """Dijkstra from waypoint `start`. `goals`: {name: native waypoint}. Returns
        {name: (distance_m, [native waypoints of the path])} for each goal reached: a node
        within step/2 of a goal on the goal's lane counts as reaching it."""
        by_lane = {}
        for name, g in goals.items():
            by_lane.setdefault((g.road, g.section, g.lane), []).append((name, g))
        found = {}
        dist = {_key(start): 0.0}
        parent = {_key(start): None}
        nodes = {_key(start): start}
        heap = [(0.0, 0, _key(start))]
        counter = 1
        half = self.step / 2 + 1e-6
        while heap:
            d, _, k = heapq.heappop(heap)
            if d > dist.get(k, math.inf) + 1e-9:
                continue
            w = nodes[k]
            for name, g in by_lane.get((w.road, w.section, w.lane), ()):
                if name not in found and d > 0 and abs(w.s - g.s) <= half:
                    path = []
                    kk = k
                    while kk is not None:
                        path.append(nodes[kk])
                        kk = parent[kk]
                    found[name] = (d + abs(w.s - g.s), path[::-1])
            if len(found) == len(goals) or d > max_m:
                if len(found) == len(goals):
                    break
                continue
            for n in self.map.next(w, self.step):
                nk = _key(n)
                px, py = w.pose[0], w.pose[1]
                qx, qy = n.pose[0], n.pose[1]
                nd = d + max(math.hypot(qx - px, qy - py), 1e-3)
                if nd < dist.get(nk, math.inf) - 1e-9:
                    dist[nk] = nd
                    parent[nk] = k
                    nodes[nk] = n
                    heapq.heappush(heap, (nd, counter, nk))
                    counter += 1
        return found


def turns(path, threshold_deg=45.0):
    """The turns a path makes: 'Left' / 'Right' for each time its heading leaves the current
    reference direction by more than the threshold, the reference then moving on by a
    right angle (the towns' streets meet at right angles; a curved corner road counts as
    a turn as much as a turn at a junction, as in CARLA 0.8's 'One curve' task). ENU yaw
    grows counter-clockwise: a left turn raises it."""
    out = []
    if len(path) < 2:
        return out
    ref = _yaw(path[0])
    for w in path[1:]:
        d = math.degrees(_angle(ref, _yaw(w)))
        if abs(d) > threshold_deg:
            out.append('Left' if d > 0 else 'Right')
            ref += math.copysign(math.pi / 2, d)
    return out


def junctions_crossed(path):
    return sum(1 for prev, w in zip(path, path[1:]) if w.junction >= 0 and prev.junction < 0)


def path_points(path, every_m=20.0):
    """Points of a path about every `every_m` metres outside junctions, last one included, CARLA
    convention [x, y, z]."""
    out = []
    acc = every_m
    for prev, w in zip(path, path[1:]):
        acc += math.hypot(w.pose[0] - prev.pose[0], w.pose[1] - prev.pose[1])
        # No point inside a junction: its lanes overlap there, and the nearest lane to a point
        # may be a turn the route does not take (the Traffic Manager's set_path would take it).
        if acc >= every_m and w.junction < 0:
            out.append(to_carla(w.pose)[:3])
            acc = 0.0
    if path:
        last = to_carla(path[-1].pose)[:3]
        if not out or out[-1] != last:
            out.append(last)
    return out
