"""Progress along a route: the episode's start and route points as a polyline, the car's
furthest point on it within `max_deviation_m`, monotonic (going back undoes nothing)."""
import math


class RouteProgress:
    def __init__(self, episode, max_deviation_m=8.0, window=4):
        self.pts = [tuple(episode['start'][:2])] + [tuple(p[:2]) for p in episode['path']]
        self.cum = [0.0]
        for a, b in zip(self.pts, self.pts[1:]):
            self.cum.append(self.cum[-1] + math.hypot(b[0] - a[0], b[1] - a[1]))
        self.total = self.cum[-1]
        self.seg = 0
        self.along = 0.0
        self.max_dev = max_deviation_m
        self.window = window

    def update(self, x, y):
        """Moves the progress on from a car position; returns the route length still ahead (m)."""
        best = None
        for k in range(self.seg, min(self.seg + self.window, len(self.pts) - 1)):
            (ax, ay), (bx, by) = self.pts[k], self.pts[k + 1]
            dx, dy = bx - ax, by - ay
            L2 = dx * dx + dy * dy
            t = 0.0 if L2 == 0 else max(0.0, min(1.0, ((x - ax) * dx + (y - ay) * dy) / L2))
            dev = math.hypot(x - (ax + t * dx), y - (ay + t * dy))
            if dev <= self.max_dev and (best is None or dev < best[0] - 1e-9):
                best = (dev, k, self.cum[k] + t * math.sqrt(L2))
        if best is not None and best[2] > self.along:
            self.along, self.seg = best[2], best[1]
        return self.total - self.along

    def completion(self):
        return min(1.0, self.along / self.total) if self.total > 0 else 0.0

    def heading_ahead(self, metres):
        """The route's direction (CARLA yaw, degrees) `metres` ahead of the progress."""
        target = min(self.along + metres, self.total)
        k = self.seg
        while k < len(self.pts) - 2 and self.cum[k + 1] < target:
            k += 1
        (ax, ay), (bx, by) = self.pts[k], self.pts[k + 1]
        return math.degrees(math.atan2(by - ay, bx - ax))


FOLLOW_LANE, LEFT, RIGHT, STRAIGHT = 0, 1, 2, 3   # CIL's high-level commands, in this order


def _wrap_deg(a):
    return (a + 180.0) % 360.0 - 180.0


def command(progress, carla_map, x, y, location_type):
    """CIL's high-level command at a car position: a turn of the route within the next
    20 m (left / right), a junction straight ahead within 10 m (straight), else follow the
    lane. `location_type` is carla.Location (kept out of this module's imports)."""
    turn = _wrap_deg(progress.heading_ahead(20.0) - progress.heading_ahead(0.0))
    if turn > 45:
        return RIGHT    # CARLA's yaw grows clockwise
    if turn < -45:
        return LEFT
    ahead = math.radians(progress.heading_ahead(10.0))
    wp = carla_map.get_waypoint(location_type(x + 10 * math.cos(ahead), y + 10 * math.sin(ahead), 0.0))
    return STRAIGHT if wp is not None and wp.is_junction else FOLLOW_LANE
